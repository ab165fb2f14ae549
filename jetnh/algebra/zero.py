"""Every zero test of jetnh: symbolic (``expr_is_zero``, ``zero_residual``: expand, a
random witness, a common denominator, simplify only when asked) and by evaluation at
random points on the shared graph (``vanishes``; ``dag.evaluate``, never flattened): what
the symbolic tests do above their size budget, and how ``compare`` decides.

A Schwartz-Zippel style test: a nonzero analytic expression vanishes at a random point
with probability zero (also on a constraint manifold, the dependent velocities computed
at each point).  Each point is rational, in [0.31, 1.37] (and with random signs too where
the expressions hold a node that is not analytic across a sign change, such as Abs or
sqrt(u**2): ``_one_signed``), and evaluated at 30 and 60 digits: a value both precisions
confirm is nonzero; one that shrinks with the precision is the
rounding noise of an exact zero; between the two the point is evaluated exactly
(rational expressions at rational points) or at 120 digits.  An expression with Floats
(inexact input) is zero where its value is below ``ROUNDING`` times the magnitude of the
terms that cancel in it (every sum evaluated with its terms' absolute values), or below
``DOUBLE_ROUNDING``: a coefficient typed into the input is data, not rounding, unless it
is below the rounding of a double (1e-15; give smaller ones as a Rational or a
parameter).

``decisions()`` collects, for the callers that report how they decided, how many
expressions were decided this way.
"""

from __future__ import annotations

import contextlib
import contextvars
import random

import mpmath
import sympy as sp
from sympy.core.function import AppliedUndef

from . import dag, linalg

