"""Polynomial first integrals of a principle's equations, found by an ansatz.

``conserved_quantities(sysm, principle, degree, coefficients)`` returns a basis of the
functions I(t, q, qdot^mu[, lambda]) = sum_j c_j g_j(t, q) m_j(qdot^mu, lambda), m_j a
monomial of degree <= ``degree`` in the independent velocities (and, for the vakonomic and
Hoelder principles, the multipliers), with rational constants c_j, whose total derivative
vanishes on the equations on the constraint manifold (Olver 1993, section 4.3: first
integrals as the kernel of the total derivative on the solution manifold).  The condition
D I = 0 is linear in c: it is imposed at random rational points, solved exactly over Q
(or at 50 digits, the null vectors then read back as rationals), and every returned I is
checked again, symbolically where cheap and at fresh points.

Parameters of the system are indeterminates: the c_j do not depend on them (include
parameter factors in ``coefficients`` to allow it).
"""

from __future__ import annotations

import itertools
import random
from fractions import Fraction

import mpmath
import sympy as sp

from . import dag
from .constraints import PRINCIPLES, System
from .errors import ArgumentError, JetnhError, PrincipleError

BUDGET = 400            # unknowns of the ansatz
DPS = 50                # digits of the numeric route
_TOL = mpmath.mpf(10) ** -30

_WITH_MULTIPLIERS = ("vakonomic", "holder")


def conserved_quantities(sysm, principle, degree=2, coefficients=None) -> list:
    """A basis (echelon form, rational coefficients) of the nontrivial first integrals of
    ``principle`` polynomial of degree <= ``degree`` in the independent velocities (and
    multipliers), with coefficient functions spanned by ``coefficients`` (expressions in t
    and q; default: the monomials in t and q of degree <= ``degree``).  The constants are
    numbers: an integral whose coefficients depend on the system's parameters (m x_t**2/2
    + k x**2/2) is found only when ``coefficients`` holds those parameter factors."""
    if not isinstance(sysm, System):
        raise ArgumentError(f"conserved_quantities needs a jetnh System, not {type(sysm).__name__}")
    if not isinstance(principle, str) or principle not in PRINCIPLES:
        raise PrincipleError(f"unknown principle {principle!r}; choose one of {PRINCIPLES}")
    if isinstance(degree, bool) or not isinstance(degree, int) or degree < 1:
        raise ArgumentError(f"degree must be an integer >= 1 (the degree in the velocities), "
                            f"not {degree!r}")
    J = sysm.J
    eom = sysm.equations(principle)
    acc = eom.accelerations()                       # its errors propagate
    G = _coefficients(sysm, coefficients, degree)
    vel = list(sysm.independent_velocities)
    lam = list(eom.multipliers) if principle in _WITH_MULTIPLIERS else []
    rates = list(eom.multiplier_rates) if lam else []
    qdd = [J.jet(q, 2) for q in sysm.independent]
    needed = [acc[a] for a in qdd + rates]
    if not lam and any(e.free_symbols & set(eom.multipliers) for e in needed):
        lam = list(eom.multipliers)               # the motion depends on them: keep them
        rates = list(eom.multiplier_rates)
        needed = [acc[a] for a in qdd + rates]
    U = vel + lam
    monos = [e for d in range(degree + 1) for e in _exponents(len(U), d)]
    base = {J.t, *J.q}
    pairs = [(i, e) for i, g in enumerate(G) for e in monos
             if sum(e) or g.free_symbols & base]          # no constant
    if len(pairs) > BUDGET:
        raise ArgumentError(
            f"the ansatz has {len(pairs)} unknowns ({len(G)} coefficient functions x "
            f"{len(monos)} monomials of degree <= {degree} in {len(U)} velocities and "
            f"multipliers), over the budget of {BUDGET}; lower degree or pass fewer "
            "coefficients (e.g. coefficients=[1])")
    qdot = [sysm.phi.get(v, v) for v in J.qd]
    ev = _Evaluator(sysm, eom.J, G, needed, qdot, U)
    basis = _nullspace(lambda rng, count: _rows(ev, pairs, monos, U, rng, count),
                       len(pairs), ev.exact)
    out = []
    for vec in basis:
        I = sp.Add(*[c * G[i] * _mono(U, e) for c, (i, e) in zip(vec, pairs) if c])
        _check(sysm, I, acc, ev, U)
        out.append(I)
    return out


