"""Noether and Lie point symmetries of a principle's equations, each proved.

A point generator X = xi0(t, q) d/dt + xi^s(t, q) d/dq^s with characteristic
xibar^s = xi^s - qdot^s xi0 is a **Noether symmetry** of a principle, with gauge G(t, q),
when on the constraint manifold::

    pr X(F) + F D(xi0) + Q_s xibar^s + D(G) = 0                                  (N)

and then I = F xi0 + (dF/dqdot) xibar + G is conserved on that principle's motions
(D I = pr X(F) + F D xi0 + (Q + R) xibar with R the constraint terms of the equations):

- chetaev: F = L, and xibar restricted to the Chetaev subspace df^a/dqdot^s xibar^s = 0,
  so the reaction does no work on it (Bahar & Kwatny 1987, "Extension of Noether's
  theorem to constrained non-conservative dynamical systems", Int. J. Non-Linear Mech.
  22; Mei Fengxiang's Noether theory of nonholonomic nonconservative systems).  For
  Chaplygin systems with an abelian symmetry this is Bloch's momentum equation with
  vanishing right-hand side (Bloch, *Nonholonomic Mechanics and Control*, 2003, sec. 5.4).
- vakonomic and holder: F = L + lambda_a f^a on the space extended by the multipliers,
  no restriction (Fu Jingli, Chen Liqun et al., Noether symmetries of vakonomic systems:
  the symmetries of the composite Lagrangian); the paper's Hoelder equations (22) are the
  vakonomic ones, so their symmetries agree.
- suslov: F = L~ (the constraints substituted) with momenta over the independent
  velocities, and xibar^alpha = Phi^alpha_mu xibar^mu: along (31),
  D(dL~/dqdot^mu) = dL~/dq^mu + Phi^alpha_mu dL~/dq^alpha + Q~_mu.

Forces Q_s enter through their work on xibar.  The principles differ: for the
nonholonomic particle (zdot = y xdot) the translation d/dz gives the vakonomic integral
m zdot + lambda but is no Chetaev symmetry (it leaves the Chetaev subspace), while d/dy
gives the Chetaev integral m ydot but no vakonomic one (F depends on y).

A **Lie point symmetry** of the motion qdot^alpha = phi^alpha, qddot^mu = A^mu (and
lambdadot = R for the multiplier principles) is a field whose prolongation (Olver 1993,
Thm 2.36) annihilates these equations on their solutions.  ``is_noether`` decides which
Lie symmetries are Noether ones for a principle (a gauge exists).

All three solve a linear ansatz with ``jetnh.algebra.ansatz`` (constants may depend on the
parameters), and every result is proved: the identity holds exactly (cancel) where the
system is rational, at 20 random points at 50 digits always, and D I = 0 on the
principle's equations.
"""

from __future__ import annotations

import itertools
import random
from math import comb
from dataclasses import dataclass
from types import MappingProxyType

import mpmath
import numpy as np
import sympy as sp

from ..algebra import ansatz, dag
from ..algebra.ansatz import exponents, monomial
from ..errors import ArgumentError, JetnhError
from ..geometry.fields import prolong
from .integrals import (Sampler, check_arguments, check_budget, coefficient_count,
                        coefficient_functions, nontrivial, prove_conserved,
                        vanishes_on_motions)

_WIDTH = 72             # characters of each expression in a repr


def _short(e) -> str:
    s = str(e)
    return s if len(s) <= _WIDTH else s[:_WIDTH - 5] + " ...)"


# ---------------------------------------------------------------------- results
@dataclass(frozen=True, repr=False)
class NoetherSymmetry:
    """A Noether point symmetry of ``principle``: generator (xi0, xi), gauge and the
    conserved quantity I = F xi0 + (dF/dqdot) xibar + G it gives (proved)."""

    principle: str
    xi0: sp.Expr
    xi_items: tuple
    gauge: sp.Expr
    quantity: sp.Expr

    @property
    def xi(self):
        """coordinate -> xi^s, the nonzero ones (read-only)."""
        return MappingProxyType(dict(self.xi_items))

    def __repr__(self):
        comps = ", ".join(f"{q}: {_short(e)}" for q, e in self.xi_items if e != 0)
        return (f"NoetherSymmetry({self.principle}: xi0={_short(self.xi0)}, xi={{{comps}}}, "
                f"gauge={_short(self.gauge)}, quantity={_short(self.quantity)})")[:600]


