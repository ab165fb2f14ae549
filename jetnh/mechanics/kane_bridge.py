"""Kane models into jetnh: a ``KanesMethod`` or a mechanics ``System`` becomes a ``System``.

A Kane model states its kinematics in generalized speeds u, tied to the coordinates by
the kinematic differential equations k(t, q, qdot, u) = 0 (linear in qdot and u).  jetnh
works in q and qdot, so the speeds are solved from them, u = U(t, q, qdot), and every
expression of the model is read with u replaced by U:

- L = T - V: T the kinetic energies of the bodies and particles; V the potential of the
  loads that have one, a function of the configuration, checked against their
  generalized forces: a force constant in the inertial frame on a point located from a
  point at rest, V = -F . r; a load whose generalized forces are free of t and qdot
  with a symmetric Jacobian, such as a spring F = -k r: the potential a spring actuator
  states (a ``LinearSpring``'s k (L - l)^2 / 2 of its pathway's length L, a
  ``DuffingSpring``'s), else integrated (sympy's integrate, in a forked child process within
  ``POTENTIAL_SECONDS`` of CPU time: past it the load stays a generalized force, with a
  JetnhWarning; in process and without a bound where there is no ``os.fork`` or it is
  refused), and kept
  only where V stands for the load wherever it is defined and is 2 pi-periodic in every
  coordinate the load is (a torque tau on an angle has no potential: V = -tau theta; a
  torsion spring's k theta^2 / 2 stands for it);
- every other load gives generalized forces Q_s = sum F . dv/dqdot^s (v the velocity of
  the point, or the angular velocity of the frame, in the inertial frame; the loads of
  one actuator are judged together; a component of F along which no velocity moves the
  point does no work and is not read, as KanesMethod with auxiliary speeds);
- velocity constraints (linear in u) become constraints in qdot; configuration
  constraints g(t, q) = 0 stay holonomic (``System.holonomic``: a Scene checks or
  completes the initial configuration and keeps runs on g = 0), and the velocity
  constraints that only restate D g are left out (one that has its velocities but
  another term is refused);
- ``Speeds`` keeps the map both ways, u = U(t, q, qdot) and qdot = V(t, q, u).

The model's kinematics must hold for every qdot, not only on the constraints: each body's
velocity and angular velocity is checked at random states against the time derivative
of its position (from a point at rest) and of its orientation.  A model that builds a
constraint into its kinematics (a rolling contact point set at rest) is refused, with
the fix: give the contact point coordinates and the constraint as velocity constraints.
Functions of time other than q and u (specified inputs) are refused, as loads whose
point has no velocity.
"""

from __future__ import annotations

import numbers
import os
import random
import sys
import warnings
from dataclasses import dataclass

import mpmath
import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from ..algebra import dag, linalg, singular, zero
from ..errors import JetnhError, JetnhWarning, JetSpaceError
from ..geometry.jet import JetSpace, key_name
from . import forked

#: relative agreement asked of the kinematic and potential checks at random states
CHECK_TOL = 1e-12
#: random states per check
CHECK_POINTS = 2
#: CPU seconds that sympy may take to integrate one load into its potential, in a forked
#: child process (given three times that and a second of wall time: it shares the CPUs,
#: and may wait on a lock another thread held at the fork); past it the load stays a
#: generalized force; ``math.inf``: no bound
POTENTIAL_SECONDS = 5.0


@dataclass(frozen=True)
class Speeds:
    """A Kane model's generalized speeds and jetnh's velocities, both ways.

    ``symbols`` are Symbols named like the speeds (``u1`` for ``u1(t)``);
    ``of_velocities[i]`` is u_i in t, q, qdot (jet Symbols) and ``velocities[s]`` is
    qdot^s in t, q and ``symbols``.
    """

    J: JetSpace
    symbols: tuple
    of_velocities: tuple
    velocities: tuple

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.symbols)

    def read(self, traj, params=None) -> dict[str, np.ndarray]:
        """The speeds along a trajectory (or at a state: anything indexed by the names of
        t, q and qdot), keyed by name; ``params`` gives the parameters they contain."""
        J = self.J
        point = {J.t: np.asarray(traj.t if hasattr(traj, "t") else traj[J.t.name], dtype=float)}
        point.update((s, np.asarray(traj[s.name], dtype=float)) for s in (*J.q, *J.qd))
        for k, v in (params or {}).items():
            name = key_name(k)
            if name is None:
                raise JetnhError(f"params keys are parameter Symbols or names, not {k!r}")
            point[sp.Symbol(name)] = float(v)
        try:
            values = dag.evaluate_numpy(list(self.of_velocities), point)
        except ValueError as exc:
            raise JetnhError(f"Speeds.read: {exc}; give the parameters in params=") from None
        return dict(zip(self.names, values))

    def __repr__(self):
        return "Speeds(" + ", ".join(f"{u} = {e}" for u, e in
                                     zip(self.names, self.of_velocities)) + ")"