# ---------------------------------------------------------------------- the ansatz
def _exponents(n, d):
    """Exponent tuples of the monomials of degree d in n variables (graded lex order)."""
    return sorted((tuple(c.count(i) for i in range(n))
                   for c in itertools.combinations_with_replacement(range(n), d)), reverse=True)


def _mono(U, e):
    return sp.Mul(*[u**k for u, k in zip(U, e)])


def _coefficients(sysm, coefficients, degree):
    J = sysm.J
    base = [J.t, *J.q]
    if coefficients is None:
        return [_mono(base, e) for d in range(degree + 1) for e in _exponents(len(base), d)]
    if isinstance(coefficients, (str, bytes)) or not hasattr(coefficients, "__iter__"):
        raise ArgumentError("coefficients must be a list of expressions in t and q, "
                            f"not {coefficients!r}")
    allowed = set(base) | set(sysm.parameters)
    G = []
    for c in coefficients:
        try:
            g = sp.sympify(c)
        except (sp.SympifyError, TypeError):
            raise ArgumentError(f"coefficient {c!r} is not an expression; give expressions "
                                "in t and q") from None
        extra = g.free_symbols - allowed
        if extra or g == 0:
            raise ArgumentError(
                f"coefficient {g} " + (f"has {sorted(map(str, extra))}, not t, q or a parameter"
                                       if extra else "is zero") +
                "; coefficients are nonzero functions of t and q (velocities go in degree)")
        G.append(g)
    if not G:
        raise ArgumentError("coefficients is empty; give at least one function of t and q")
    consts = [g for g in G if not g.free_symbols & set(base)]
    if len(consts) > 1:
        raise ArgumentError(f"coefficients has {len(consts)} constants ({consts}); keep one")
    return G


# ---------------------------------------------------------------------- evaluation
class _Evaluator:
    """Values at a point of qdot^s, the accelerations, the coefficient functions and
    their derivatives: exact (Rational) when all are rational functions, else 50 digits."""

    def __init__(self, sysm, J, G, needed, qdot, U):
        self.J, self.sysm = J, sysm
        self.vars = [J.t, *sysm.J.q, *U, *sysm.parameters]
        grads = [[sp.diff(g, x) for x in (J.t, *sysm.J.q)] for g in G]
        self.exprs = [*qdot, *needed, *G, *itertools.chain(*grads)]
        self.sizes = (len(qdot), len(needed), len(G))
        self.exact = all(not e.has(sp.Float) and e.is_rational_function(*self.vars)
                         for e in self.exprs)

    def point(self, rng):
        """A random point: rationals in [-2, 2] (parameters in [1/2, 2])."""
        p = {}
        for s in self.vars:
            if s in self.sysm.parameters:
                p[s] = sp.Rational(rng.randint(4, 16), 8)
            else:
                p[s] = sp.Rational(rng.randint(-24, 24), rng.randint(7, 12))
        return p

    def values(self, exprs, point):
        if self.exact:
            vals = dag.xreplace(list(exprs), point)
            if all(v.is_Rational for v in vals):
                return vals
            raise ZeroDivisionError                 # a singular point: draw another
        vals = dag.evaluate(list(exprs), point, dps=DPS + 10)
        if any(not isinstance(v, mpmath.mpf) or not mpmath.isfinite(v) for v in vals):
            raise ZeroDivisionError
        return vals

    def split(self, vals):
        a, b, c = self.sizes
        grads = vals[a + b + c:]
        n1 = 1 + self.sysm.J.n
        return vals[:a], vals[a:a + b], vals[a + b:a + b + c], \
            [grads[i * n1:(i + 1) * n1] for i in range(c)]


def _rows(ev, pairs, monos, U, rng, count):
    """``count`` rows of the linear condition on c: D(g m) at random points."""
    rows = []
    while len(rows) < count:
        p = ev.point(rng)
        try:
            qdot, accel, gv, grads = ev.split(ev.values(ev.exprs, p))
        except (ZeroDivisionError, ValueError):
            continue
        u = [p[x] for x in U]
        Dg = [gr[0] + sum(d * v for d, v in zip(gr[1:], qdot)) for gr in grads]
        mv, dm = {}, {}
        for e in monos:
            mv[e] = _prod(u, e)
            dm[e] = sum((e[k] * _prod(u, e[:k] + (e[k] - 1,) + e[k + 1:]) * accel[k]
                         for k in range(len(U)) if e[k]), 0)
        rows.append([Dg[i] * mv[e] + gv[i] * dm[e] for i, e in pairs])
    return rows


