"""Polynomial first integrals of a principle's equations, found by an ansatz.

``conserved_quantities(sysm, principle, degree, coefficients)`` returns a basis, modulo
the constraints, of the functions I(t, q, qdot[, lambda]) = sum_j c_j g_j(t, q) m_j(qdot,
lambda), m_j a monomial of degree <= ``degree`` in all the velocities (the dependent ones
included) and, for every principle whose multipliers are states (vakonomic, Hoelder,
Suslov: their rates are integrated with the motion), the multipliers, whose total
derivative vanishes on the equations on the constraint manifold
(Olver 1993, section 4.3: first integrals as the kernel of the
total derivative on the solution manifold).  The condition D I = 0 is linear in c and is
solved by ``jetnh.algebra.ansatz``: the constants c_j may depend on the system's parameters
(polynomially in them and in functions of them such as sin(alpha), after clearing
denominators), and the basis is reduced over the rational functions of the parameters.
Every returned I is then proved: D I = 0 exactly (cancel) where the equations are rational,
and at 20 fresh random points at 50 digits always.
"""

from __future__ import annotations

import itertools
import numbers
import random
from collections.abc import Iterable
from fractions import Fraction
from math import comb

import mpmath
import numpy as np
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
    """A basis, modulo the constraints, of the nontrivial first integrals of ``principle``
    polynomial of total degree <= ``degree`` in all the velocities (dependent ones
    included) and the multipliers of every principle whose multipliers are states
    (vakonomic, Hoelder, Suslov), e.g. the Suslov integrals lambda_alpha + p_alpha of a
    Chaplygin system (Zhao et al. 2008, (41a)).

    The search is complete in its space: an empty list means that no integral exists
    there.  None vanishes on the constraint manifold (checked exactly against the
    constraints), no combination of them does, and integrals that are polynomial in the
    independent velocities are written in them.  For example the Heisenberg system's
    vakonomic integrals lambda, m x_t + 2 lambda y, m y_t - 2 lambda x and the energy.  A
    JetnhWarning says when some integral's parameter dependence exceeds the search; an
    ``ArgumentError`` refuses an ansatz over the budget before it is built.

    Parameters
    ----------
    sysm : System
        The constrained system.
    principle : str
        The principle whose motions conserve them ("chetaev", "vakonomic", ...).
    degree : int, default 2
        The largest total degree in the velocities and multipliers.
    coefficients : list of sympy expressions, optional
        Functions of t and q spanning the coefficients; default the monomials in t and q
        of degree <= ``degree``, and those times each function of q that L, the
        constraints and the forces contain (such as sin(theta)).  The constants may
        depend on the parameters.  Strings are refused (never parsed).

    Returns
    -------
    list of sympy expressions
        The integrals, in t, q, the velocities and the multipliers.
    """
    p = check_arguments(sysm, principle, degree, "conserved_quantities")
    J = sysm.J
    # sizes first (nothing built yet): at least the n velocities enter
    G_count = coefficient_count(sysm, coefficients, degree)
    check_budget(G_count * _count(J.n, degree) - 1,
                 f"{G_count} coefficient functions x the monomials of degree <= {degree} "
                 f"in {J.n} velocities")
    eom = sysm.equations(p)
    acc = eom.accelerations()                       # its errors propagate
    lam = list(eom.multipliers) if eom.multiplier_rates else []     # states
    rates = list(eom.multiplier_rates) if lam else []
    on = sysm.on_constraints

    def on_manifold(syms):
        return dag.xreplace([acc[a] for a in syms], sysm.phi) if sysm.phi else \
            [acc[a] for a in syms]

    needed = on_manifold(list(J.qdd) + rates)
    if not lam and any(dag.free_symbols(e) & set(eom.multipliers) for e in needed):
        lam = list(eom.multipliers)               # the motion depends on them: keep them
        rates = list(eom.multiplier_rates)
        needed = on_manifold(list(J.qdd) + rates)
    U = [*J.qd, *lam]
    check_budget(G_count * _count(len(U), degree) - 1,
                 f"{G_count} coefficient functions x the monomials of degree <= {degree} "
                 f"in {len(U)} velocities and multipliers")
    G = coefficient_functions(sysm, coefficients, degree)
    dep = {U.index(v) for v in sysm.dependent_velocities}
    monos = [e for d in range(degree + 1) for e in _exponents(len(U), d)]
    base = {J.t, *J.q}
    pairs = [(i, e) for i, g in enumerate(G) for e in monos
             if sum(e) or g.free_symbols & base]          # no constant
    # the unknowns free of the dependent velocities first: an integral that is polynomial
    # in the independent velocities comes out written in them
    pairs.sort(key=lambda ie: any(ie[1][k] for k in dep))
    qdot = [on(v) for v in J.qd]
    problem = _Integrals(sysm, eom.J, G, needed, qdot, U, lam, pairs)
    out = []
    for vec in ansatz.solve(problem, "conserved_quantities"):
        I = sp.Add(*[c * G[i] * _mono(U, e) for c, (i, e) in zip(vec, pairs) if c])
        if problem.exact and sp.cancel(sp.together(on(I))) == 0:
            raise JetnhError(f"internal: {I} vanishes on the constraints but passed the "
                             "sampled rank test; please report")
        _check(sysm, I, acc, problem, U)
        out.append(I)
    return [out[j] for j in nontrivial(sysm, out, [J.t, *J.q, *J.qd, *lam])]


