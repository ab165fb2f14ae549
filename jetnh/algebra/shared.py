"""Large expressions in shared form: named intermediate quantities, the way a paper
writes them ("x'' = u_7 / u_3, where u_1 = ..., u_2 = ...").

Solved equations share their subexpressions (``jetnh.algebra.dag``): as trees they are
exponentially larger than as graphs, so they are never printed flat.  ``shared_form``
walks the graph of the expressions once and names a subexpression when

- it is used more than once (by distinct parents or roots) and is not tiny
  (``SHARED_MIN`` nodes or more once its own named parts count as one), or
- a parent would otherwise print more than ``INLINE_MAX`` nodes (its largest parts are
  named until it fits; a sum keeps its short terms, so a long sum is one long line),

so every printed line is short and the whole is linear in the number of distinct
subexpressions.  Expressions whose trees are small altogether (``FLAT_MAX``) are shown
as they are, without names.  ``text``, ``latex`` and ``as_dict`` print the same form,
within an optional character budget (what does not fit is counted, never cut in a line).
"""

from __future__ import annotations

import sympy as sp

from . import dag

FLAT_MAX = 1_500          # tree nodes of all expressions shown flat, without names
INLINE_MAX = 40           # tree nodes of one printed line (names count as one)
SHARED_MIN = 8            # tree nodes from which a repeated subexpression gets a name
LINE_MAX = 4_000          # characters of one line (a sum of thousands of names)


def tree_size(exprs, cap: int) -> int:
    """Nodes of ``exprs`` (a list) as trees, counted on the graph up to ``cap + 1``."""
    size: dict[int, int] = {}
    total = 0
    roots = [sp.sympify(e, strict=True) for e in exprs]
    for e in dag.nodes(roots):
        size[id(e)] = min(cap + 1, 1 + sum(size[id(a)] for a in e.args))
    for e in roots:
        total = min(cap + 1, total + size[id(e)])
    return total


class SharedForm:
    """Expressions written with named intermediate quantities.

    ``rows``: headings (str) and (lhs, expression in the names) pairs, lhs a Symbol, a
    string or None (an equation: expression = 0); ``where``: (name Symbol, definition),
    each definition using only names defined before it.
    """

    def __init__(self, rows: list, where: list):
        self.rows = rows
        self.where = where

    def expressions(self) -> list:
        """The rows' expressions (in the names), headings left out."""
        return [r[1] for r in self.rows if not isinstance(r, str)]

    def printed(self, printer=sp.sstr, cut: bool = False):
        """The rows as headings and (lhs text or None, expression text) pairs, and the
        definitions as (name, text); with ``cut`` each text within ``LINE_MAX``."""
        tex = printer is not sp.sstr
        rows = [r if isinstance(r, str) else
                (None if r[0] is None else printer(r[0]) if isinstance(r[0], sp.Basic)
                 else str(r[0]), _cut(printer(r[1]), cut, tex)) for r in self.rows]
        return rows, [(printer(s), _cut(printer(e), cut, tex)) for s, e in self.where]

    def text(self, budget: int | None = None, more: str = "") -> str:
        """Plain text: the rows, then "where" and the definitions; past ``budget``
        characters the lines left out are counted (``more``: how to see them)."""
        rows, defs = self.printed(cut=budget is not None)
        rows = [r if isinstance(r, str) else f"  {r[1]} = 0" if r[0] is None
                else f"  {r[0]} = {r[1]}" for r in rows]
        return "\n".join(fit(rows, [f"    {a} = {b}" for a, b in defs], budget, "  where",
                              lambda n, w: f"  ... and {n} more {w}{more}"))

    def latex_lines(self, J=None, cut: bool = True):
        r"""The rows and the definitions as ``aligned`` lines (``lhs &= rhs``, ``&rhs =
        0``, headings ``&\text{...}``); dotted jets with ``J``."""
        rows, defs = self.printed(J.latex if J is not None else sp.latex, cut)
        rows = [r"&\text{" + tex_text(r) + "}" if isinstance(r, str) else
                f"&{r[1]} = 0" if r[0] is None else f"{r[0]} &= {r[1]}" for r in rows]
        return rows, [f"{a} &= {b}" for a, b in defs]

    def latex(self, J=None, budget: int | None = None, more: str = "") -> str:
        r"""``\begin{aligned} ... \end{aligned}``, within ``budget`` as ``text``."""
        rows, defs = self.latex_lines(J, cut=budget is not None)
        lines = fit(rows, defs, budget, WHERE_TEX,
                    lambda n, w: r"&\text{" + tex_text(f"... and {n} more {w}{more}") + "}")
        return r"\begin{aligned}" + r" \\ ".join(lines) + r"\end{aligned}"

    def as_dict(self, budget: int | None = None) -> dict:
        """Each heading -> its rows (a list of equations' texts, or {lhs: text}: one
        kind per heading; "rows" before the first heading), then
        "where": {name: text}; within ``budget`` characters, "omitted" counts the rows
        and definitions left out (in order)."""
        rows, defs = self.printed(cut=budget is not None)
        size = [len(r) if isinstance(r, str) else len(r[1]) + len(r[0] or "") + 8
                for r in rows]
        kept_rows = _keep(size, budget)
        left = None if budget is None else budget - sum(size[:kept_rows])
        kept_defs = _keep([len(a) + len(b) + 8 for a, b in defs], left)
        out: dict = {}
        key = "rows"
        for r in rows[:kept_rows]:
            if isinstance(r, str):
                key = r
            elif r[0] is None:
                out.setdefault(key, []).append(r[1])
            else:
                out.setdefault(key, {})[r[0]] = r[1]
        out["where"] = dict(defs[:kept_defs])
        if kept_rows < len(rows) or kept_defs < len(defs):
            out["omitted"] = {"rows": len(rows) - kept_rows, "where": len(defs) - kept_defs}
        return out