# ------------------------------------------------------------------ the model read
@dataclass(frozen=True)
class _Kane:
    """What a Kane model states, in dynamicsymbols."""

    frame: object
    q: tuple
    u: tuple
    u_aux: tuple
    kdes: tuple
    bodies: tuple
    loads: tuple              # groups of (Point or frame, Vector): a load, an actuator's
    springs: tuple            # per group, the potential its actuator states, or None
    holonomic: tuple          # g(t, q) = 0
    velocity: tuple           # velocity constraints, linear in u (or qdot)
    restates_holonomic: bool  # whether ``velocity`` contains D g too (KanesMethod's contract)
    fixed_point: object       # a point at rest in ``frame``, or None: searched


def _unread_potential_energy(bodies, method: str):
    """Refuse a body's potential_energy, which KanesMethod does not read."""
    for b in bodies:
        if getattr(b, "potential_energy", 0) != 0:
            raise JetnhError(
                f"the body {b.name} has a potential_energy, which KanesMethod ({method}) does "
                "not read; give the force as a load (e.g. System.apply_uniform_gravity), or "
                "form the equations with LagrangesMethod (a mechanics System: "
                "system.form_eoms(LagrangesMethod)) to import those")


def read_kanes_method(km) -> _Kane:
    if km.bodies is None:
        raise JetnhError("the KanesMethod has no bodies yet; pass bodies= (and forcelist=) "
                         "to KanesMethod or call km.kanes_equations(bodies, loads) first")
    _unread_potential_energy(km.bodies, "the model's")
    vel = (sp.Matrix(km._k_nh) * km.u + sp.Matrix(km._f_nh)) if len(km._k_nh) else []
    loads = tuple((ld,) for ld in km.loads or ())
    return _Kane(km._inertial, tuple(km.q), tuple(km.u), tuple(km._uaux),
                 tuple(km._k_kqdot_implicit * km.q.diff(_t()) + km._k_ku_implicit * km.u
                       + km._f_k_implicit) if len(km._k_ku_implicit) else (),
                 tuple(km.bodies), loads, (None,) * len(loads), tuple(km._f_h),
                 tuple(vel), True, None)


def read_mechanics_system(ms) -> _Kane:
    _unread_potential_energy(ms.bodies, "the System's default")
    loads = tuple((ld,) for ld in ms.loads) + tuple(tuple(act.to_loads()) for act in ms.actuators)
    springs = (None,) * len(ms.loads) + tuple(_spring(act) for act in ms.actuators)
    explicit = ms._vel_constrs is not None
    return _Kane(ms.frame, tuple(ms.q), tuple(ms.u), tuple(ms.u_aux), tuple(ms.kdes),
                 tuple(ms.bodies), loads, springs, tuple(ms.holonomic_constraints),
                 tuple(ms.velocity_constraints if explicit else ms.nonholonomic_constraints),
                 explicit, ms.fixed_point)


def _spring(actuator):
    """The potential a spring actuator states, from its pathway's length L and rest
    length l (x = L - l): a ``LinearSpring`` k x^2 / 2, a ``DuffingSpring`` (sympy 1.13)
    a x^2 / 2 + b x^4 / 4; None for any other actuator (or a length sympy cannot give)."""
    from sympy.physics import mechanics as me

    duffing = getattr(me, "DuffingSpring", ())
    if not isinstance(actuator, (me.LinearSpring, duffing)):
        return None
    try:
        x = actuator.pathway.length - actuator.equilibrium_length
    except Exception:  # a pathway whose length sympy cannot state: integrated instead
        return None
    if isinstance(actuator, me.LinearSpring):
        return actuator.stiffness * x**2 / 2
    return actuator.linear_stiffness * x**2 / 2 + actuator.nonlinear_stiffness * x**4 / 4