@dataclass(frozen=True, repr=False)
class LieSymmetry:
    """A Lie point symmetry xi0 d/dt + xi^b d/db of ``principle``'s motion (b: the
    coordinates and, for vakonomic and Hoelder, the multipliers)."""

    principle: str
    xi0: sp.Expr
    xi_items: tuple

    @property
    def xi(self):
        return MappingProxyType(dict(self.xi_items))

    def __repr__(self):
        comps = ", ".join(f"{q}: {_short(e)}" for q, e in self.xi_items if e != 0)
        return f"LieSymmetry({self.principle}: xi0={_short(self.xi0)}, xi={{{comps}}})"[:600]


# ---------------------------------------------------------------------- the setting
class _Setting:
    """One principle's Noether data: F, its velocities, restriction rows, the manifold."""

    def __init__(self, sysm, p):
        self.sysm, self.principle = sysm, p.name
        J = sysm.J
        self.J = J
        self.eom = sysm.equations(p)
        self.acc = self.eom.accelerations()             # its errors propagate
        self.lams = ()
        if not p.has_multipliers:                       # Chetaev: L, eta restricted
            self.F, self.vel, self.restrict = sysm.L, tuple(J.qd), True
        elif p.multipliers_act:                         # vakonomic, Hoelder: L + lambda f
            self.lams = tuple(self.eom.multipliers)
            self.F = sysm.L + sp.Add(*[m * f for m, f in zip(self.lams, self.eom.constraints)])
            self.vel, self.restrict = tuple(J.qd), False
        else:                                           # Suslov: L~, eta restricted
            self.F, self.restrict = sysm.L_tilde, True
            self.vel = tuple(sysm.independent_velocities)
        self.qdot = [sysm.phi.get(v, v) for v in J.qd]
        self.U = tuple(sysm.independent_velocities) + self.lams
        on = sysm.on_constraints
        self.dF = {x: on(sp.diff(self.F, x)) for x in (J.t, *J.q)}
        self.P = {v: on(sp.diff(self.F, v)) for v in self.vel}
        self.Fm = on(self.F)
        self.A = sysm.jacobian.applyfunc(on) if sysm.k else sp.zeros(0, J.n)

    def D(self, g):
        """Total derivative of a function of (t, q) on the constraint manifold."""
        J = self.J
        return sp.diff(g, J.t) + sp.Add(*[sp.diff(g, q) * v for q, v in zip(J.q, self.qdot)])

    def terms(self, xi0, xi, G):
        """(N) and the restriction rows for the generator (xi0, xi) and gauge G."""
        J, sysm = self.J, self.sysm
        D0 = self.D(xi0)
        bar = [xi[s] - self.qdot[s] * xi0 for s in range(J.n)]
        E = xi0 * self.dF[J.t] + sp.Add(*[xi[s] * self.dF[q] for s, q in enumerate(J.q)])
        for s, v in enumerate(J.qd):
            if v in self.P:
                E += (self.D(xi[s]) - self.qdot[s] * D0) * self.P[v]
        E += self.Fm * D0 + sp.Add(*[sysm.on_constraints(Q) * b
                                     for Q, b in zip(sysm.Q, bar) if Q != 0])
        E += self.D(G)
        rows = [sp.Add(*[self.A[a, s] * bar[s] for s in range(J.n)])
                for a in range(sysm.k)] if self.restrict else []
        return [E, *rows]

    def quantity(self, xi0, xi, G):
        J = self.J
        I = self.Fm * xi0 + G
        for s, v in enumerate(J.qd):
            if v in self.P:
                I += self.P[v] * (xi[s] - self.qdot[s] * xi0)
        return I


def _functions(sysm, coefficients, degree, extra=()):
    """The ansatz functions of (t, q[, extra]): ``coefficients``, or the monomials of
    degree <= ``degree`` and those times each function of q the system contains."""
    return coefficient_functions(sysm, coefficients, degree, extra)