def _prod(u, e):
    r = 1
    for x, k in zip(u, e):
        if k:
            r = r * x**k
    return r


# ---------------------------------------------------------------------- linear algebra
def _nullspace(draw, n, exact):
    """The reduced-echelon null basis (lists of Rationals) of the condition rows."""
    rng = random.Random(20240614)
    rows = draw(rng, 2 * n)
    if exact:       # exact rows: the same fast route, then the exact check (cancel)
        with mpmath.workdps(DPS):
            rows = [[mpmath.mpf(int(v.p)) / int(v.q) for v in r] for r in rows]
    return _numeric_nullspace(rows, n)


def _numeric_nullspace(rows, n):
    """RREF of the 50-digit rows (scaled partial pivoting) in fixed point (integers times
    2^-256, fast), null vectors read back as rationals."""
    P = 256
    tol = int(_TOL * 2**P)
    with mpmath.workdps(DPS):
        A = []
        for r in rows:
            s = max((abs(v) for v in r), default=0)
            if s:
                A.append([int(mpmath.nint(mpmath.mpf(v) / s * 2**P)) for v in r])
    piv, i = [], 0
    for j in range(n):
        k = max(range(i, len(A)), key=lambda k: abs(A[k][j]), default=None)
        if k is None or abs(A[k][j]) < tol:
            continue
        A[i], A[k] = A[k], A[i]
        p = A[i][j]
        A[i] = [0] * j + [(v << P) // p for v in A[i][j:]]
        row = A[i][j:]
        for k2 in range(len(A)):
            f = A[k2][j]
            if k2 != i and f:
                A[k2][j:] = [a - ((f * b) >> P) for a, b in zip(A[k2][j:], row)]
        piv.append(j)
        i += 1
    free = [j for j in range(n) if j not in set(piv)]
    out = []
    with mpmath.workdps(DPS):
        for f in free:
            vec = [sp.S.Zero] * n
            vec[f] = sp.S.One
            for r, j in enumerate(piv):
                vec[j] = _rational(-mpmath.mpf(A[r][f]) / 2**P)
            out.append(vec)
    return out


def _rational(x):
    fr = Fraction(mpmath.nstr(x, DPS)).limit_denominator(10**12)
    if abs(x - mpmath.mpf(fr.numerator) / fr.denominator) > _TOL * max(1, abs(x)):
        raise JetnhError(
            f"a first integral has the coefficient {mpmath.nstr(x, 20)}, not a rational "
            "number: jetnh finds integrals with rational coefficients only; pass "
            "coefficients that absorb the irrational factor")
    return sp.Rational(fr.numerator, fr.denominator)


# ---------------------------------------------------------------------- the final check
def _check(sysm, I, acc, ev, U):
    """D I = 0 on the equations and the constraints: symbolically (cancel) where that
    decides it, and at 20 fresh random points (50 digits) always."""
    J = ev.J
    DI = sysm.on_constraints(J.D(I).xreplace(acc))
    if ev.exact and sp.cancel(sp.together(DI)) != 0:
        raise JetnhError(f"internal: {I} passed the sampled condition but D I = "
                         f"{sp.cancel(sp.together(DI))} != 0; please report")
    rng = random.Random(7)
    scale = 1 + sum(abs(c) for c in sp.Poly(I, *U).coeffs() if c.is_Number) \
        if I.is_polynomial(*U) else 1
    done = 0
    while done < 20:
        p = ev.point(rng)
        try:
            v = dag.evaluate(DI, p, dps=DPS)
        except (ZeroDivisionError, ValueError):
            continue
        if not mpmath.isfinite(v):
            continue
        if abs(v) > mpmath.mpf(10) ** -25 * scale:
            raise JetnhError(f"{I} is not conserved: D I = {mpmath.nstr(v, 10)} at {p}; the "
                             "numeric null space was misread, lower degree and report this")
        done += 1