def _t():
    from sympy.physics.vector import dynamicsymbols

    return dynamicsymbols._t


# ------------------------------------------------------------------ the conversion
class _Reader:
    """Reads the expressions of one Kane model as jet expressions."""

    def __init__(self, model: _Kane):
        self.model = model
        t = _t()
        names = []
        for q in model.q:
            if not (isinstance(q, AppliedUndef) and q.args == (t,)):
                raise JetnhError(f"the coordinate {q} is not a dynamicsymbol q(t); build it "
                                 "with dynamicsymbols('q')")
            names.append(q.func.__name__)
        if len(model.u) != len(model.q):
            raise JetnhError(
                f"the model has {len(model.q)} coordinates and {len(model.u)} generalized "
                "speeds; jetnh reads speeds as an invertible change of the velocities, one "
                "per coordinate: add the missing speeds (dependent ones with velocity "
                "constraints) and their kinematic differential equations")
        if len(model.kdes) != len(model.q):
            raise JetnhError("the model has no kinematic differential equations for every "
                             "coordinate; give one per coordinate (e.g. q' - u = 0)")
        self.J = JetSpace(names, t=t.name)
        qd = [q.diff(t) for q in model.q]
        kd = sp.Matrix(model.kdes).xreplace(dict.fromkeys(model.u_aux, 0))
        k_u, k_qd = kd.jacobian(model.u), kd.jacobian(qd)
        f_k = kd.xreplace({**dict.fromkeys(model.u, 0), **dict.fromkeys(qd, 0)})
        if any(M.has(*model.u, *qd) for M in (k_u, k_qd, f_k)):
            raise JetnhError("the kinematic differential equations are not linear in the "
                             "speeds and the velocities; write them linear (as KanesMethod "
                             "requires), e.g. q' - u = 0")
        if _singular(k_u) or _singular(k_qd):
            raise JetnhError(
                "the kinematic differential equations do not determine the speeds from the "
                "velocities (and back) at a random state; give one speed per independent "
                "velocity combination")
        self.u_of_qd = dict(zip(model.u, _solve(k_u, -(k_qd * sp.Matrix(qd) + f_k))))
        self.u_of_qd.update(dict.fromkeys(model.u_aux, 0))
        syms = [sp.Symbol(u.func.__name__) for u in model.u]
        qd_of_u = _solve(k_qd, -(k_u * sp.Matrix(syms) + f_k))
        self.speeds = Speeds(self.J, tuple(syms),
                             tuple(self.jet(self.u_of_qd[u], f"the speed {u}") for u in model.u),
                             tuple(self.J.from_dynamic(e) for e in qd_of_u))

    def jet(self, expr, what):
        """``expr`` (dynamicsymbols, speeds) in t, q, qdot."""
        expr = sp.sympify(expr, strict=True).xreplace(self.u_of_qd)
        try:
            return self.J.from_dynamic(expr)
        except JetSpaceError as exc:
            raise JetSpaceError(
                f"{what} of the Kane model: {exc}. from_mechanics reads functions of time "
                "only among the coordinates and speeds; substitute specified inputs (e.g. "
                "r(t)) by parameters or expressions of t first") from None

    def vector(self, vec, what) -> sp.Matrix:
        """The inertial components of a Vector, as jet expressions."""
        N = self.model.frame
        return sp.Matrix([self.jet(c, what) for c in vec.to_matrix(N)])


def _solve(A: sp.Matrix, b: sp.Matrix) -> list:
    """A^-1 b without spurious singularities (``linalg.solve``: the only denominator of
    a small system is det A, so u3/cos(q2) is not written over sin(q2))."""
    return list(linalg.solve(A, b))