POINTS = 4
TREE_MAX = 400           # tree nodes above which the symbolic zero tests evaluate instead
SIMPLIFY_MAX = 100       # ... and above which a numerically zero one is not simplified
ROUNDING = 1e-9          # relative size under which a value with Floats in it is zero
DOUBLE_ROUNDING = 1e-15  # absolute size under which it is zero (a few ulps of a double)
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

    def at(signed):
        base = {s: sp.Rational(rng.randrange(31 * _DEN // 100, 137 * _DEN // 100), _DEN)
                * (_sign(s, rng) if signed else 1) for s in syms}
        try:
            real = _real_point(point) if signed else point
            if signed and any(isinstance(v, mpmath.mpc) and v.imag
                              for v in _values(exprs, base, real, 30)):
                return None         # not real here (a root of a negative number)
            return (_small_at(exprs, base, real) if inexact
                    else _zero_at(exprs, base, real, exact_point))
        except (ValueError, ZeroDivisionError, ArithmeticError):
            return None             # off the domain (a root of a negative number, ...)

    for signed in (False, True) if _one_signed(exprs) else (False,):
        got = 0
        for _ in range(4 * points):
            if got >= points:
                break
            zero = at(signed)
            if zero is False:
                return False
            got += zero is True
        if not signed and got < max(1, points // 2):
            return False
    return True


def _sign(s, rng) -> int:
    """A random sign for symbol ``s`` within its assumptions (a symbol declared positive
    or nonnegative stays positive, one declared negative or nonpositive negative; drawn
    for every symbol, so the points stay those of the same seed)."""
    sign = rng.choice((-1, 1))
    return 1 if s.is_nonnegative else -1 if s.is_nonpositive else sign


def _one_signed(exprs) -> bool:
    """Whether ``exprs`` hold a node that is not analytic where a symbol changes sign
    (Abs, sign, sqrt(u**2), ...): then positive points alone cannot decide them, and
    ``vanishes`` also draws points with random signs."""
    for e in dag.nodes(exprs):
        if isinstance(e, (sp.Abs, sp.sign, sp.Heaviside, sp.Piecewise, sp.Max, sp.Min)):
            return True
        if (e.is_Pow and not e.exp.is_integer and e.base.is_Pow
                and e.base.exp.is_even):
            return True
    return False


def _real_point(point):
    """``point`` (or the plain one) refusing a point where a dependent value is not real."""
    def real(base, dps):
        pt = point(base, dps) if point else {s: mpmath.mpf(v.p) / v.q
                                              for s, v in base.items()}
        if any(isinstance(v, mpmath.mpc) for v in pt.values()):
            raise ValueError("no real point here")
        return pt
    return real


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
            vals = linalg.exact_values(exprs, free)
            sol = sp.Matrix(k, k, vals[:k * k]).LUsolve(-sp.Matrix(vals[k * k:]))
        else:
            vals = dag.evaluate(exprs, free, dps=mpmath.mp.dps)
            A = mpmath.matrix([vals[i * k:(i + 1) * k] for i in range(k)])
            sol = linalg.mp_solve(A, -mpmath.matrix(vals[k * k:]))
    elif exact:
        sol = linalg.exact_values([system.phi[v] for v in vel], free)
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
            pt[v] = linalg.real_value(x)
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
        pt.update({s: linalg.exact_values([e], pt)[0] for s, e in derived.items()})
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
    magnitude of the terms that cancel (``_magnitudes``), or below ``DOUBLE_ROUNDING``."""
    with mpmath.workdps(30):
        pt = point(base, 30) if point else {s: mpmath.mpf(v.p) / v.q
                                             for s, v in base.items()}
        pairs = _magnitudes(exprs, pt)
    for v, m in pairs:
        if not (mpmath.isfinite(v) and mpmath.isfinite(m)):
            raise ZeroDivisionError("not finite here")
        if abs(v) > ROUNDING * m + DOUBLE_ROUNDING:
            return False
    return True


def _magnitudes(exprs, pt) -> list:
    """(value, magnitude) of each of ``exprs`` at ``pt`` on the shared graph: the
    magnitude is the value with every sum taken over its terms' magnitudes (a product
    of magnitudes, a positive integer power of one), so what rounding can leave of a
    cancellation is small relative to it, and a lone term is its own magnitude."""
    prec = mpmath.mp.prec

    def leaf(e):
        if e in pt:
            v = mpmath.mpmathify(pt[e])
        elif e.is_Number or e.is_NumberSymbol or e is sp.I:
            v = dag._number(e, prec)
        else:
            return None
        return v, abs(v)

    def add(args):
        return mpmath.fsum(v for v, _ in args), mpmath.fsum(m for _, m in args)

    def mul(args):
        return mpmath.fprod(v for v, _ in args), mpmath.fprod(m for _, m in args)

    def power(base, exp):
        if base[0] != 0 and exp[0] != 0:
            dag._exponent_check(mpmath.re(exp[0]) * mpmath.log(abs(base[0])), 30)
        v = mpmath.power(base[0], exp[0])
        whole = exp[0] == mpmath.nint(mpmath.re(exp[0])) and mpmath.re(exp[0]) > 0
        return v, (mpmath.power(base[1], exp[0]) if whole else abs(v))

    def function(e, args):
        f = dag._SPECIAL.get(type(e).__name__) or getattr(mpmath, type(e).__name__, None)
        vals = [a for a, _ in args]
        if isinstance(e, sp.exp):
            dag._exponent_check(mpmath.re(vals[0]), 30)
        v = f(*vals) if f else dag.evaluate(e.func(*map(dag.to_sympy, vals)), {}, dps=30)
        return v, abs(v)

    return dag._values(exprs, leaf, add, mul, power, function)


def _zero_exactly(undecided, base, point, exact_point) -> bool:
    """Undecided values ``[(expr, value at 60 digits), ...]``: exactly, those small enough
    when everything is rational (one point, one walk for all), else at 120 digits."""
    small = [(e, hi) for e, hi in undecided
             if dag.size(e, cap=linalg.EXACT_MAX + 1) <= linalg.EXACT_MAX]
    rest = [u for u in undecided if all(u is not v for v in small)]
    if small:
        try:
            pt = exact_point(base) if exact_point else dict(base)
            if any(v != 0 for v in linalg.exact_values([e for e, _ in small], pt)):
                return False
        except linalg.Inexact:
            rest = undecided
    if not rest:
        return True
    tops = _values([e for e, _ in rest], base, point, 120)
    return all(abs(top) <= _SHRINK * abs(hi) for top, (_, hi) in zip(tops, rest))


# ---------------------------------------------------------------------- symbolic zero tests
def expr_is_zero(expr, *, simplify: bool = False, numeric: bool = False, samples: int = 3,
                 seed: int = 0, tol: float = 1e-9) -> bool:
    """Decide expr == 0 without ``simplify`` unless asked (see :func:`zero_residual`).

    expand; a nonzero value at one random point proves non-zero; a rational expression
    is put over a common denominator (``together`` of the unexpanded expression) and its
    numerator expanded.  ``simplify=True`` adds ``sympy.simplify`` as a last resort (trig
    identities); ``numeric=True`` instead decides by evaluation at ``samples`` random
    points (every free symbol, function application and derivative replaced by random
    real numbers of both signs, evaluated to 30 digits; points where the expression is
    undefined are resampled).
    """
    return zero_residual(expr, simplify=simplify, numeric=numeric, samples=samples,
                         seed=seed, tol=tol) is None


def zero_residual(expr, *, simplify: bool = False, numeric: bool = False, samples: int = 3,
                  seed: int = 0, tol: float = 1e-9):
    """None when ``expr`` is decided zero, else a nonzero form of it (expanded/simplified).

    An expression over ``TREE_MAX`` tree nodes is decided by evaluation at random
    points on its shared graph (``vanishes``) and returned as it is.  One over
    ``SIMPLIFY_MAX`` is not expanded (its expansion can still explode): step (2)
    decides a nonzero one, and one numerically zero that Poly does not prove zero goes
    to ``vanishes`` too.  Otherwise, steps, cheapest first: (1) ``sympy.expand``
    (for a rational expression, whose expansion can be huge, instead the numerator of
    ``together(expr)`` is expanded after step 2); (2) one evaluation at a random point:
    a clearly nonzero value proves non-zero and ends the test; (3) ``numeric``:
    evaluation at ``samples`` points decides; otherwise (4) ``simplify`` when asked.  So ``simplify`` only ever runs on expressions
    that are numerically zero but not algebraically zero after expansion -
    trigonometric identities, in practice.
    """
    raw = dag.sympy_object(expr)
    if raw == 0:
        return None
    if large(raw):                  # expand/simplify would explode: evaluate
        return _by_evaluation(raw, seed)
    rational = any(p.exp.is_negative for p in raw.atoms(sp.Pow))
    small = not large(raw, SIMPLIFY_MAX)
    e = raw
    if not rational and small:
        e = sp.expand(raw)
        if e == 0:
            return None
    try:
        looks_zero = numeric_is_zero(raw, samples=1, seed=seed, tol=tol)
    except ValueError:                   # undefined at every sampled point: no witness
        looks_zero = True
    if not looks_zero:
        return e
    if rational and _polynomial_is_zero(sp.numer(sp.together(raw))):
        return None
    if not small and not numeric:
        return _by_evaluation(raw, seed)
    if rational and small:
        e = sp.expand(raw)
        if e == 0:
            return None
    if numeric:
        try:
            return None if numeric_is_zero(raw, samples=samples, seed=seed + 1, tol=tol) else e
        except ValueError:
            return e
    if simplify:
        s_ = sp.simplify(e)
        return None if s_ == 0 else s_
    return e


def _by_evaluation(raw, seed):
    """``zero_residual`` of a large expression: ``vanishes`` on its graph (undefined
    functions and derivatives as independent symbols)."""
    opaque = [a for a in dag.nodes(raw) if isinstance(a, (sp.Derivative, AppliedUndef))]
    plain = dag.xreplace(raw, {a: sp.Dummy(f"u{i}") for i, a in enumerate(opaque)})
    return None if vanishes([plain], seed=seed) else raw


def _polynomial_is_zero(expr) -> bool:
    """Exact zero test of a polynomial expression via sympy.Poly (fast multiplication).

    Non-polynomial subexpressions (sin(x), sqrt(x), f(t), ...) become generators treated
    as independent, so True is always correct; False may miss relations between them.
    """
    if expr == 0:
        return True
    try:
        return sp.Poly(expr).is_zero
    except sp.polys.polyerrors.GeneratorsNeeded:          # a number
        return sp.expand(expr) == 0
    except sp.polys.polyerrors.PolynomialError:
        return sp.expand(expr) == 0


def numeric_is_zero(expr, *, samples: int = 3, seed: int = 0, tol: float = 1e-9) -> bool:
    """True when ``expr`` vanishes at ``samples`` random points (relative tolerance ``tol``)."""
    expr = dag.sympy_object(expr)
    opaque = list(expr.atoms(sp.Derivative)) + list(expr.atoms(AppliedUndef))
    if opaque:
        expr = expr.xreplace({a: sp.Dummy(f"u{i}") for i, a in enumerate(opaque)})
    syms = sorted(expr.free_symbols, key=sp.default_sort_key)
    terms = sp.Add.make_args(expr)
    rng = random.Random(seed)
    done = tries = 0
    while done < samples:
        tries += 1
        if tries > 50 * samples:
            raise ValueError(f"could not find points where {expr} is defined")
        vals = {s: sp.Float(rng.choice((-1, 1)) * rng.uniform(0.2, 1.6), 30) for s in syms}
        try:
            v = complex(expr.xreplace(vals).evalf(30))
            scale = max(abs(complex(t.xreplace(vals).evalf(30))) for t in terms)
        except (TypeError, ValueError, ZeroDivisionError):
            continue
        if not all(map(_finite, (v.real, v.imag, scale))):
            continue
        if abs(v) > tol * max(1.0, scale):
            return False
        done += 1
    return True


def _finite(x: float) -> bool:
    return x == x and abs(x) != float("inf")