class _Linear(ansatz.Problem):
    """Rows: the values of per-unknown condition expressions at random points; the ansatz
    function of unknown j is g_j times a random weight of its component (so that the
    rank of solutions is that of the generators)."""

    def __init__(self, sysm, conds, funcs, comp, ncomp, variables):
        self.n = len(funcs)
        self.conds, self.funcs, self.comp = conds, funcs, comp
        self.W = sp.symbols(f"_w0:{ncomp}", cls=sp.Dummy)
        self.parameters = sysm.parameters
        self.atoms = ansatz.parameter_atoms([sysm.L, *sysm.constraints, *sysm.Q, *funcs],
                                             sysm.parameters)
        flat = list(itertools.chain(*conds))
        self.sampler = Sampler([*variables, *self.W], sysm.parameters, flat + funcs)
        self.flat = flat
        self.ncond = len(conds[0]) if conds else 0

    def rows(self, rng, count, fixed=None, columns=None):
        out = []
        m = self.ncond
        cols = range(self.n) if columns is None else columns
        # a point per row asked for: the m rows of one point may be dependent
        for vals, p in self.sampler.draw(self.flat, rng, count, fixed):
            for c in range(m):
                out.append(([vals[j * m + c] for j in cols], p))
        return out

    def raw_points(self, rng, count, fixed=None):
        return [self.sampler.point(rng, fixed) for _ in range(count)]

    def float_values(self, points):
        at = {s: np.array([float(p[s]) for p in points]) for s in points[0]}
        k = len(points)
        gv = [np.broadcast_to(np.asarray(v, dtype=float), (k,))
              for v in dag.evaluate_numpy(list(self.funcs), at)]
        return np.column_stack([g * at[self.W[c]] for g, c in zip(gv, self.comp)])

    def values(self, point):
        gv = self.sampler.values(self.funcs, point)
        if self.sampler.exact:
            return [g * point[self.W[k]] for g, k in zip(gv, self.comp)]
        with mpmath.workdps(ansatz.DPS + 10):
            return [g * ansatz.to_mpf(point[self.W[k]]) for g, k in zip(gv, self.comp)]


# ---------------------------------------------------------------------- Noether
def noether_symmetries(sysm, principle, degree=1, coefficients=None) -> list:
    """The Noether point symmetries of ``principle`` (see the module docstring): a basis
    over the rational functions of the parameters, each a ``NoetherSymmetry`` whose
    identity (N) and conserved quantity are proved.  Symmetries whose quantity is a
    constant are left out.  For Suslov, F = L~ on the reduced motion: its quantities are
    free of the multipliers, so integrals in the Suslov multipliers (lambda_alpha +
    p_alpha of a Chaplygin system) are not Noether quantities here;
    ``conserved_quantities`` finds them.

    Parameters
    ----------
    sysm : System
        The constrained system.
    principle : str
        "chetaev", "vakonomic", ... (the principles differ: for
        ``models.get("nonholonomic_particle")``, d/dz is a vakonomic symmetry with
        I = m zdot + lambda_z and is not a Chetaev one; d/dy is a Chetaev symmetry,
        I = m ydot, and not a vakonomic one).
    degree : int, default 1
        xi0 and xi^s are spanned by the monomials in t and q of degree <= ``degree``, the
        gauge by those of degree <= degree + 1.
    coefficients : list of sympy expressions, optional
        Functions of t and q spanning xi0 and xi^s instead of the monomials.

    Returns
    -------
    list of jetnh.mechanics.symmetries.NoetherSymmetry
    """
    p = check_arguments(sysm, principle, degree, "noether_symmetries")
    J = sysm.J
    n = J.n
    ng, nh = coefficient_count(sysm, coefficients, degree), comb(n + 2 + degree, degree + 1) - 1
    check_budget((n + 1) * ng + nh, f"{n + 1} components x {ng} functions + {nh} gauge "
                 "functions")                   # sizes first: nothing built yet
    S = _Setting(sysm, p)
    g = _functions(sysm, coefficients, degree)
    base = [J.t, *J.q]
    h = [monomial(base, e) for d in range(1, degree + 2) for e in exponents(len(base), d)]
    zero = [sp.S.Zero] * n
    conds, funcs, comp = [], [], []
    for k in range(n + 1):
        for gi in g:
            xi = list(zero)
            if k:
                xi[k - 1] = gi
            conds.append(S.terms(gi if k == 0 else sp.S.Zero, xi, sp.S.Zero))
            funcs.append(gi)
            comp.append(k)
    for hl in h:
        conds.append(S.terms(sp.S.Zero, zero, hl))
        funcs.append(hl)
        comp.append(n + 1)
    problem = _Linear(sysm, conds, funcs, comp, n + 2, [J.t, *J.q, *S.U])
    out = []
    for vec in ansatz.solve(problem, "noether_symmetries"):
        parts = [sp.Add(*[c * f for c, f, k in zip(vec, funcs, comp) if k == j and c])
                 for j in range(n + 2)]
        sym = _prove_noether(S, problem.sampler, parts[0], parts[1:n + 1], parts[n + 1])
        if sym is not None:
            out.append(sym)
    return out