# ---------------------------------------------------------------------- triviality
def nontrivial(sysm, exprs, gens) -> list:
    """The indices of a maximal subfamily of ``exprs`` (in order) none of whose nonzero
    combinations is constant on the constrained motions, i.e. lies in the constants plus
    the ideal of the holonomic constraints g(t, q) and the velocity constraints (D g among
    them): x**2 + y**2 of a pendulum on x**2 + y**2 - 1 = 0 is the constant 1 there.
    Decided by the remainders of the numerators (over a common denominator) on a
    Groebner basis in ``gens``, whose linear relations are those of the ideal.  Without
    holonomic constraints, or when they, the constraints or ``exprs`` are not polynomial
    (rational) in ``gens``, every index is kept (the velocity constraints alone are
    already worked modulo by the searches)."""
    rems = _remainders(sysm, exprs, gens)
    if rems is None:
        return list(range(len(exprs)))
    monos = sorted({m for r in rems for m in r.monoms()})
    rows = [[r.coeff_monomial(m) for m in monos] for r in rems]
    kept, out = [rows[0]], []               # rows[0]: the constants (the denominator)
    rank = sp.Matrix(kept).rank()
    for j, row in enumerate(rows[1:]):
        r = sp.Matrix(kept + [row]).rank()
        if r > rank:
            kept.append(row)
            rank = r
            out.append(j)
    return out


def vanishes_on_motions(sysm, exprs, gens) -> bool:
    """Whether every one of ``exprs`` lies in the ideal of the holonomic and velocity
    constraints (``nontrivial``), so vanishes on every constrained motion; False when
    that cannot be decided (no holonomic constraint, or not polynomial)."""
    rems = _remainders(sysm, exprs, gens)
    return rems is not None and all(r.is_zero for r in rems[1:])


def _remainders(sysm, exprs, gens):
    """[denominator, numerators of ``exprs`` over it] reduced on a Groebner basis of the
    holonomic and velocity constraints in ``gens`` (Polys), or None (see ``nontrivial``)."""
    if not sysm.holonomic or not exprs:
        return None
    gens = list(dict.fromkeys(gens))
    rels = [*sysm.holonomic, *sysm.constraints]
    fracs = [sp.together(sp.sympify(e, strict=True)) for e in exprs]
    den = sp.lcm([sp.denom(f) for f in fracs]) if len(fracs) > 1 else sp.denom(fracs[0])
    nums = [sp.cancel(f * den) for f in fracs]
    polys = [*rels, den, *nums]
    extra = set().union(*(dag.free_symbols(e) for e in polys)) - set(gens)
    try:
        if any(not e.is_polynomial(*gens) for e in polys):
            return None
        domain = sp.QQ.frac_field(*sorted(extra, key=str)) if extra else sp.QQ
        basis = sp.groebner(rels, *gens, order="grevlex", domain=domain)
        return [sp.Poly(basis.reduce(e)[1], *gens, domain=domain) for e in [den, *nums]]
    except (sp.PolynomialError, sp.polys.polyerrors.CoercionFailed,
            sp.polys.polyerrors.DomainError):
        return None