def _singular(M: sp.Matrix) -> bool:
    rnd = random.Random(1)
    point = {s: sp.Float(rnd.uniform(0.3, 1.3), 30) for s in M.free_symbols}
    for f in M.atoms(AppliedUndef) | M.atoms(sp.Derivative):
        point[f] = sp.Float(rnd.uniform(-1, 1), 30)
    num = M.xreplace(point).evalf(30)
    return num.rows != num.cols or abs(num.det()) < 1e-20


def _random_points(J: JetSpace, exprs, n=CHECK_POINTS, seed=7):
    """States (t, q, qdot and the parameters of ``exprs``) drawn at random."""
    rnd = random.Random(seed)
    free = set().union(*(dag.free_symbols(e) for e in exprs)) if exprs else set()
    own = {J.t, *J.q, *J.qd}
    out = []
    for _ in range(n):
        p = {s: rnd.uniform(0.4, 1.4) for s in free - own}
        p.update({s: rnd.uniform(-1, 1) for s in own})
        out.append(p)
    return out


def _agree(a, b, points, nonfinite=False) -> bool:
    """Whether ``a`` and ``b`` agree at ``points`` (``CHECK_TOL`` relative); at a point
    where a value is NaN or infinite, ``nonfinite`` is the answer."""
    for p in points:
        va, vb = dag.evaluate(list(a), p), dag.evaluate(list(b), p)
        if not all(mpmath.isfinite(v) for v in (*va, *vb)):
            return nonfinite
        scale = max([1] + [abs(v) for v in vb])
        if any(abs(x - y) > CHECK_TOL * scale for x, y in zip(va, vb)):
            return False
    return True


def _fixed_point(model: _Kane, start):
    """A point at rest in the inertial frame from which ``start`` is located, or None."""
    N = model.frame
    if model.fixed_point is not None:
        return model.fixed_point
    seen, todo = {start}, [start]
    while todo:
        p = todo.pop()
        v = p._vel_dict.get(N)
        if v is not None and v == 0:
            return p
        for nxt in p._pos_dict:
            if nxt not in seen:
                seen.add(nxt)
                todo.append(nxt)
    return None


def _position(reader: _Reader, point, what) -> sp.Matrix:
    O = _fixed_point(reader.model, point)
    if O is None:
        raise JetnhError(
            f"{what} ({point.name}) is not located from a point at rest in "
            f"{reader.model.frame.name}, so its velocity cannot be checked against its "
            "motion; locate it (locatenew) from a point whose velocity is set to zero. If "
            "the model sets a contact point at rest to build a rolling constraint into the "
            "kinematics, give the contact point coordinates instead and the rolling as "
            "velocity constraints")
    try:
        r = point.pos_from(O)
    except ValueError:
        raise JetnhError(f"{what} ({point.name}) has no position from {O.name}") from None
    return reader.vector(r, f"the position of {point.name}")


def _check_point(reader: _Reader, point, what):
    """The velocity of ``point`` is the time derivative of its position."""
    J, N = reader.J, reader.model.frame
    r = _position(reader, point, what)
    v = reader.vector(point.vel(N), f"the velocity of {point.name}")
    dr = [J.D(c) for c in r]
    if not _agree(v, dr, _random_points(J, list(v) + dr)):
        raise JetnhError(
            f"the velocity of {point.name} ({what}) in {N.name} is not the time derivative "
            f"of its position at random states: the kinematics hold only on some "
            "constraint (e.g. a rolling point set at rest); state the velocities for every "
            "motion and give the constraint as a velocity constraint")
    return r


def _check_frame(reader: _Reader, frame, what):
    """The angular velocity of ``frame`` is the one of its orientation (W = C' C^T)."""
    J, N = reader.J, reader.model.frame
    try:
        dcm = frame.dcm(N)
    except ValueError:
        raise JetnhError(f"the orientation of {frame.name} ({what}) in {N.name} is not known, so "
                         "its angular velocity cannot be checked; orient it from "
                         f"{N.name} (orient_axis, orientnew, a joint)") from None
    C = sp.Matrix(dcm).applyfunc(lambda e: reader.jet(e, f"the orientation of {what}"))
    Cd = C.applyfunc(J.D)
    W = Cd * C.T
    w = [W[1, 2], W[2, 0], W[0, 1]]
    given = [reader.jet(c, f"the angular velocity of {what}")
             for c in frame.ang_vel_in(N).to_matrix(frame)]
    if not _agree(given, w, _random_points(J, given + w)):
        raise JetnhError(
            f"the angular velocity of {frame.name} ({what}) in {N.name} is not the one of "
            "its orientation at random states; set it from the orientation (or with speeds "
            "whose kinematic differential equations match it)")


