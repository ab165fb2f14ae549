"""When do two principles share solutions?  Zhao et al. (2008), (11), (32), (39).

- ``branch_32``: the multiplier values lambda_alpha = -p_alpha (32) on which the
  vakonomic (20) and Suslov (31) equations coincide.
- ``frobenius_T``: for affine constraints, T^alpha_mu = K^alpha_{rho mu} qdot^rho where
  K^alpha_{rho sigma} = X_rho B^alpha_sigma - X_sigma B^alpha_rho are the Frobenius
  obstructions of the distribution (X_rho = d_rho + B^beta_rho d_beta, qdot^0 = 1); so
  T vanishes for all velocities exactly when the constraints are integrable, which is
  the content of the affine condition (39).
- ``compare``: decides for two principles whether their accelerations agree identically,
  on the branch (32), or at given states.

Agreement of expressions is decided by evaluation at random states on the constraint
manifold (with random multipliers and parameters), a Schwartz-Zippel style test: a
nonzero analytic difference vanishes at random points with probability zero.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from . import dag, linalg
from .constraints import System
from .frobenius import bracket_components
from .testing import vanishes

_POINTS = 4


def branch_32(system: System, multipliers, explicit: bool = True) -> dict:
    """{lambda_alpha: -p_alpha} on the constraint manifold: the branch of (32), for the
    multipliers of the explicit constraints qdot^alpha - phi^alpha.  For those of the
    constraints as given (``explicit=False``; f = A_dep (qdot^alpha - phi^alpha) when
    affine) the same branch is lambda = -A_dep^-T p."""
    p = sp.Matrix([system.on_constraints(e) for e in system.p_dependent])
    if not explicit:
        p = linalg.solve(system.on_constraints(system.jacobian_dependent.T), p)
    return {lam: -e for lam, e in zip(multipliers, p)}


def obstructions(system: System) -> dict:
    """K^alpha_{rho sigma} = X_rho B^alpha_sigma - X_sigma B^alpha_rho, keyed
    (x_rho, x_sigma, q_alpha) with rho < sigma over (t, q^mu); zeros included."""
    return bracket_components(system.J, system.B, system.dependent, system.independent)


def frobenius_T(system: System) -> sp.Matrix:
    """T^alpha_mu rebuilt from the Frobenius obstructions: sum_rho K^alpha_{rho mu} qdot^rho."""
    J = system.J
    K = obstructions(system)
    coords = (J.t,) + system.independent
    vel = (sp.S.One,) + system.independent_velocities

    def k(qa, r, s):
        if r == s:
            return sp.S.Zero
        return K[(coords[r], coords[s], qa)] if r < s else -K[(coords[s], coords[r], qa)]
    return sp.Matrix(system.k, len(system.independent),
                     lambda a, m: sp.Add(*[k(system.dependent[a], r, m + 1) * vel[r]
                                           for r in range(len(coords))]))


@dataclass(frozen=True)
class Comparison:
    """The verdict of ``compare``: which coordinates' accelerations agree, and where."""

    principles: tuple
    identical: bool
    on_branch_32: bool | None
    defects: dict = field(default_factory=dict)   # q'' difference (symbolic, unsimplified)

    def __str__(self):
        a, b = self.principles
        if self.identical:
            return f"{a} and {b} have the same accelerations at every state"
        if self.on_branch_32:
            return f"{a} and {b} agree on the branch lambda_alpha = -p_alpha (32), not in general"
        return f"{a} and {b} do not share solutions in general"

    def _repr_html_(self):
        from .display import comparison_html

        return comparison_html(self)

    def _repr_latex_(self):
        from .display import comparison_latex

        return comparison_latex(self)


def agrees(system: System, expr, derived=None) -> bool:
    """Whether ``expr`` vanishes at random states on the constraint manifold (with the
    ``derived`` symbols set from the others, as in ``jetnh.testing.vanishes``)."""
    return vanishes(expr, system, points=_POINTS, derived=derived)


def compare(system: System, first: str, second: str, convention: str = "paper") -> Comparison:
    """Do ``first`` and ``second`` give the same coordinate accelerations?"""
    e1 = system.equations(first, convention=convention)
    e2 = system.equations(second, convention=convention)
    a1, a2 = e1.accelerations(), e2.accelerations()
    qdd = system.J.qdd
    defects = {q: a1[q] - a2[q] for q in qdd}
    same = all(agrees(system, d) for d in defects.values())
    on_branch = None
    owner = e1 if e1.multipliers else e2
    if not same and owner.multipliers:
        sub = branch_32(system, owner.multipliers, owner.explicit)
        on_branch = all(agrees(system, d, derived=sub) for d in defects.values())
    return Comparison((first, second), same, on_branch, defects)


def defect_along(system: System, first: str, second: str, samples, convention: str = "paper"):
    """Largest |q''_first - q''_second| over given states: do the principles agree along a
    trajectory?  ``samples`` maps names (or Symbols) to arrays of equal length, e.g.
    ``traj.as_dict()`` of a jetnh Trajectory; multipliers missing from it count as zero."""
    import numpy as np

    e1 = system.equations(first, convention=convention)
    e2 = system.equations(second, convention=convention)
    a1, a2 = e1.accelerations(), e2.accelerations()
    data = {(k.name if isinstance(k, sp.Symbol) else str(k)): np.asarray(v, dtype=float)
            for k, v in dict(samples).items()}
    worst = 0.0
    for q in system.J.qdd:
        d = dag.xreplace(a1[q] - a2[q], system.phi)
        syms = sorted(dag.free_symbols(d), key=lambda s: s.name)
        missing = [s.name for s in syms if s.name not in data
                   and s not in (e1.multipliers + e2.multipliers)]
        if missing:
            from .errors import JetnhError
            raise JetnhError(f"the samples lack values for {missing}; pass every coordinate, "
                             "velocity and parameter (e.g. traj.as_dict() plus parameters)")
        n = len(next(iter(data.values())))
        args = [data.get(s.name, np.zeros(n)) for s in syms]
        val = sp.lambdify(syms, d, "numpy", cse=True)(*args)
        worst = max(worst, float(np.max(np.abs(np.broadcast_to(val, (n,))))))
    return worst
