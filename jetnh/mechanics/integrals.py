"""Polynomial first integrals of a principle's equations, found by an ansatz.

``conserved_quantities(sysm, principle, degree, coefficients)`` returns a basis of the
functions I(t, q, qdot^mu[, lambda]) = sum_j c_j g_j(t, q) m_j(qdot^mu, lambda), m_j a
monomial of degree <= ``degree`` in the independent velocities (and, for the vakonomic and
Hoelder principles, the multipliers), whose total derivative vanishes on the equations on
the constraint manifold (Olver 1993, section 4.3: first integrals as the kernel of the
total derivative on the solution manifold).  The condition D I = 0 is linear in c and is
solved by ``jetnh.algebra.ansatz``: the constants c_j may depend on the system's parameters
(polynomially in them and in functions of them such as sin(alpha), after clearing
denominators), and the basis is reduced over the rational functions of the parameters.
Every returned I is then proved: D I = 0 exactly (cancel) where the equations are rational,
and at 20 fresh random points at 50 digits always.
"""

from __future__ import annotations

import itertools
import random
from fractions import Fraction

import mpmath
import sympy as sp

from ..algebra import ansatz, dag
from . import principles
from ..algebra.ansatz import exponents as _exponents
from ..algebra.ansatz import monomial as _mono
from ..algebra.ansatz import power_product
from .system import System
from ..errors import ArgumentError, JetnhError
from .principles import Principle

DPS = ansatz.DPS


def check_arguments(sysm, principle, degree, what) -> Principle:
    """The registered principle of ``principle`` after checking the arguments."""
    if not isinstance(sysm, System):
        raise ArgumentError(f"{what} needs a jetnh System, not {type(sysm).__name__}")
    p = principles.get(principle)
    if isinstance(degree, bool) or not isinstance(degree, int) or degree < 1:
        raise ArgumentError(f"degree must be an integer >= 1, not {degree!r}")
    return p


def conserved_quantities(sysm, principle, degree=2, coefficients=None) -> list:
    """A basis of the nontrivial first integrals of ``principle`` that are polynomials in
    the independent velocities (and multipliers).

    None vanishes identically on the constraint manifold (each is written in the
    independent velocities, so no multiple of a constraint appears), and no two are
    proportional over the parameters.  For example the Heisenberg system's vakonomic
    integrals lambda, m x_t + 2 lambda y, m y_t - 2 lambda x and the energy.  A
    JetnhWarning says when some integral's parameter dependence exceeds the search.

    Parameters
    ----------
    sysm : System
        The constrained system.
    principle : str
        The principle whose motions conserve them ("chetaev", "vakonomic", ...).
    degree : int, default 2
        The largest degree in the velocities and multipliers.
    coefficients : list of sympy expressions, optional
        Functions of t and q spanning the coefficients; default the monomials in t and q
        of degree <= ``degree``.  The constants may depend on the parameters.

    Returns
    -------
    list of sympy expressions
        The integrals, in t, q, the independent velocities and the multipliers.
    """
    p = check_arguments(sysm, principle, degree, "conserved_quantities")
    J = sysm.J
    eom = sysm.equations(p)
    acc = eom.accelerations()                       # its errors propagate
    G = coefficient_functions(sysm, coefficients, degree)
    vel = list(sysm.independent_velocities)
    lam = list(eom.multipliers) if p.multipliers_act else []
    rates = list(eom.multiplier_rates) if lam else []
    qdd = [J.jet(q, 2) for q in sysm.independent]
    def on_manifold(syms):
        return dag.xreplace([acc[a] for a in syms], sysm.phi) if sysm.phi else \
            [acc[a] for a in syms]

    needed = on_manifold(qdd + rates)
    if not lam and any(dag.free_symbols(e) & set(eom.multipliers) for e in needed):
        lam = list(eom.multipliers)               # the motion depends on them: keep them
        rates = list(eom.multiplier_rates)
        needed = on_manifold(qdd + rates)
    U = vel + lam
    monos = [e for d in range(degree + 1) for e in _exponents(len(U), d)]
    base = {J.t, *J.q}
    pairs = [(i, e) for i, g in enumerate(G) for e in monos
             if sum(e) or g.free_symbols & base]          # no constant
    if len(pairs) > ansatz.BUDGET:
        raise ansatz.budget_error(
            len(pairs), f"{len(G)} coefficient functions x {len(monos)} monomials of degree "
            f"<= {degree} in {len(U)} velocities and multipliers")
    qdot = [sysm.phi.get(v, v) for v in J.qd]
    problem = _Integrals(sysm, eom.J, G, needed, qdot, U, pairs, monos)
    out = []
    for vec in ansatz.solve(problem, "conserved_quantities"):
        I = sp.Add(*[c * G[i] * _mono(U, e) for c, (i, e) in zip(vec, pairs) if c])
        _check(sysm, I, acc, problem, U)
        out.append(I)
    return out


