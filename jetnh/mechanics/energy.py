"""Why the energy of a principle's motions is not conserved, where it is not by design.

The energy a trajectory reports is E = qdot^s dF/dqdot^s - F, with F = L + lambda_a f^a
where the multipliers are states (vakonomic, Hoelder) and F = L otherwise (Chetaev,
Suslov).  Along the motions of the Chetaev principle, d/dt dL/dqdot - dL/dq = Q +
lambda_a df^a/dqdot, so::

    dE/dt = -dL/dt (explicit) + Q_s qdot^s + lambda_a qdot^s df^a/dqdot^s,

and along the vakonomic and Hoelder motions (the Euler-Lagrange equations of F in q and
lambda, with Q) dE/dt = -dF/dt (explicit) + Q_s qdot^s.  ``changes`` names the terms
that do not vanish identically at the given parameter values (decided by
``zero.vanishes`` on the shared graphs, never by simplification):

- an explicit t in L, or in a constraint for the principles whose F holds it;
- generalized forces (``System.Q``);
- Chetaev: constraint reactions that work, qdot^s df^a/dqdot^s not zero on the
  constraints (a constraint affine in the velocities, z_t - y x_t - c, or a rheonomic
  one); a constraint homogeneous in the velocities does no work.

Suslov's energy balance is not derived here: only the first two reasons are named
there.  No reason: the energy is conserved by the equations, and a drift is the
integration's error.
"""

from __future__ import annotations

import sympy as sp

from ..algebra import dag, zero

#: principles whose energy holds the multipliers (F = L + lambda f)
_EXTENDED = ("vakonomic", "holder")


def changes(system, principle: str, params: dict) -> tuple[str, ...]:
    """The reasons (module docstring) the energy of ``principle``'s motions of
    ``system`` is not conserved at the parameter values ``params`` (Symbol or name ->
    number; those not given are kept symbolic); () where it is."""
    values = {s: sp.Float(params[s.name] if s.name in params else params[s])
              for s in system.parameters if s.name in params or s in params}
    t = system.J.t

    def nonzero(exprs, on_constraints=False):
        if on_constraints:              # the dependent velocities from the constraints
            exprs = [dag.xreplace(e, system.phi) for e in exprs]
        exprs = [dag.xreplace(e, values) for e in exprs]
        exprs = [e for e in exprs if e != 0]
        return bool(exprs) and not zero.vanishes(exprs)

    def explicit_t(exprs):
        return nonzero([dag.diff(e, t) for e in exprs if t in dag.free_symbols(e)])

    out = []
    if explicit_t([system.L]):
        out.append("L depends on t")
    if principle in _EXTENDED and explicit_t(system.constraints):
        out.append("the constraints depend on t")
    if nonzero(system.Q):
        out.append("the generalized forces work (traj.power)")
    if principle == "chetaev" and system.constraints:
        J = system.J
        work = [sum((v * dag.diff(f, v) for v in J.qd), sp.S.Zero)
                for f in system.constraints]
        if nonzero(work, on_constraints=True):
            out.append("the constraint reactions work (a constraint not homogeneous in "
                       "the velocities)")
    return tuple(out)