# ---------------------------------------------------------------------- the ansatz
def _count(n, d) -> int:
    """The number of monomials of degree <= d in n variables."""
    return comb(n + d, d)


def check_budget(count, detail):
    """An ``ArgumentError`` when an ansatz of ``count`` unknowns is over the budget of
    the ansatz as written (``ansatz.RAW_BUDGET``; the solve has its own, ``BUDGET``)."""
    if count > ansatz.RAW_BUDGET:
        raise ansatz.budget_error(count, detail, ansatz.RAW_BUDGET)


def functions_of_q(sysm) -> tuple:
    """The non-polynomial functions of t and q that L, the constraints and the forces
    contain (sin(theta), cos(theta), sqrt(x**2 + y**2), ...), and the non-polynomial
    coefficients of their velocity monomials (sin(theta)**2 of L = (... + sin(theta)**2
    phi_t**2)/2, 1/(1 + x**2)), without their constant and parameter factors, so that the
    energy and the momenta of L lie in the default search space; sorted by their text."""
    J = sysm.J
    base = {J.t, *J.q}
    allowed = base | set(sysm.parameters)
    exprs = [sysm.L, *sysm.constraints, *sysm.Q]
    found = set()
    for e in dag.nodes(exprs):
        fs = e.free_symbols
        if fs & base and fs <= allowed and (
                isinstance(e, sp.Function) or (e.is_Pow and not e.exp.is_Integer)):
            found.add(e)
    for e in exprs:
        for c in _velocity_coefficients(e, J.qd):
            c = c.as_independent(*base, as_Add=False)[1]
            if (c.free_symbols & base and c.free_symbols <= allowed
                    and not c.is_polynomial(*base)):
                found.add(c)
    return tuple(sorted(found, key=str))


def _velocity_coefficients(expr, velocities) -> list:
    """The coefficients of ``expr`` as a polynomial in the velocities ([] when it is not
    one or is too large to expand)."""
    from ..algebra import zero

    if zero.large(expr):
        return []
    try:
        poly = sp.Poly(expr, *velocities)
    except sp.PolynomialError:
        return []
    if any(not c.free_symbols.isdisjoint(velocities) for c in poly.coeffs()):
        return []
    return [sp.factor_terms(c) for c in poly.coeffs()]


def coefficient_count(sysm, coefficients, degree) -> int:
    """How many coefficient functions ``coefficient_functions`` gives, without building
    them (so that budgets are checked first)."""
    if coefficients is None:
        return _count(1 + sysm.J.n, degree) * (1 + len(functions_of_q(sysm)))
    return len(check_coefficients(sysm, coefficients))


def check_coefficients(sysm, coefficients) -> list:
    """The user's coefficient functions, checked: sympy expressions (never strings, which
    would be executed) in t, q and the parameters, finite, nonzero, at most one constant."""
    J = sysm.J
    base = [J.t, *J.q]
    if isinstance(coefficients, (str, bytes)) or not isinstance(coefficients, Iterable):
        raise ArgumentError("coefficients must be a list of sympy expressions in t and q "
                            f"(e.g. [1, sympy.sin(theta)]), not {coefficients!r}")
    coefficients = list(coefficients)
    if len(coefficients) > ansatz.BUDGET:
        raise ansatz.budget_error(len(coefficients), "coefficient functions")
    allowed = set(base) | set(sysm.parameters)
    G = []
    for c in coefficients:
        if isinstance(c, (str, bytes)):
            raise ArgumentError(
                f"coefficient {c!r} is a string; jetnh never parses strings here (that "
                "would execute code): build it from the system's Symbols, e.g. "
                "sympy.sin(J.q[2])")
        if isinstance(c, bool) or not isinstance(c, (sp.Expr, numbers.Number)):
            raise ArgumentError(f"coefficient {c!r} is a {type(c).__name__}, not a sympy "
                                "expression or a number; give expressions in t and q")
        g = sp.sympify(c, strict=True)
        if not isinstance(g, sp.Expr) or dag.has(g, sp.nan, sp.oo, -sp.oo, sp.zoo) or (
                g.is_Number and not g.is_finite):
            raise ArgumentError(f"coefficient {c!r} is not a finite expression; give "
                                "finite expressions in t and q")
        if g.is_Number and g.is_Float:
            g = sp.nsimplify(g, rational=True)
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