def lagrangian_and_forces(reader: _Reader):
    """T - V and the generalized forces of the other loads (see the module docstring)."""
    from sympy.physics.vector import Point, ReferenceFrame

    J, N = reader.J, reader.model.frame
    T = sp.S.Zero
    for b in reader.model.bodies:
        what = f"the body {b.name}"
        _check_point(reader, b.masscenter, what)
        if not _is_particle(b):
            _check_frame(reader, b.frame, what)
        T += reader.jet(b.kinetic_energy(N), f"the kinetic energy of {b.name}")
    V = sp.S.Zero
    Q = [sp.S.Zero] * J.n
    for group, spring in zip(reader.model.loads, reader.model.springs):
        # an actuator's loads are judged together
        q_load, names = [sp.S.Zero] * J.n, []
        for where, vec in (load[:2] for load in group):
            if isinstance(where, Point):
                try:
                    vel = where.vel(N)
                except ValueError:
                    raise JetnhError(f"a load acts on the point {where.name}, whose velocity "
                                     f"in {N.name} is not known; set it (set_vel, "
                                     "v2pt_theory)") from None
                names.append(f"the point {where.name}")
            elif isinstance(where, ReferenceFrame):
                vel = where.ang_vel_in(N)
                names.append(f"the frame {where.name}")
            else:
                raise JetnhError(f"a load acts on {where!r}; loads act on a Point or a "
                                 "ReferenceFrame")
            v = reader.vector(vel, f"the velocity of {names[-1]}")
            partial = [[dag.diff(c, qd) for c in v] for qd in J.qd]
            F, whole = _components(reader, vec, partial, f"the load on {names[-1]}")
            q_load = [a + sum((f * p for f, p in zip(F, row)), sp.S.Zero)
                      for a, row in zip(q_load, partial)]
        if all(e == 0 for e in q_load):
            continue
        what = " and ".join(names)
        pot = (_potential(reader, where, F, q_load)
               if len(group) == 1 and isinstance(where, Point) and whole else None)
        if pot is None and spring is not None:
            pot = _stated(reader, spring, q_load)
        if pot is None:
            pot = _conservative(J, q_load, f"the load on {what}")
        if pot is not None:
            V += pot
        else:
            Q = [a + b for a, b in zip(Q, q_load)]
    return T - V, {q: e for q, e in zip(J.q, Q) if e != 0}


def _components(reader: _Reader, vec, partial, what):
    """The inertial components of a load, as jet expressions, and whether all of them
    are: a component along which no velocity moves the point (every partial velocity's
    is 0) does no work and may hold what jet expressions cannot (a contact force f(t) on
    a point moved by auxiliary speeds only, as KanesMethod reads it): it is 0 then."""
    out, whole = [], True
    for i, c in enumerate(vec.to_matrix(reader.model.frame)):
        try:
            out.append(reader.jet(c, what))
        except JetSpaceError:
            if any(row[i] != 0 for row in partial):
                raise
            out.append(sp.S.Zero)
            whole = False
    return out, whole


def _is_particle(b) -> bool:
    """Whether ``b`` has no frame to check (sympy's Body is a RigidBody and a Particle:
    ``is_rigidbody`` tells)."""
    from sympy.physics.mechanics import RigidBody

    return not isinstance(b, RigidBody) or not getattr(b, "is_rigidbody", True)


def _potential(reader: _Reader, point, F, Q):
    """-F . r for a force constant in the inertial frame on a point located from a point
    at rest, when its generalized forces are -dV/dq (checked); else None."""
    J = reader.J
    own = {J.t, *J.q, *J.qd}
    if any(dag.free_symbols(c) & own for c in F) or _fixed_point(reader.model, point) is None:
        return None
    r = _check_point(reader, point, "the point of a load")
    V = -sum((F[i] * r[i] for i in range(3)), sp.S.Zero)
    minus_dV = [-dag.diff(V, q) for q in J.q]
    return V if _agree(minus_dV, Q, _random_points(J, minus_dV + list(Q))) else None