# ---------------------------------------------------------------------- the ansatz
def coefficient_functions(sysm, coefficients, degree):
    """The coefficient functions of an ansatz: ``coefficients`` checked, or the monomials
    in t and q of degree <= ``degree``."""
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
class Sampler:
    """Values of expressions at random points of ``variables`` (and the parameters):
    exact (Rational) when all are rational functions, else 50 digits; singular points
    are skipped."""

    def __init__(self, variables, parameters, exprs):
        self.parameters = tuple(parameters)
        self.vars = [*variables, *self.parameters]
        self.exact = all(not e.has(sp.Float) and e.is_rational_function(*self.vars)
                         for e in exprs)

    def point(self, rng, fixed=None):
        """Nonzero rationals in [-2, 2] of moderate height (never 0 or a small integer,
        where charts such as Euler angles are singular); parameters from ``fixed`` or in
        [1/2, 2]."""
        p = {s: sp.Rational(rng.choice((-1, 1)) * rng.randint(1, 90), rng.randint(41, 47))
             for s in self.vars if s not in self.parameters}
        p.update(fixed if fixed is not None else
                 ansatz.random_parameters(self.parameters, rng))
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

    def draw(self, exprs, rng, count, fixed=None):
        """``count`` (values, point) pairs at random regular points."""
        out, misses = [], 0
        while len(out) < count:
            p = self.point(rng, fixed)
            try:
                out.append((self.values(exprs, p), p))
            except (ZeroDivisionError, ValueError) as exc:
                misses += 1
                if misses > 100 + 10 * count:
                    raise JetnhError(
                        f"internal: {misses} random points were singular or incomplete "
                        f"({exc!r}); the ansatz conditions may be undefined almost "
                        "everywhere; please report") from None
        return out


class _Integrals(ansatz.Problem):
    """D(g_i m_e) at random points, by the chain rule from the values of qdot^s, the
    accelerations, the coefficient functions and their gradients."""

    def __init__(self, sysm, J, G, needed, qdot, U, pairs, monos):
        self.J, self.sysm, self.G, self.U = J, sysm, G, U
        self.pairs, self.monos = pairs, monos
        self.n = len(pairs)
        grads = [[sp.diff(g, x) for x in (J.t, *sysm.J.q)] for g in G]
        self.exprs = [*qdot, *needed, *G, *itertools.chain(*grads)]
        self.sizes = (len(qdot), len(needed), len(G))
        self.parameters = sysm.parameters
        self.atoms = ansatz.parameter_atoms([sysm.L, *sysm.constraints, *sysm.Q, *G],
                                             sysm.parameters)
        self.sampler = Sampler([J.t, *sysm.J.q, *U], sysm.parameters, self.exprs)
        self.exact = self.sampler.exact

    def point(self, rng):
        return self.sampler.point(rng)

    def _split(self, vals):
        a, b, c = self.sizes
        grads = vals[a + b + c:]
        n1 = 1 + self.sysm.J.n
        return vals[:a], vals[a:a + b], vals[a + b:a + b + c], \
            [grads[i * n1:(i + 1) * n1] for i in range(c)]

    def rows(self, rng, count, fixed=None, columns=None):
        pairs = self.pairs if columns is None else [self.pairs[j] for j in columns]
        return [(self._row(vals, p, pairs), p)
                for vals, p in self.sampler.draw(self.exprs, rng, count, fixed)]

    def _u(self, p):
        return [_fraction(p[x]) if self.exact else ansatz.to_mpf(p[x]) for x in self.U]

    def _row(self, vals, p, pairs):
        U = self.U
        with mpmath.workdps(DPS + 10):
            if self.exact:                  # Fractions: much faster than sympy Rationals
                vals = [_fraction(v) for v in vals]
            qdot, accel, gv, grads = self._split(vals)
            u = self._u(p)
            Dg = [gr[0] + sum(d * v for d, v in zip(gr[1:], qdot)) for gr in grads]
            mv, dm = {}, {}
            for e in {e for _, e in pairs}:
                mv[e] = power_product(u, e)
                dm[e] = sum((e[k] * power_product(u, e[:k] + (e[k] - 1,) + e[k + 1:])
                             * accel[k] for k in range(len(U)) if e[k]), 0)
            return [Dg[i] * mv[e] + gv[i] * dm[e] for i, e in pairs]

    def values(self, point):
        gv = self.sampler.values(self.G, point)
        if self.exact:
            gv = [_fraction(v) for v in gv]
        with mpmath.workdps(DPS + 10):
            u = self._u(point)
            return [gv[i] * power_product(u, e) for i, e in self.pairs]


def _fraction(v):
    return Fraction(int(v.p), int(v.q))


# ---------------------------------------------------------------------- the final check
def _check(sysm, I, acc, problem, U):
    prove_conserved(sysm, problem.J, I, acc, problem.sampler, U)


def prove_conserved(sysm, J, I, acc, sampler, U=()):
    """D I = 0 on the equations (``acc``) and the constraints: exactly (cancel) when they
    are rational, and at 20 fresh random points (50 digits) always; a JetnhError if not."""
    DI = sysm.on_constraints(J.D(I).xreplace(acc))
    if sampler.exact and sp.cancel(sp.together(DI)) != 0:
        raise JetnhError(f"internal: {I} passed the sampled condition but D I = "
                         f"{sp.cancel(sp.together(DI))} != 0; please report")
    rng = random.Random(7)
    scale = 1 + sum(abs(c) for c in sp.Poly(I, *U).coeffs() if c.is_Number) \
        if U and I.is_polynomial(*U) else 1
    missing = dag.free_symbols(DI) - set(sampler.vars)
    if missing:
        raise JetnhError(f"internal: D I depends on {sorted(map(str, missing))}, which the "
                         "check does not sample; please report")
    done = 0
    while done < 20:
        p = sampler.point(rng)
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