def _prove_noether(S, sampler, xi0, xi, G):
    """The NoetherSymmetry, after proving (N) and D I = 0; None if it is trivial: I a
    constant, or (with holonomic constraints) the generator vanishing on them or I
    constant on the motions (``integrals.nontrivial``)."""
    sysm = S.sysm
    for e in S.terms(xi0, xi, G):
        _vanishes(e, sampler, "the Noether identity")
    I = S.quantity(xi0, xi, G)
    if not (sp.expand(I).free_symbols - set(sysm.parameters)):
        return None
    gens = [sysm.J.t, *sysm.J.q, *sysm.J.qd, *S.lams]
    if sysm.holonomic and (vanishes_on_motions(sysm, [xi0, *xi], gens)
                           or not nontrivial(sysm, [I], gens)):
        return None
    prove_conserved(sysm, S.eom.J, I, S.acc, sampler, S.U)
    if dag.size(I, 2000) < 2000:
        I = sp.expand(I)                        # small: the readable form
    return NoetherSymmetry(S.principle, xi0, tuple((q, e) for q, e in zip(sysm.J.q, xi) if e != 0),
                           G, I)


def _vanishes(e, sampler, what):
    """e = 0 exactly when rational (cancel), and at 20 random points (50 digits)."""
    if sampler.exact:
        if sp.cancel(sp.together(e)) != 0:
            raise JetnhError(f"internal: {what} fails: {_short(e)} != 0; please report")
        return
    rng = random.Random(11)
    done = 0
    while done < 20:
        p = sampler.point(rng)
        try:
            v = dag.evaluate(e, p, dps=ansatz.DPS)
        except (ZeroDivisionError, ValueError):
            continue
        if not mpmath.isfinite(v):
            continue
        if abs(v) > mpmath.mpf(10) ** -25:
            raise JetnhError(f"internal: {what} fails at {p} ({mpmath.nstr(v, 8)}); please "
                             "report")
        done += 1


def is_noether(sysm, principle, symmetry, degree=None):
    """The ``NoetherSymmetry`` of ``principle`` with the generator of ``symmetry`` (a
    LieSymmetry or NoetherSymmetry, of any principle) if a gauge G(t, q) of degree <=
    ``degree`` (default: one more than the generator's) makes (N) hold; else None.
    Components on the multipliers are ignored (F depends on them through f = 0)."""
    if not isinstance(symmetry, (LieSymmetry, NoetherSymmetry)):
        raise ArgumentError(f"is_noether needs a LieSymmetry or NoetherSymmetry, not "
                            f"{type(symmetry).__name__}")
    S = _Setting(sysm, check_arguments(sysm, principle, 1, "is_noether"))
    J = sysm.J
    xi = [symmetry.xi.get(q, sp.S.Zero) for q in J.q]
    base = [J.t, *J.q]
    if degree is None:
        degree = 1 + max((sp.Poly(e, *base).total_degree() for e in [symmetry.xi0, *xi]
                          if e != 0 and e.is_polynomial(*base)), default=0)
    h = [monomial(base, e) for d in range(1, degree + 1) for e in exponents(len(base), d)]
    conds = [S.terms(symmetry.xi0, xi, sp.S.Zero)] + [S.terms(0, [0] * J.n, hl) for hl in h]
    funcs = [sp.S.One] + h
    problem = _Linear(sysm, conds, funcs, [0] + [1] * len(h), 2, [J.t, *J.q, *S.U])
    for vec in ansatz.solve(problem, "is_noether"):
        if vec[0] != 0:
            G = sp.Add(*[c * f for c, f in zip(vec[1:], h)]) / vec[0]
            return _prove_noether(S, problem.sampler, symmetry.xi0, xi, G)
    return None