WHERE_TEX = r"&\text{where}"


def _cut(text: str, cut: bool, latex: bool = False) -> str:
    """A line over ``LINE_MAX`` (a sum of thousands of terms) cut, or in LaTeX, whose
    syntax a cut would break, replaced by a note."""
    if not cut or len(text) <= LINE_MAX:
        return text
    if latex:
        return r"\text{" + f"(a line of {len(text)} characters: see the full form)" + "}"
    return text[:LINE_MAX] + f" ... ({len(text) - LINE_MAX} more characters)"


def _keep(sizes: list, budget: int | None) -> int:
    """How many leading items of ``sizes`` fit in ``budget``."""
    if budget is None:
        return len(sizes)
    used = 0
    for i, n in enumerate(sizes):
        used += n + 1
        if used > budget:
            return i
    return len(sizes)


def fit(rows: list, defs: list, budget: int | None, where: str, note) -> list:
    """The rows, ``where`` and the definitions within ``budget`` characters (200 kept
    for the notes); each run of lines left out replaced by ``note(count, what)``."""
    if budget is None:
        return rows + ([where] if defs else []) + defs
    n = _keep([len(r) for r in rows], budget - 200)
    left = budget - 200 - sum(len(r) + 1 for r in rows[:n])
    m = _keep([len(where)] + [len(d) for d in defs], left) - 1 if n == len(rows) else -1
    out = rows[:n] + ([note(len(rows) - n, "rows")] if n < len(rows) else [])
    if defs and m >= 0:
        out += [where] + defs[:m]
    if defs and m < len(defs):
        out.append(note(len(defs) - max(m, 0), "named quantities"))
    return out


def tex_text(s: str) -> str:
    """``s`` escaped for ``\\text{...}``."""
    for a, b in (("\\", r"\textbackslash "), ("{", r"\{"), ("}", r"\}"), ("_", r"\_"),
                 ("#", r"\#"), ("%", r"\%"), ("&", r"\&"), ("$", r"\$"), ("^", r"\^{}"),
                 ("~", r"\~{}")):
        s = s.replace(a, b)
    return s


def _prefix(exprs) -> str:
    """A name prefix no symbol of ``exprs`` uses (u, w, c, ...)."""
    names = {s.name for s in dag.free_symbols(exprs)}
    for p in ("u", "w", "c", "k", "z"):
        if not any(n.startswith(p + "_") for n in names):
            return p
    return "shared"


def canonical(order: list) -> dict:
    """id of each node of ``order`` (children before parents) -> the first node of
    ``order`` equal to it as a tree: equal subexpressions built apart (two principles'
    equations) become one, in time linear in the number of nodes (no tree is compared)."""
    rep, table = {}, {}
    for e in order:
        key = (type(e), e) if not e.args else (e.func, tuple(id(rep[id(a)]) for a in e.args))
        rep[id(e)] = table.setdefault(key, e)
    return rep


def shared_form(rows, flat_max: int = FLAT_MAX, inline_max: int = INLINE_MAX,
                shared_min: int = SHARED_MIN) -> SharedForm:
    """``rows`` ((label, expression) pairs, or a dict) in shared form (module docstring);
    time and size linear in the number of distinct subexpressions.  Equal
    subexpressions get one name, however many objects hold them (``canonical``)."""
    rows = [r if isinstance(r, str) else (r[0], sp.sympify(r[1], strict=True))
            for r in (rows.items() if isinstance(rows, dict) else rows)]
    exprs = [r[1] for r in rows if not isinstance(r, str)]
    if tree_size(exprs, flat_max) <= flat_max:
        return SharedForm(rows, [])
    order = dag.nodes(exprs)
    rep = canonical(order)
    order = [e for e in order if rep[id(e)] is e]

    def key(a) -> int:
        return id(rep[id(a)])

    uses: dict[int, int] = {}
    for e in order:
        for a in {key(a) for a in e.args}:
            uses[a] = uses.get(a, 0) + 1
    for k in {key(e) for e in exprs}:   # a row repeated (two principles agree) is
        uses[k] = uses.get(k, 0) + 1    # printed again, not named
    size: dict[int, int] = {}           # tree nodes as printed (a name counts one)
    named: set[int] = set()
    for e in order:
        if not e.args:
            size[id(e)] = 1
            continue
        args = [rep[id(a)] for a in e.args]
        parts = sorted((a for a in {id(a): a for a in args}.values() if id(a) not in named),
                       key=lambda a: -size[id(a)])
        s = 1 + sum(1 if id(a) in named else size[id(a)] for a in args)
        for a in parts:                 # name the largest parts until the line fits
            if size[id(a)] <= inline_max and (e.is_Add or s <= inline_max
                                              or size[id(a)] <= 2):
                break                   # (a sum of short terms reads well on one line)
            named.add(id(a))
            s -= (size[id(a)] - 1) * sum(b is a for b in args)
        size[id(e)] = s
        if uses.get(id(e), 0) > 1 and s >= shared_min:
            named.add(id(e))
    prefix = _prefix(exprs)
    shown: dict[int, sp.Expr] = {}      # what a parent prints for the node
    where = []
    for e in order:
        if not e.args:
            shown[id(e)] = e
            continue
        args = tuple(shown[key(a)] for a in e.args)
        body = e.func(*args) if any(a is not b for a, b in zip(args, e.args)) else e
        if id(e) in named:
            name = sp.Symbol(f"{prefix}_{len(where) + 1}")
            where.append((name, body))
            shown[id(e)] = name
        else:
            shown[id(e)] = body
    return SharedForm([r if isinstance(r, str) else (r[0], shown[key(r[1])]) for r in rows],
                      where)
