"""Results shown by derive and compare: text, LaTeX or JSON, on the screen within a
budget or in full to a file, with small expressions simplified for display."""

from __future__ import annotations

import time
from pathlib import Path

import sympy as sp

from . import outputs

#: characters of a result printed on the screen; --out FILE writes the full form
SCREEN_BUDGET = 20_000


def label(expr) -> str:
    """A short input expression (L, a force) in full, a large one summarized."""
    from ..algebra.singular import label as summarized

    return summarized(sp.sympify(expr, strict=True))


def write(args, progress, text: str, form) -> None:
    """The result: to --out in full, else on stdout (``text`` is the short form)."""
    if args.out:
        path = outputs.check(args.out, outputs.TEXT, "--out")
        outputs.write(path, lambda tmp: Path(tmp).write_text(text + "\n", encoding="utf-8"))
        progress.note(f"jetnh: wrote {path} ({len(form.where)} named quantities)")
    else:
        print(text)


def render(args, form, header: list, data: dict, J, keys=None) -> str:
    """``form`` (``jetnh.algebra.shared``) after ``header`` lines (text and LaTeX) or inside
    ``data`` (JSON, its headings renamed by ``keys``): in full with --out, else within
    the screen budget."""
    from ..algebra.shared import SharedForm

    budget = None if args.out else SCREEN_BUDGET
    more = " (write them all with --out FILE)"
    if args.format == "json":
        keys = keys or {}
        form = SharedForm([keys.get(r, r) if isinstance(r, str) else r for r in form.rows],
                          form.where)
        data.update(form.as_dict(budget))
        return outputs.as_json(data, indent=2)
    if args.format == "latex":
        return form.latex(J, budget, more)
    return "\n".join(header + [form.text(budget, more)])


def simplified(form, seconds, progress):
    """``form`` with its small expressions (rows and named quantities: ``Simplifier``)
    trigsimp'd within ``seconds`` each, 10 x ``seconds`` in all, the others kept (the
    rows refer to the named quantities by name).  ``seconds`` None: 0.5 s for a result
    small enough to be shown without names, else none."""
    from ..algebra.shared import SharedForm

    if seconds is None:
        seconds = 0.0 if form.where else 0.5
    simp = Simplifier(per=seconds, total=10 * seconds)
    if not simp.ok:
        return form
    with progress.step(f"simplifying for display ({seconds:g} s each)"):
        rows = [r if isinstance(r, str) else (r[0], simp(r[1])) for r in form.rows]
        where = [(name, simp(e)) for name, e in form.where]
    progress.note(f"jetnh: simplified {simp.done} of {len(form.expressions()) + len(where)} expressions ("
                  f"{simp.large} too large, {simp.timed_out} out of time, "
                  f"{simp.unstarted} "
                  f"past the {simp.total:g} s budget: shown as derived)")
    return SharedForm(rows, where)


class _Budget(Exception):
    pass


class Simplifier:
    """trigsimp for display (never on a hot path): each expression of at most ``nodes``
    tree nodes within ``per`` seconds, at most ``total`` seconds in all (SIGALRM; where
    that is unavailable, or with ``per = 0``, expressions are shown as derived)."""

    def __init__(self, per: float = 0.5, total: float = 5.0, nodes: int = 60):
        import signal
        import threading

        self.per, self.left, self.total, self.nodes = per, total, total, nodes
        self.done = self.timed_out = self.unstarted = self.large = 0
        self.ok = (per > 0 and hasattr(signal, "setitimer")
                   and threading.current_thread() is threading.main_thread())

    def __call__(self, expr):
        from ..algebra.shared import tree_size

        if tree_size([expr], self.nodes) > self.nodes:
            self.large += 1
            return expr
        if not self.ok or self.left <= 0:
            self.unstarted += 1
            return expr
        import signal

        def alarm(signum, frame):
            raise _Budget
        budget = min(self.per, self.left)
        old = signal.signal(signal.SIGALRM, alarm)
        t0 = time.perf_counter()
        try:
            signal.setitimer(signal.ITIMER_REAL, budget)
            try:
                out = sp.trigsimp(expr)
                self.done += 1
                return out
            finally:
                signal.setitimer(signal.ITIMER_REAL, 0)
        except _Budget:
            self.timed_out += 1
            return expr
        finally:
            signal.signal(signal.SIGALRM, old)
            self.left -= time.perf_counter() - t0


def forces(system) -> dict:
    """The nonzero generalized forces Q_s (forces and -dD/dqdot^s), by coordinate name."""
    return {q.name: label(Q) for q, Q in zip(system.J.q, system.Q) if Q != 0}