# ---------------------------------------------------------------------- Lie
def lie_symmetries(sysm, principle, degree=1, coefficients=None) -> list:
    """The Lie point symmetries of ``principle``'s motion whose components are spanned by
    ``coefficients`` (default: monomials of degree <= ``degree`` in t and q; for the
    vakonomic and Hoelder principles the multipliers' components also in lambda, so the
    field is projectable on (t, q); for Suslov, whose coordinate motion is free of the
    multipliers, the fields of that motion alone): a basis over the rational
    functions of the parameters, each a ``LieSymmetry`` whose determining equations are
    proved.  The determining equations are pr X(qdot^alpha - phi^alpha) = 0,
    pr X(qddot^mu - A^mu) = 0 (and pr X(lambdadot - R) = 0) on the solutions; requiring
    them at random points of (t, q, qdot^mu, lambda) is the same as splitting them by
    powers of the velocities."""
    p = check_arguments(sysm, principle, degree, "lie_symmetries")
    ng = coefficient_count(sysm, coefficients, degree)
    check_budget((sysm.J.n + 1) * ng, f"{sysm.J.n + 1} components x {ng} functions")
    eom = sysm.equations(p)
    acc = eom.accelerations()
    J0 = sysm.J
    lams = tuple(eom.multipliers) if p.multipliers_act else ()
    J = J0.with_fields(tuple(m.name for m in lams)) if lams else J0
    lams = tuple(J.fields)
    bases = (*J.q, *lams)
    g = _functions(sysm, coefficients, degree)
    gl = _functions(sysm, coefficients, degree, lams) if lams else []
    check_budget((J0.n + 1) * len(g) + len(lams) * len(gl),
                 f"{len(bases) + 1} components x {len(g)} functions")
    on = sysm.on_constraints
    rates = [J.jet(m, 1) for m in lams]
    # targets: (jet symbol, its value on the solutions as a function of the state)
    targets = [(v, sysm.phi[v]) for v in sysm.dependent_velocities]
    targets += [(J.jet(q, 2), on(acc[J0.jet(q, 2)])) for q in sysm.independent]
    targets += [(r, on(acc[sp.Symbol(r.name)])) for r in rates]
    state = [J.t, *J.q, *sysm.independent_velocities, *lams]
    shell = {v: sysm.phi[v] for v in sysm.dependent_velocities}
    shell.update({J.jet(q, 2): on(acc[J0.jet(q, 2)]) for q in J.q})
    shell.update({r: on(acc[sp.Symbol(r.name)]) for r in rates})
    conds, funcs, comp = [], [], []
    for k in range(len(bases) + 1):
        for gi in (g if k <= J0.n else gl):
            V = prolong(J, {bases[k - 1]: gi} if k else {}, xi=gi if k == 0 else 0, order=2)
            row = []
            for jet, value in targets:
                e = V[jet] - sp.Add(*[V[z] * sp.diff(value, z) for z in state
                                      if V[z] != 0])
                row.append(dag.xreplace(e, shell))
            conds.append(row)
            funcs.append(gi)
            comp.append(k)
    problem = _Linear(sysm, conds, funcs, comp, len(bases) + 1,
                      [J.t, *J.q, *sysm.independent_velocities, *lams])
    out = []
    for vec in ansatz.solve(problem, "lie_symmetries"):
        parts = [sp.Add(*[c * f for c, f, k in zip(vec, funcs, comp) if k == j and c])
                 for j in range(len(bases) + 1)]
        total = [sp.Add(*[c * e for c, e in zip(vec, col)]) for col in zip(*conds)]
        for e in total:
            _vanishes(e, problem.sampler, "a determining equation")
        out.append(LieSymmetry(p.name, parts[0],
                               tuple((b, e) for b, e in zip(bases, parts[1:]) if e != 0)))
    return out