def _gradient_like(J: JetSpace, Q) -> bool:
    """Whether generalized forces ``Q`` may be -dV/dq: they depend on q and are free of t
    and qdot (and of Piecewise, which is not evaluated at random points)."""
    own, q = {J.t, *J.qd}, set(J.q)
    free = [dag.free_symbols(e) for e in Q]
    return (any(f & q for f in free) and not any(f & own for f in free)
            and not any(dag.has(e, sp.Piecewise) for e in Q))


def _stated(reader: _Reader, V, Q):
    """The potential ``V`` an actuator states (in dynamicsymbols), as a jet expression,
    where its load's generalized forces ``Q`` may be a gradient and it ``_stands_for``
    them; else None."""
    J = reader.J
    if not _gradient_like(J, Q):
        return None
    try:
        V = reader.jet(V, "the spring's potential")
    except JetSpaceError:
        return None
    return V if _stands_for(J, V, Q) else None


def _conservative(J: JetSpace, Q, what="a load"):
    """V with -dV/dq = ``Q`` where the generalized forces ``Q`` of ``what`` (a load)
    are conservative: ``_gradient_like``, with a symmetric Jacobian (dQ_i/dq_j =
    dQ_j/dq_i, at random configurations), ``_integrated`` within ``POTENTIAL_SECONDS``
    (``_bounded``) and ``_stands_for`` Q (checked here: the child process is not trusted
    either); else None: the load stays a generalized force, which is always right."""
    if not _gradient_like(J, Q):
        return None
    n = len(J.q)
    rows = [dag.diff(Q[i], J.q[j]) for i in range(n) for j in range(i + 1, n)]
    cols = [dag.diff(Q[j], J.q[i]) for i in range(n) for j in range(i + 1, n)]
    if rows and not _agree(rows, cols, _random_points(J, rows + cols)):
        return None
    V = _bounded(what, _integrated, J, Q)
    return V if V is not None and _stands_for(J, V, Q) else None


def _integrated(J: JetSpace, Q):
    """V = -int Q_1 dq_1, then -int (Q_2 + dV/dq_2) dq_2, ... (a spring F = -k r on a
    point, a torsion spring on a frame), or None where sympy gives up or leaves an
    integral."""
    V = sp.S.Zero
    for qi, e in zip(J.q, Q):
        try:
            part = sp.integrate(sp.expand(-e - dag.diff(V, qi)), qi)
        except Exception:  # sympy gave up: the load stays a force, as without integrating
            return None
        if part.has(sp.Integral):
            return None
        V += part
    return V


# ------------------------------------------------------------------ the time bound
def _bounded(what, fn, *args):
    """``fn(*args)`` (picklable) computed in a forked child process within
    ``POTENTIAL_SECONDS`` of CPU time (``math.inf``: no bound), three times that and a
    second of wall time (a child may wait forever on a lock another thread held at the
    fork); None, with a JetnhWarning naming the load (``what``) and why, once the child
    ends or is ended without a result (the advice to raise the budget only where the
    budget ended it).  Where there is no ``os.fork`` (Windows) or the fork is refused (no
    memory, a process limit), ``fn(*args)`` in process, without a bound.  Ctrl-C calls
    the SIGINT handler within ``forked.POLL`` (its KeyboardInterrupt ends the child); the child
    is always reaped and the pipe closed."""
    seconds = POTENTIAL_SECONDS
    if isinstance(seconds, bool) or not isinstance(seconds, numbers.Real) or not seconds >= 0:
        raise JetnhError(f"jetnh.mechanics.kane_bridge.POTENTIAL_SECONDS is {seconds!r}; set "
                         "it to a number of seconds >= 0 (math.inf: no bound)")
    if not hasattr(os, "fork"):
        return fn(*args)
    how, out = forked.computed(fn, args, seconds, 3 * seconds + 1)
    if how == "value":
        return out
    if how == "no fork":
        return fn(*args)
    lost = ("so it stays a generalized force: the equations are the same, but the energy "
            "and connect's cost leave it out")
    if how == "time":
        text = (f"{what}: its potential was not found within {seconds:g} s of CPU time "
                f"(sympy's integration, in a child process: {out}), {lost}; to wait longer, "
                "raise jetnh.mechanics.kane_bridge.POTENTIAL_SECONDS")
    else:
        text = (f"{what}: its potential was not found (sympy's integration, in a child "
                f"process: {out}), {lost}")
    warnings.warn(text, JetnhWarning, stacklevel=_outside_jetnh())
    return None


