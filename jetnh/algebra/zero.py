"""Deciding that expressions vanish by evaluation at random points, on their shared
graph (``dag.evaluate``), never flattened: what every zero test does above its size
budget, and how ``compare`` decides.

A Schwartz-Zippel style test: a nonzero analytic expression vanishes at a random point
with probability zero (also on a constraint manifold, the dependent velocities computed
at each point).  Each point is rational and evaluated at 30 and 60 digits: a
value both precisions confirm is nonzero; one that shrinks with the precision is the
rounding noise of an exact zero; between the two the point is evaluated exactly
(rational expressions at rational points) or at 120 digits.  An expression with Floats
(inexact input) is zero where its value is below ``ROUNDING`` times its terms.

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
ROUNDING = 1e-9          # relative size under which a value with Floats in it is zero
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


def vanishes(exprs, system=None, points: int = POINTS, seed: int = 0, *, derived=None,
             symbols=None, point=None, exact_point=None) -> bool:
    """Whether ``exprs`` (an expression, or every one of a list) vanishes, by evaluation
    at ``points`` random rational points (module docstring), the list in one walk of its
    shared graph.

    ``system``: draw the points on its constraint manifold (the dependent velocities
    from phi); ``derived``: symbols set at each point from the others (e.g. a branch of
    multiplier values); ``symbols``: those to draw (default: the free symbols, but the
    dependent velocities and the derived ones).  The points can also be given whole:
    ``point(base, dps)`` the values of every symbol at the drawn ``base`` (ValueError off
    the domain: the point is skipped); ``exact_point(base)`` the same as rationals, or
    ``linalg.Inexact``.
    """
    exprs = [sp.sympify(e, strict=True) for e in ([exprs] if isinstance(exprs, sp.Basic) else exprs)]
    exprs = [e for e in exprs if e != 0]
    log = _LOG.get()
    if log is not None:
        log.extend(exprs)
    if not exprs:
        return True
    if point is None and (system is not None or derived):
        syms, point, exact_point = _manifold(exprs, system, dict(derived or {}))
        symbols = syms if symbols is None else symbols
    syms = sorted(dag.free_symbols(exprs) if symbols is None else symbols,
                  key=lambda s: s.name)
    inexact = bool(dag.atoms(exprs, sp.Float))
    rng = random.Random(seed)
    got = 0
    for _ in range(4 * points):
        if got >= points:
            return True
        base = {s: sp.Rational(rng.randrange(31 * _DEN // 100, 137 * _DEN // 100), _DEN)
                for s in syms}
        try:
            zero = (_small_at(exprs, base, point) if inexact
                    else _zero_at(exprs, base, point, exact_point))
        except (ValueError, ZeroDivisionError, ArithmeticError):
            continue                # off the domain (a root of a negative number, ...)
        if not zero:
            return False
        got += 1
    return got >= max(1, points // 2)


def on_constraints(system, values: dict) -> dict:
    """``values`` with the dependent velocities set on the constraints: exactly for a
    rational point (``linalg.Inexact`` when that is impossible), else in the working
    precision of mpmath (the rank tests evaluate at 50 and 80 digits)."""
    vel = system.dependent_velocities
    if not vel:
        return values
    free = {s: v for s, v in values.items() if s not in set(vel)}
    exact = all(isinstance(v, sp.Rational) for v in free.values())
    if system.is_affine:      # A_dep qdot_dep = -f(qdot_dep = 0), never the nested phi
        k = system.k
        f0 = [f.xreplace({v: sp.S.Zero for v in vel}) for f in system.constraints]
        exprs = list(system.jacobian_dependent) + f0
        if exact:
            vals = linalg._exact(exprs, free)
            sol = sp.Matrix(k, k, vals[:k * k]).LUsolve(-sp.Matrix(vals[k * k:]))
        else:
            vals = dag.evaluate(exprs, free, dps=mpmath.mp.dps)
            A = mpmath.matrix([vals[i * k:(i + 1) * k] for i in range(k)])
            sol = mpmath.lu_solve(A, -mpmath.matrix(vals[k * k:]))
    elif exact:
        sol = linalg._exact([system.phi[v] for v in vel], free)
    else:
        sol = dag.evaluate([system.phi[v] for v in vel], free, dps=mpmath.mp.dps)
        if any(isinstance(z, mpmath.mpc) and abs(z.imag) > 1e-12 * (1 + abs(z))
               for z in sol):
            raise ValueError("no real point on the constraints here")
        sol = [mpmath.re(z) for z in sol]
    return {**free, **{v: sol[i] for i, v in enumerate(vel)}}


def _manifold(exprs, system, derived: dict):
    """The symbols to draw and the ``point``/``exact_point`` of ``vanishes`` on the
    constraint manifold of ``system`` (or none), with the ``derived`` symbols."""
    vel = system.dependent_velocities if system is not None else ()
    phi = [system.phi[v] for v in vel]
    syms = dag.free_symbols([*exprs, *derived.values(), *phi]) - set(vel) - set(derived)
    names = list(derived)

    def point(base, dps):
        pt = {s: mpmath.mpf(v.p) / v.q for s, v in base.items()}
        for v, x in zip(vel, dag.evaluate(phi, pt, dps=dps)):
            pt[v] = linalg._real(x)
            if pt[v] is None:
                raise ValueError("no real point on the constraints here")
        pt.update(zip(names, dag.evaluate([derived[s] for s in names], pt, dps=dps)))
        return pt

    def exact_point(base):
        pt = dict(base)
        if system is not None:
            with mpmath.workdps(60):
                pt = on_constraints(system, pt)
        if any(not isinstance(v, sp.Rational) for v in pt.values()):
            raise linalg.Inexact("irrational point")
        pt.update({s: linalg._exact([e], pt)[0] for s, e in derived.items()})
        return pt

    return syms, point, exact_point


def on_manifold_point(system, symbols, rng: random.Random) -> dict:
    """Random Float values (30 digits, in [0.2, 1.3]) for ``symbols`` and the free
    symbols of phi, the dependent velocities of ``system`` computed from phi."""
    dep_vel = set(system.dependent_velocities)
    syms = set(symbols).union(*(dag.free_symbols(p) for p in system.phi.values()))
    vals = {s: sp.Float(rng.uniform(0.2, 1.3), 30)
            for s in sorted(syms - dep_vel, key=lambda s: s.name)}
    with mpmath.workdps(30):
        for v in system.dependent_velocities:
            vals[v] = dag.to_sympy(dag.evaluate(system.phi[v], vals))
    return vals


def value(expr, point: dict) -> complex:
    """``expr`` evaluated at ``point`` on its graph (30 digits), as a complex number."""
    return complex(dag.evaluate(expr, point))


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
    return not undecided or _zero_exactly(undecided, base, point, exact_point)


def _small_at(exprs, base, point) -> bool:
    """Floats in the input: zero up to their rounding, ``ROUNDING`` relative to the
    size of the expression's terms (and at least 1)."""
    terms = [list(sp.Add.make_args(e))[:50] for e in exprs]
    vals = _values(exprs + [t for ts in terms for t in ts], base, point, 30)
    at = len(exprs)
    for v, ts in zip(vals, terms):
        scale = max([1] + [abs(x) for x in vals[at:at + len(ts)]])
        at += len(ts)
        if abs(v) > ROUNDING * scale:
            return False
    return True


def _zero_exactly(undecided, base, point, exact_point) -> bool:
    """Undecided values ``[(expr, value at 60 digits), ...]``: exactly, those small enough
    when everything is rational (one point, one walk for all), else at 120 digits."""
    small = [(e, hi) for e, hi in undecided
             if dag.size(e, cap=linalg._EXACT_MAX + 1) <= linalg._EXACT_MAX]
    rest = [u for u in undecided if all(u is not v for v in small)]
    if small:
        try:
            pt = exact_point(base) if exact_point else dict(base)
            if any(v != 0 for v in linalg._exact([e for e, _ in small], pt)):
                return False
        except linalg.Inexact:
            rest = undecided
    if not rest:
        return True
    tops = _values([e for e, _ in rest], base, point, 120)
    return all(abs(top) <= _SHRINK * abs(hi) for top, (_, hi) in zip(tops, rest))
