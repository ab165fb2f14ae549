"""Rich displays (HTML and LaTeX, for notebooks) of jetnh's objects, within a size budget.

Every display is at most ``BUDGET`` characters.  Equations and comparisons are shown in
shared form (``jetnh.algebra.shared``: named intermediate quantities), the rows and quantities
that do not fit counted.  In the other displays an expression whose printed tree would
be large (over ``TREE_CAP`` nodes, counted on the shared graph so that nothing large is
ever printed), whose LaTeX exceeds ``EXPR_BUDGET`` or does not fit in what is left of
the budget is shown as a summary (its size and its symbols), and rows stop, with a
count of those left out, before the budget.
"""

from __future__ import annotations

import html

import numpy as np
import sympy as sp

from .algebra import dag
from .algebra.shared import WHERE_TEX, shared_form, tex_text as _tex_text

BUDGET = 20_000          # characters of one display
TEXT_BUDGET = 20_000     # characters of a printed (str) result
EXPR_BUDGET = 8_000      # characters of one expression's LaTeX
TREE_CAP = 1_500         # nodes of an expression's tree printed in full
MAX_ROWS = 24            # rows of one list (constraints, runs)
SHARED_ROWS = 80         # lines of a shared form (rows, "where", named quantities)
_STYLE = 'style="text-align:left"'


def tree_size(expr, cap: int = TREE_CAP) -> int:
    """Nodes of ``expr`` as a tree (what printing walks), counted on its graph; counting
    stops once past ``cap``."""
    size: dict[int, int] = {}
    for e in dag.nodes(expr, cap=cap + 1):
        size[id(e)] = 1 + sum(size.get(id(a), cap + 1) for a in e.args)
        if size[id(e)] > cap:
            return cap + 1
    return size.get(id(sp.sympify(expr, strict=True)), cap + 1)


def _summary(expr) -> str:
    syms = sorted((s.name for s in dag.free_symbols(expr)), key=str)
    shown = ", ".join(syms[:8]) + (", ..." if len(syms) > 8 else "")
    return f"expression of {dag.size(expr)} distinct parts in {shown or 'no symbols'}"


def text(expr) -> str:
    """``str(expr)``, or its summary when its printed tree would be large (counted on the
    shared graph, never printed)."""
    return str(expr) if tree_size(expr) <= TREE_CAP else f"<{_summary(expr)}>"


def text_items(items, budget: int = TEXT_BUDGET) -> str:
    """``items`` (strings) joined by ", " within ``budget`` characters; the ones past it
    are counted."""
    items = list(items)
    out, used = [], 0
    for i, item in enumerate(items):
        if used + len(item) > budget:
            out.append(f"... ({len(items) - i} more)")
            break
        out.append(item)
        used += len(item) + 2
    return ", ".join(out)


def latex(expr, J=None) -> list[str]:
    """LaTeX of ``expr`` (dotted jets with ``J``) and ``\\text{<summary>}``, or only the
    summary when the expression is large: the forms to try, longest first."""
    expr = sp.sympify(expr, strict=True)
    short = r"\langle\text{" + _tex_text(_summary(expr)) + r"}\rangle"
    if tree_size(expr) <= TREE_CAP:
        text = J.latex(expr) if J is not None else sp.latex(expr)
        if len(text) <= EXPR_BUDGET:
            return [text, short]
    return [short]


class Rows:
    """Rows added until a budget is spent; ``done()`` says how many were left out."""

    def __init__(self, budget: int, max_rows: int = MAX_ROWS):
        self.rows: list[str] = []
        self.left = budget
        self.max_rows = max_rows
        self.omitted = 0

    def add(self, *forms: str) -> bool:
        """Add the first of ``forms`` that fits (none once one row was left out)."""
        if not self.omitted and len(self.rows) < self.max_rows:
            for row in forms:
                if len(row) <= self.left:
                    self.rows.append(row)
                    self.left -= len(row)
                    return True
        self.omitted += 1
        return False


# ---------------------------------------------------------------------- HTML
def _td(x) -> str:
    return f"<td {_STYLE}>{x}</td>"


def _math(tex: str) -> str:
    """Inline maths for MathJax: the class ``math`` marks it for typesetting where a page
    typesets only marked elements (Sphinx; Jupyter typesets every output)."""
    return '<span class="math">' + html.escape(r"\(" + tex + r"\)") + "</span>"


