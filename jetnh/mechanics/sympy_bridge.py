"""The bridge to sympy.physics.mechanics: ``LagrangesMethod`` <-> ``System`` (Kane
models, a ``KanesMethod`` or a mechanics ``System``, come in through ``kane_bridge``).

``from_mechanics(lm)`` reads a ``LagrangesMethod``: its coordinates ``lm.q``
(dynamicsymbols) become a ``JetSpace`` of the same names, its Lagrangian and its
constraints become jet expressions (``JetSpace.from_dynamic``).

- ``nonhol_coneqs`` are the constraints as written.
- ``hol_coneqs`` g(t, q) = 0 stay holonomic (``System.holonomic``): the equations use
  dg/dt = 0, as LagrangesMethod itself does (its ``coneqs``), and a ``Scene`` checks (or
  completes) the initial configuration against g = 0 and keeps its runs on it.
- ``forcelist``: loads on points and frames become the generalized forces
  Q_s = sum F . dv/dqdot^s (``generalized_forces``), the system's ``forces``.
- Any other function of time in the Lagrangian or the constraints (a specified input
  u(t)) is refused: substitute it first.

``to_mechanics(system)`` is the way back (``JetSpace.to_dynamic``), for systems without
forces (a generalized force has no unique load to stand for it).
"""

from __future__ import annotations

import sympy as sp

from . import kane_bridge
from .system import System
from ..errors import JetnhError, JetSpaceError
from ..geometry.jet import JetSpace


def _coordinates(lm) -> JetSpace:
    from sympy.core.function import AppliedUndef
    from sympy.physics.vector import dynamicsymbols

    t = dynamicsymbols._t
    names = []
    for q in lm.q:
        if not (isinstance(q, AppliedUndef) and q.args == (t,)):
            raise JetnhError(f"the coordinate {q} of the LagrangesMethod is not a "
                             "dynamicsymbol q(t); build it with dynamicsymbols('q')")
        names.append(q.func.__name__)
    return JetSpace(names, t=t.name)


def _convert(J, expr, what):
    try:
        return J.from_dynamic(expr)
    except JetSpaceError as exc:
        raise JetSpaceError(
            f"{what} of the LagrangesMethod: {exc}. from_mechanics reads functions of time "
            "only among lm.q; substitute specified inputs (e.g. u(t)) by parameters or "
            "expressions first") from None


def constraints(lm, J: JetSpace) -> list:
    """The nonholonomic constraints as written, then the holonomic ones g as written
    (a System keeps a constraint without velocities holonomic)."""
    n_hol = len(lm._hol_coneqs)
    nonhol = list(lm.coneqs[n_hol:])
    hol = list(lm._hol_coneqs)
    return ([_convert(J, f, f"nonholonomic constraint {a + 1}") for a, f in enumerate(nonhol)]
            + [_convert(J, f, f"holonomic constraint {a + 1}") for a, f in enumerate(hol)])


def generalized_forces(lm, J: JetSpace) -> tuple:
    """Q_s = sum over the forcelist of F . dv/dqdot^s (v the velocity of the point, or
    the angular velocity of the frame, in ``lm.inertial``), as jet expressions in the
    order of ``J.q``; zeros without forces."""
    from sympy.physics.vector import Point, ReferenceFrame, dynamicsymbols

    loads = list(lm.forcelist or ())
    if not loads:
        return (sp.S.Zero,) * J.n
    N = lm.inertial
    if N is None:
        raise JetnhError("the LagrangesMethod has forces but no inertial frame; pass "
                         "frame=N to LagrangesMethod")
    pairs = []
    for load in loads:
        where, vec = load[0], load[1]
        if isinstance(where, Point):
            pairs.append((where.vel(N), vec))
        elif isinstance(where, ReferenceFrame):
            pairs.append((where.ang_vel_in(N), vec))
        else:
            raise JetnhError(f"a load acts on {where!r}; loads act on a Point or a "
                             "ReferenceFrame")
    qds = lm.q.diff(dynamicsymbols._t)
    return tuple(_convert(J, sp.Add(*[v.diff(qd, N).dot(f) for v, f in pairs]),
                          f"the generalized force on {J.q[s]}")
                 for s, qd in enumerate(qds))


def from_mechanics(lm, dependent=None, *, branch=None, defaults=None, name="") -> System:
    """A jetnh ``System`` from a sympy.physics.mechanics model.

    Parameters
    ----------
    lm : sympy.physics.mechanics.LagrangesMethod or sympy.physics.mechanics.KanesMethod or sympy.physics.mechanics.System
        A ``LagrangesMethod``: its Lagrangian, coordinates and nonholonomic constraints
        (``nonhol_coneqs``) become the system's (see the module docstring).  A
        ``KanesMethod`` or mechanics ``System`` (``kane_bridge``): the result's
        ``speeds`` attribute is then the map between the model's generalized speeds and
        the velocities (``kane_bridge.Speeds``); a mechanics System whose equations were
        formed with LagrangesMethod is read as that LagrangesMethod.
    dependent, branch, defaults, name
        As for ``System``.

    Returns
    -------
    System
    """
    from sympy.physics.mechanics import KanesMethod, LagrangesMethod
    from sympy.physics.mechanics import System as MechanicsSystem

    if isinstance(lm, MechanicsSystem) and isinstance(lm.eom_method, LagrangesMethod):
        lm = lm.eom_method
    if isinstance(lm, (KanesMethod, MechanicsSystem)):
        J, L, cons, forces, speeds = kane_bridge.read(lm)
        return System(J, L, cons, dependent=dependent, branch=branch, defaults=defaults,
                      name=name, forces=forces, speeds=speeds)
    if not isinstance(lm, LagrangesMethod):
        raise JetnhError(
            f"from_mechanics takes a sympy.physics.mechanics LagrangesMethod, KanesMethod or "
            f"System, got {type(lm).__name__}; for a Lagrangian and constraints of your own "
            "build a jetnh System(J, L, constraints) directly")
    J = _coordinates(lm)
    L = _convert(J, lm._L[0], "the Lagrangian")
    forces = {q: Q for q, Q in zip(J.q, generalized_forces(lm, J)) if Q != 0}
    return System(J, L, constraints(lm, J), dependent=dependent, branch=branch,
                  defaults=defaults, name=name, forces=forces)


def to_mechanics(system: System):
    """A ``LagrangesMethod`` with the system's Lagrangian, coordinates and constraints
    (holonomic ones as ``hol_coneqs``, the others as nonholonomic, in dynamicsymbols)."""
    from sympy.physics.mechanics import LagrangesMethod

    if system.forced:
        raise JetnhError("to_mechanics: the system has generalized forces, which have no "
                         "unique loads on points and frames to stand for them; build the "
                         "LagrangesMethod's forcelist by hand")
    J = system.J
    hol = set(system.holonomic_rows)
    nonhol = [f for i, f in enumerate(system.constraints) if i not in hol]
    return LagrangesMethod(J.to_dynamic(system.L), [J.to_dynamic(q) for q in J.q],
                           hol_coneqs=[J.to_dynamic(g) for g in system.holonomic] or None,
                           nonhol_coneqs=[J.to_dynamic(f) for f in nonhol] or None)