def _outside_jetnh() -> int:
    """The ``stacklevel`` that points a warning of the caller at the first caller outside
    jetnh (the user's ``from_mechanics``)."""
    level, frame = 1, sys._getframe(1)
    while (frame.f_back is not None
           and frame.f_globals.get("__name__", "").partition(".")[0] == "jetnh"):
        level, frame = level + 1, frame.f_back
    return level


#: functions defined, finite and smooth on the whole real line: a V may contain them
#: where its load does not (V = -k cos q for Q = -k sin q)
_ENTIRE = (sp.exp, sp.sin, sp.cos, sp.sinh, sp.cosh)


def _stands_for(J: JetSpace, V, Q) -> bool:
    """Whether L = T - V gives the equations of Q, wherever Q is defined, and V is a
    function of the configuration wherever Q is:

    - V is real (no imaginary unit: the vortex Q = k (-y, x) / ``|r|^2`` integrates to
      complex logs, it has no potential on the punctured plane);
    - V has no function Q does not have, but entire ones (a Piecewise from q^a; log q
      from k/q is undefined at q < 0, log(tanh q + 1) from tanh q is log 0 at q = -25
      in floating point);
    - V and its -dV/dq are singular nowhere Q is not (``_new_singularities``);
    - -dV/dq is Q (``_zero``);
    - V is 2 pi-periodic in every coordinate Q is 2 pi-periodic in (at random states):
      such a coordinate may be an angle, on which a torque tau (or tau - k sin q) does
      work 2 pi tau a turn and V = -tau q is no function of the configuration; a torsion
      spring -k q is no function of an angle either, and V = k q^2 / 2 stands for it."""
    if V.has(sp.I):
        return False
    heads = {type(f) for e in Q for f in dag.atoms(e, sp.Function)}
    if any(not isinstance(f, (*heads, *_ENTIRE)) for f in V.atoms(sp.Function)):
        return False
    minus_dV = [-dag.diff(V, qi) for qi in J.q]
    if _new_singularities(Q, (V, *minus_dV)):
        return False
    if not _zero([a - e for a, e in zip(minus_dV, Q)]):
        return False
    return all(_zero([V.xreplace({qi: qi + 2 * sp.pi}) - V])
               for qi in J.q if _periodic_at_random(J, Q, qi))


def _new_singularities(Q, exprs) -> bool:
    """Whether ``exprs`` may be singular or undefined where ``Q`` is not: a base
    (``singular.bases``) Q does not have, but a denominator whose factors
    (``singular.factors``: no powers, no sign) are all factors of Q's bases, which
    vanishes only where one of them does (the derivative of sqrt(w^2) is
    w sqrt(w^2) / w^2, with 1 / w^2 where Q has sqrt(w^2)); a root's or a log's
    argument is compared as it is (sqrt(w) is undefined where sqrt(w^2) is not)."""
    allowed = {b for e in Q for b in singular.bases(e)}
    zeros = {f for b in allowed for f in singular.factors(b)}
    for e in exprs:
        over = {p: p.base ** -p.exp for p in dag.atoms(e, sp.Pow)
                if p.exp.is_Integer and p.exp.is_negative}
        # the other bases: those of e with its denominators made numerators (one within
        # another's base stays: compared as it is, which only asks more)
        if any(b not in allowed for b in singular.bases(dag.xreplace(e, over))):
            return True
        if any(p.base not in allowed and not set(singular.factors(p.base)) <= zeros
               for p in over):
            return True
    return False