def coefficient_functions(sysm, coefficients, degree, extra=()):
    """The coefficient functions of an ansatz: ``coefficients`` checked, or the monomials
    in t, q (and ``extra``) of degree <= ``degree``, and those times each function of q
    that the system contains (``functions_of_q``)."""
    J = sysm.J
    if coefficients is not None:
        return check_coefficients(sysm, coefficients)
    base = [J.t, *J.q, *extra]
    monos = [_mono(base, e) for d in range(degree + 1) for e in _exponents(len(base), d)]
    return monos + [m * f for f in functions_of_q(sysm) for m in monos]


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
    """D(g_i m_e) at random points of the constraint manifold, by the chain rule from the
    values of every qdot^s (the dependent ones from the constraints), the accelerations,
    the coefficient functions and their gradients."""

    def __init__(self, sysm, J, G, needed, qdot, U, lam, pairs):
        self.J, self.sysm, self.G, self.U = J, sysm, G, U
        self.pairs, self.lam = pairs, lam
        self.n = len(pairs)
        grads = [[sp.diff(g, x) for x in (J.t, *sysm.J.q)] for g in G]
        self.exprs = [*qdot, *needed, *G, *itertools.chain(*grads)]
        self.sizes = (len(qdot), len(needed), len(G))
        self.parameters = sysm.parameters
        self.atoms = ansatz.parameter_atoms([sysm.L, *sysm.constraints, *sysm.Q, *G],
                                             sysm.parameters)
        self.sampler = Sampler([J.t, *sysm.J.q, *sysm.independent_velocities, *lam],
                               sysm.parameters, self.exprs)
        self.exact = self.sampler.exact

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

    def _num(self, v):
        return _fraction(v) if self.exact else ansatz.to_mpf(v)

    def _row(self, vals, p, pairs):
        U = self.U
        with mpmath.workdps(DPS + 10):
            if self.exact:                  # Fractions: much faster than sympy Rationals
                vals = [_fraction(v) for v in vals]
            qdot, accel, gv, grads = self._split(vals)
            u = [*qdot, *(self._num(p[m]) for m in self.lam)]
            Dg = [gr[0] + sum(d * v for d, v in zip(gr[1:], qdot)) for gr in grads]
            mv, dm = {}, {}
            for e in {e for _, e in pairs}:
                mv[e] = power_product(u, e)
                dm[e] = sum((e[k] * power_product(u, e[:k] + (e[k] - 1,) + e[k + 1:])
                             * accel[k] for k in range(len(U)) if e[k]), 0)
            return [Dg[i] * mv[e] + gv[i] * dm[e] for i, e in pairs]

    def raw_points(self, rng, count, fixed=None):
        return [self.sampler.point(rng, fixed) for _ in range(count)]

    def float_values(self, points):
        a = self.sizes[0]
        at = {s: np.array([float(p[s]) for p in points]) for s in points[0]}
        vals = dag.evaluate_numpy([*self.exprs[:a], *self.G], at)
        k = len(points)
        vals = [np.broadcast_to(np.asarray(v, dtype=float), (k,)) for v in vals]
        u = [*vals[:a], *(at[m] for m in self.lam)]
        gv = vals[a:]
        return np.column_stack([gv[i] * power_product(u, e) for i, e in self.pairs]) \
            if self.pairs else np.zeros((k, 0))

    def values(self, point):
        a, _, c = self.sizes
        vals = self.sampler.values([*self.exprs[:a], *self.G], point)
        if self.exact:
            vals = [_fraction(v) for v in vals]
        with mpmath.workdps(DPS + 10):
            u = [*vals[:a], *(self._num(point[m]) for m in self.lam)]
            gv = vals[a:]
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
