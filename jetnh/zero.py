"""Deciding that expressions vanish by evaluation at random points, on their shared
graph (``dag.evaluate``), never flattened: what every zero test does above its size
budget, and how ``compare`` decides.

A Schwartz-Zippel style test: a nonzero analytic expression vanishes at a random point
with probability zero.  Each point is rational and evaluated at 30 and 60 digits: a
value both precisions confirm is nonzero; one that shrinks with the precision is the
rounding noise of an exact zero; between the two the point is evaluated exactly
(rational expressions at rational points) or at 120 digits.

``decisions()`` collects, for the callers that report how they decided, how many
expressions were decided this way.
"""

from __future__ import annotations

import contextlib
import contextvars
import random

import mpmath
import sympy as sp

from . import dag, linalg

POINTS = 4
TREE_MAX = 400           # tree nodes above which the symbolic zero tests evaluate instead
SIMPLIFY_MAX = 100       # ... and above which a numerically zero one is not simplified
_DEN = 100 * 2**16
_CONFIRM = 1e-12         # relative agreement of two precisions that confirms a value
_SHRINK = 1e-20          # a value that shrinks by this going to 60 digits is noise

_LOG: contextvars.ContextVar = contextvars.ContextVar("jetnh_zero_log", default=None)


@contextlib.contextmanager
def decisions():
    """Collect (in a list) one entry per expression ``vanishes`` decided in the block."""
    out: list = []
    token = _LOG.set(out)
    try:
        yield out
    finally:
        _LOG.reset(token)


def large(expr, cap: int = TREE_MAX) -> bool:
    """Whether ``expr`` is over ``cap`` tree nodes (counted on its graph): too large to
    expand or simplify."""
    from .shared import tree_size

    return tree_size([expr], cap) > cap


def vanishes(exprs, point=None, exact_point=None, points: int = POINTS, seed: int = 0,
             symbols=None) -> bool:
    """Whether every expression of ``exprs`` vanishes, by evaluation at ``points`` random
    rational points (module docstring).

    ``symbols``: those to draw (default: the free symbols); ``point(base, dps)``: the
    values of every symbol at the drawn ``base`` (default ``base``; ValueError off the
    domain: the point is skipped); ``exact_point(base)``: the same as rationals, or
    ``linalg.Inexact``.
    """
    exprs = [sp.sympify(e) for e in exprs]
    exprs = [e for e in exprs if e != 0]
    log = _LOG.get()
    if log is not None:
        log.extend(exprs)
    if not exprs:
        return True
    syms = sorted(dag.free_symbols(exprs) if symbols is None else symbols,
                  key=lambda s: s.name)
    rng = random.Random(seed)
    got = 0
    for _ in range(4 * points):
        if got >= points:
            return True
        base = {s: sp.Rational(rng.randrange(31 * _DEN // 100, 137 * _DEN // 100), _DEN)
                for s in syms}
        try:
            zero = _zero_at(exprs, base, point, exact_point)
        except (ValueError, ZeroDivisionError, ArithmeticError):
            continue                # off the domain (a root of a negative number, ...)
        if not zero:
            return False
        got += 1
    return got >= max(1, points // 2)


def _values(exprs, base, point, dps) -> list:
    with mpmath.workdps(dps):
        pt = point(base, dps) if point else {s: mpmath.mpf(v.p) / v.q
                                              for s, v in base.items()}
        vals = dag.evaluate(exprs, pt, dps=dps)
    if not all(mpmath.isfinite(v) for v in vals):
        raise ZeroDivisionError("not finite here")
    return vals


def _zero_at(exprs, base, point, exact_point) -> bool:
    los, his = (_values(exprs, base, point, d) for d in (30, 60))
    undecided = []
    for e, lo, hi in zip(exprs, los, his):
        if hi == 0 and lo == 0:
            continue
        if abs(lo - hi) <= _CONFIRM * abs(hi):
            return False
        if abs(hi) > _SHRINK * abs(lo):
            undecided.append((e, hi))
    return all(_zero_exactly(e, hi, base, point, exact_point) for e, hi in undecided)


def _zero_exactly(expr, hi, base, point, exact_point) -> bool:
    """An undecided value: exactly, when everything is rational, else at 120 digits."""
    try:
        if dag.size(expr, cap=linalg._EXACT_MAX + 1) > linalg._EXACT_MAX:
            raise linalg.Inexact("too large to evaluate exactly")
        pt = exact_point(base) if exact_point else dict(base)
        return linalg._exact([expr], pt)[0] == 0
    except linalg.Inexact:
        top = _values([expr], base, point, 120)[0]
        return abs(top) <= _SHRINK * abs(hi)