def _zero(exprs) -> bool:
    """Whether ``exprs`` vanish: expanded, else by evaluation (``zero.vanishes``: the
    forms sympy integrates to keep sin^2 + cos^2 where the load has 1)."""
    return all(sp.expand(e) == 0 for e in exprs) or zero.vanishes(exprs)


def _periodic_at_random(J: JetSpace, Q, q) -> bool:
    """Whether ``Q`` is 2 pi-periodic in ``q`` at random states: True unless shown
    otherwise (a value that cannot be compared counts as periodic, which only asks
    more of V)."""
    shifted = [e.xreplace({q: q + 2 * sp.pi}) for e in Q]
    try:
        return _agree(shifted, Q, _random_points(J, list(Q)), nonfinite=True)
    except Exception:  # no value to compare (a domain error): asks more of V, never less
        return True


def constraints(reader: _Reader) -> list:
    """The velocity constraints in qdot, then the configuration constraints through
    ``holonomic``; velocity constraints that restate D g are left out."""
    J, model = reader.J, reader.model
    vel = [reader.jet(f, f"velocity constraint {a + 1}") for a, f in enumerate(model.velocity)]
    hol = [reader.jet(g, f"configuration constraint {a + 1}")
           for a, g in enumerate(model.holonomic)]
    for a, g in enumerate(hol):
        if dag.free_symbols(g) & set(J.qd):
            raise JetnhError(f"configuration constraint {a + 1} contains velocities; give it "
                             "as a velocity (nonholonomic) constraint")
    if hol and model.restates_holonomic:
        vel = _complement(J, vel, hol)
    return vel + holonomic(hol)


def holonomic(g: list) -> list:
    """How configuration constraints g(t, q) = 0 enter the System: as written, so that
    it keeps them at position level (``System.holonomic``; its equations use D g)."""
    return list(g)


def _complement(J: JetSpace, vel: list, hol: list) -> list:
    """The velocity constraints that, with D g, span what all of them span (chosen at a
    random state, in the given order); each one left out must be a combination of D g
    and those kept, its term free of the velocities included (else it is no restatement
    of D g, and leaving it out would change the motion)."""
    point = _random_points(J, vel + hol, n=1, seed=11)[0]
    rank = np.linalg.matrix_rank

    def row(e):     # [de/dqdot, e at qdot = 0] at the point (e is linear in qdot)
        parts = [dag.diff(e, qd) for qd in J.qd] + [dag.xreplace(e, dict.fromkeys(J.qd, 0))]
        return [float(x) for x in dag.evaluate(parts, point)]

    rows = [row(J.D(g)) for g in hol]
    if rows and rank(np.array(rows)[:, :-1]) < len(hol):
        raise JetnhError("the configuration constraints are dependent (their Jacobian is "
                         "rank-deficient at a random configuration); give independent ones")
    kept = []
    for a, f in enumerate(vel):
        new = row(f)
        if rank(np.array(rows + [new])[:, :-1]) > len(rows):
            rows.append(new)
            kept.append(f)
        elif rank(np.array(rows + [new])) > len(rows):
            raise JetnhError(
                f"velocity constraint {a + 1} has the velocities of a combination of the "
                "differentiated configuration constraints (and the velocity constraints "
                "before it) but another term free of them: it is not the time derivative "
                "of the configuration constraints, and Kane's motions would leave them; "
                "give D g as the velocity constraint, or the configuration constraint "
                "as it really is")
    if len(kept) != len(vel) - len(hol):
        raise JetnhError(
            f"of the {len(vel)} velocity constraints, {len(kept)} are independent of the "
            f"{len(hol)} differentiated configuration constraints (expected "
            f"{len(vel) - len(hol)}): each velocity constraint of a KanesMethod is either "
            "nonholonomic or a derivative of a configuration constraint; give independent "
            "ones")
    return kept


def read(model):
    """``(J, L, constraints, forces, speeds)`` of a KanesMethod or a mechanics System."""
    from sympy.physics.mechanics import KanesMethod

    kane = (read_kanes_method(model) if isinstance(model, KanesMethod)
            else read_mechanics_system(model))
    reader = _Reader(kane)
    L, forces = lagrangian_and_forces(reader)
    return reader.J, L, constraints(reader), forces, reader.speeds