def html_table(title: str, facts: list[tuple[str, str]], lists=(), budget=BUDGET) -> str:
    """A titled table of (label, HTML) facts, then titled lists of rows (label, items,
    noun of the items; an item is a list of HTML forms, longest first); everything
    escaped by the caller, within ``budget``."""
    title = html.escape(title[:200])
    head = [f"<div><b>{title}</b>", "<table>"]
    body = Rows(budget - 500 - len(title), max_rows=10_000)
    for label, value in facts:
        body.add(f"<tr><th {_STYLE}>{html.escape(label)}</th>{_td(value)}</tr>")
    for label, items, noun, *most in lists:
        inner = Rows(max(body.left - 200, 0), *most)
        for forms in items:
            inner.add(*(f"<li>{x}</li>" for x in forms))
        more = (f"<li>... and {inner.omitted} more {noun}</li>" if inner.omitted else "")
        body.add(f"<tr><th {_STYLE}>{html.escape(label)}</th>"
                 f"{_td('<ol>' + ''.join(inner.rows) + more + '</ol>')}</tr>")
    tail = [f"<tr><td>... and {body.omitted} more rows</td></tr>"] if body.omitted else []
    return "\n".join(head + body.rows + tail + ["</table></div>"])


def latex_block(title: str, rows, noun: str, budget=BUDGET, max_rows=MAX_ROWS) -> str:
    r"""``$$\begin{aligned} ... \end{aligned}$$`` with a title row and ``rows`` (each a
    list of LaTeX forms with an ``&``, longest first), within ``budget``."""
    title = _tex_text(title[:200])
    out = Rows(budget - 300 - len(title), max_rows)
    for forms in rows:
        out.add(*forms)
    if out.omitted:
        out.rows.append(r"&\text{... and " + f"{out.omitted} more {noun}" + "}")
    lines = [r"&\text{" + title + "}"] + out.rows
    return "$$\\begin{aligned}" + r" \\ ".join(lines) + "\\end{aligned}$$"


def _names(symbols, limit=40) -> str:
    names = [s.name if isinstance(s, sp.Symbol) else str(s) for s in symbols]
    text = ", ".join(names[:limit]) + (f", ... ({len(names)} in all)" if len(names) > limit
                                       else "")
    return html.escape(text or "none")


# ---------------------------------------------------------------------- System
def _system_title(s) -> str:
    name = f" {s.name[:80]}{'...' if len(s.name) > 80 else ''}" if s.name else ""
    return (f"System{name}: {s.J.n} coordinates, {s.k} constraint"
            f"{'' if s.k == 1 else 's'}")


def system_html(s) -> str:
    J = s.J
    params = ", ".join(f"{p.name} = {s.defaults[p]:g}" if p in s.defaults else p.name
                       for p in s.parameters[:40])
    facts = [("coordinates", _names(J.q)), ("dependent", _names(s.dependent)),
             ("parameters", html.escape(params or "none")), ("L", _math(latex(s.L, J)[0]))]
    cons = ([_math(x + " = 0") for x in latex(f, J)] for f in s.given_constraints)
    return html_table(_system_title(s), facts, [("constraints", cons, "constraints")])


def system_latex(s) -> str:
    J = s.J
    rows = [[r"L &= " + x for x in latex(s.L, J)]]
    rows += [[f"f^{{{a + 1}}} &= " + x + " = 0" for x in latex(f, J)]
             for a, f in enumerate(s.given_constraints)]
    return latex_block(_system_title(s) + ", dependent " + ", ".join(
        q.name for q in s.dependent[:40]), rows, "constraints")


# ---------------------------------------------------------------------- Equations
def _equations_title(e) -> str:
    return f"{e.principle} equations, {e.form} form, {e.convention} convention {e.paper}".strip()


def _shared_items(form, J) -> list:
    """The rows, "where" and the definitions of a shared form as HTML list items."""
    return [[_math(x)] if x != WHERE_TEX else ["where"] for x in _shared_lines(form, J)]


def _shared_lines(form, J) -> list:
    rows, defs = form.latex_lines(J)
    return rows + ([WHERE_TEX] if defs else []) + defs


def equations_html(e) -> str:
    facts = [("multipliers", _names(e.multipliers)), ("reactions", _names(e.reactions)),
             ("equations", str(len(e.expressions)))]
    return html_table(_equations_title(e), facts,
                      [("", _shared_items(e.shared_form(), e.J), "lines", SHARED_ROWS)])


def equations_latex(e) -> str:
    return latex_block(_equations_title(e), ([x] for x in _shared_lines(e.shared_form(), e.J)),
                       "lines", max_rows=SHARED_ROWS)


# ---------------------------------------------------------------------- Comparison
def _defects(c):
    return shared_form([(sp.Symbol(f"Delta_{q.name}"), d) for q, d in c.defects.items()])


def comparison_html(c, J=None) -> str:
    return html_table(f"Comparison of {c.principles[0]} and {c.principles[1]}",
                      [("verdict", html.escape(str(c))),
                       ("identical", str(c.identical)),
                       ("on the branch (32)", str(c.on_branch_32))],
                      [("difference of accelerations", _shared_items(_defects(c), J),
                        "lines", SHARED_ROWS)])


def comparison_latex(c) -> str:
    return latex_block(str(c), ([x] for x in _shared_lines(_defects(c), None)), "lines",
                       max_rows=SHARED_ROWS)


# ---------------------------------------------------------------------- runs
def _trajectory_facts(traj) -> list[tuple[str, str]]:
    d = traj.diagnostics
    span = f"[{traj.t[0]:.6g}, {traj.t[-1]:.6g}]" if len(traj) else "empty"
    return [("principle", traj.scene.principle), ("rows", f"{len(traj)}, t in {span}"),
            ("status", f"{traj.status} ({'success' if traj.success else 'failure'})"),
            ("stop reason", traj.stop_reason[:2000]),
            ("steps", f"{d.steps} (rejected {d.rejected}), {d.rhs_evaluations} rhs evaluations"),
            ("constraint residual max", f"{d.residual_max:.3e}"),
            ("energy drift", d.drift_text()),
            *((("figures", note),) if (note := d.rows_note()) else ())]


def trajectory_html(traj) -> str:
    from .numeric.export import columns

    facts = [(k, html.escape(v)) for k, v in _trajectory_facts(traj)]
    cols = columns(traj, diagnostics=False)
    names = list(cols)[:12]
    n = len(traj)
    shown = list(range(min(n, 3))) + list(range(max(n - 3, 3), n))
    head = "".join(f"<th>{html.escape(c)}</th>" for c in names)
    rows = "".join("<tr>" + "".join(f"<td>{cols[c][i]:.6g}</td>" for c in names) + "</tr>"
                   for i in shown)
    more = len(cols) - len(names)
    facts.append(("rows (first, last)", f"<table><tr>{head}</tr>{rows}</table>"
                  + (f"... and {more} more columns" if more > 0 else "")))
    return html_table(f"Trajectory ({traj.method})", facts)


def trajectory_latex(traj) -> str:
    rows = ([f"\\text{{{_tex_text(k)}}} &: \\text{{{_tex_text(v[:300])}}}"]
            for k, v in _trajectory_facts(traj))
    return latex_block(f"Trajectory ({traj.method})", rows, "facts")


def _ensemble_facts(ens) -> list[tuple[str, str]]:
    from .numeric.methods import STATUS_TEXT

    counts = {int(s): int(c) for s, c in zip(*np.unique(ens.status, return_counts=True))}
    status = "; ".join(f"{c} x {STATUS_TEXT.get(s, s)}" for s, c in counts.items())
    checks = []
    # the checks need the aux rows of every run: computed here only when affordable
    if ens.n_runs and ("aux" in ens.__dict__ or ens.y.shape[0] * ens.y.shape[1] <= 200_000):
        with np.errstate(all="ignore"):
            checks = [("constraint residual max", f"{np.nanmax(ens.residual_max):.3e}"),
                      ("energy drift max", f"{np.nanmax(ens.energy_drift):.3e}")]
    return [("principle", ens.scene.principle),
            ("runs", f"{ens.n_runs} x {ens.y.shape[1]} rows, {int(ens.success.sum())} succeeded"),
            ("status", status[:2000]),
            ("run-time parameters", ", ".join(ens.param_names) or "none"),
            *checks, ("wall time", f"{ens.wall_time * 1e3:.3g} ms ({ens.parallel}, "
                                   f"{ens.workers} workers)")]


def ensemble_html(ens) -> str:
    facts = [(k, html.escape(v)) for k, v in _ensemble_facts(ens)]
    return html_table(f"Ensemble ({ens.method})", facts)


def ensemble_latex(ens) -> str:
    rows = ([f"\\text{{{_tex_text(k)}}} &: \\text{{{_tex_text(v[:300])}}}"]
            for k, v in _ensemble_facts(ens))
    return latex_block(f"Ensemble ({ens.method})", rows, "facts")
