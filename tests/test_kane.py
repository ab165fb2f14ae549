"""Kane models into jetnh: ``from_mechanics`` of a ``KanesMethod`` or a mechanics ``System``.

Route 1: jetnh's Chetaev accelerations q'' of the imported System, turned into speed rates
u' = D U(t, q, qdot) through the imported speed map.  Route 2: the model's own Kane
equations, ``mass_matrix u' = forcing`` (the dependent rows from the differentiated
velocity constraints), solved in 30-digit arithmetic.  States: random coordinates (on the
configuration constraints), random independent velocities, dependent ones from jetnh's
split; Kane reads the speeds u = U(q, qdot) of that state.
"""

from __future__ import annotations

import math
import random

import mpmath
import numpy as np
import pytest
import sympy as sp
from hypothesis import Phase, given, settings, strategies as st
from sympy.physics.mechanics import (KanesMethod, Particle, PinJoint, PlanarJoint, Point,
                                     PrismaticJoint, ReferenceFrame, RigidBody,
                                     TorqueActuator, dot, dynamicsymbols, inertia)
from sympy.physics.mechanics import System as MechanicsSystem

import jetnh as jn
from jetnh.algebra import dag
from jetnh.errors import JetnhError, JetSpaceError
from jetnh.mechanics.energy import changes

PREC = 30
RTOL = 1e-20

r, m, g, c, tau, ell, a, M = sp.symbols("r m g c tau ell a M", positive=True)


# ---------------------------------------------------------------------- the two routes
def kane_of(model):
    """The KanesMethod behind a model (a mechanics System forms its equations)."""
    if isinstance(model, MechanicsSystem):
        if model.eom_method is None:
            model.form_eoms()
        return model.eom_method
    return model


def agreement(system, model, params, sample_q=None, points=3, seed=0):
    """The largest relative difference of u' between jetnh and Kane at random states."""
    km = kane_of(model)
    J, speeds = system.J, system.speeds
    acc = system.equations("chetaev").accelerations()
    udot_jet = [J.D(U) for U in speeds.of_velocities]
    M_k, F_k = km.mass_matrix, km.forcing
    rnd = random.Random(seed)
    worst = 0.0
    for _ in range(points):
        vals = {p: sp.Float(v, PREC) for p, v in params.items()}
        vals[J.t] = sp.Float(rnd.uniform(-1, 1), PREC)
        qs = sample_q(rnd) if sample_q else [rnd.uniform(-1, 1) for _ in J.q]
        vals.update({q: sp.Float(v, PREC) for q, v in zip(J.q, qs)})
        vals.update({v: sp.Float(rnd.uniform(-1, 1), PREC)
                     for v in system.independent_velocities})
        for v, phi in system.phi.items():
            vals[v] = dag.evaluate(phi, vals, PREC)
        vals.update({a_: dag.evaluate(acc[a_], vals, PREC) for a_ in J.qdd})
        jet = [dag.evaluate(e, vals, PREC) for e in udot_jet]
        u = [dag.evaluate(e, vals, PREC) for e in speeds.of_velocities]
        dyn = {dynamicsymbols._t: vals[J.t], **{q: vals[s] for q, s in zip(km.q, J.q)},
               **dict(zip(km.u, u)), **{p: v for p, v in vals.items() if p in params}}
        with mpmath.workdps(PREC):
            num = [dag.to_sympy(v) for v in dag.evaluate(list(M_k) + list(F_k), dyn, PREC)]
            jet = [dag.to_sympy(v) for v in jet]
        o = len(km.u)
        ref = sp.Matrix(o, o, num[:o * o]).LUsolve(sp.Matrix(num[o * o:]))
        for x, y in zip(jet, ref):
            worst = max(worst, float(abs(x - y) / max(1, abs(y))))
    return worst


# ---------------------------------------------------------------------- models
def rolling_disc():
    """sympy's rolling disc (Kane): yaw q1, lean q2, spin q3, contact point (x, y); the
    speeds u1..u3 are the disc's angular velocity in the lean frame, u4, u5 = x', y'
    (dependent: rolling without slip), gravity on the centre."""
    q1, q2, q3, x, y = dynamicsymbols("q1 q2 q3 x y")
    u1, u2, u3, u4, u5 = dynamicsymbols("u1:6")
    N = ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [q1, N.z])
    L = Y.orientnew("L", "Axis", [q2, Y.x])
    R = L.orientnew("R", "Axis", [q3, L.y])
    kd = [dot(R.ang_vel_in(N) - (u1 * L.x + u2 * L.y + u3 * L.z), e) for e in L]
    kd += [x.diff() - u4, y.diff() - u5]
    R.set_ang_vel(N, u1 * L.x + u2 * L.y + u3 * L.z)
    O = Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", x * N.x + y * N.y)
    C.set_vel(N, u4 * N.x + u5 * N.y)
    Dmc = C.locatenew("Dmc", r * L.z)
    Dmc.set_vel(N, C.vel(N) + L.ang_vel_in(N).cross(r * L.z))
    slip = Dmc.vel(N) + R.ang_vel_in(N).cross(-r * L.z)
    disc = RigidBody("disc", Dmc, R, m, (inertia(L, m * r**2 / 4, m * r**2 / 2, m * r**2 / 4),
                                         Dmc))
    km = KanesMethod(N, q_ind=[q1, q2, q3, x, y], u_ind=[u1, u2, u3], kd_eqs=kd,
                     u_dependent=[u4, u5], velocity_constraints=[slip.dot(N.x), slip.dot(N.y)])
    km.kanes_equations([disc], [(Dmc, -m * g * N.z)])
    return km


def cart_pendulum():
    """A joint-built mechanics System: a cart on a prismatic joint, a pendulum on a pin;
    gravity, a damper on the cart and a torque on the pendulum (not potential)."""
    rail = RigidBody("rail")
    ms = MechanicsSystem.from_newtonian(rail)
    cart = RigidBody("cart", mass=M)
    bob = RigidBody("rod", mass=m)
    bob.inertia = (inertia(bob.frame, 0, 0, m * ell**2 / 12), bob.masscenter)
    s, th = dynamicsymbols("s theta")
    v, w = dynamicsymbols("v omega")
    slider = PrismaticJoint("slider", rail, cart, s, v, joint_axis=rail.x)
    pin = PinJoint("pin", cart, bob, th, w, joint_axis=cart.z, child_point=ell * bob.x)
    ms.add_joints(slider, pin)
    ms.apply_uniform_gravity(-g * rail.y)
    ms.add_loads((cart.masscenter, -c * v * rail.x), (bob.frame, tau * rail.z))
    return ms


def planar_sleigh():
    """A joint-built Chaplygin sleigh: a planar joint (rotation about the ground's x axis,
    sliding in its y-z plane), the blade's side slip forbidden by
    add_nonholonomic_constraints, a linear drag (not potential)."""
    ground = RigidBody("ground")
    ms = MechanicsSystem.from_newtonian(ground)
    body = RigidBody("sleigh", mass=m)
    body.inertia = (inertia(body.frame, m * a**2, 0, 0), body.masscenter)
    th, x, y = dynamicsymbols("theta x y")
    w, vx, vy = dynamicsymbols("omega v_x v_y")
    ms.add_joints(PlanarJoint("planar", ground, body, rotation_coordinate=th,
                              planar_coordinates=[x, y], rotation_speed=w,
                              planar_speeds=[vx, vy]))
    ms.u_ind, ms.u_dep = [w, vx], [vy]
    blade = body.masscenter.locatenew("blade", -a * body.y)
    blade.v2pt_theory(body.masscenter, ground.frame, body.frame)
    ms.add_nonholonomic_constraints(blade.vel(ground.frame).dot(body.z))
    ms.add_loads((body.masscenter, -c * body.masscenter.vel(ground.frame)))
    return ms


def _plane_point():
    """A point P at (x, y) in the plane of N moving with speeds (u_x, u_y) from a point O
    at rest: (x, y, u_x, u_y, N, O, P)."""
    x, y = dynamicsymbols("x y")
    ux, uy = dynamicsymbols("u_x u_y")
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x + y * N.y)
    P.set_vel(N, ux * N.x + uy * N.y)
    return x, y, ux, uy, N, O, P


def particle_on_circle():
    """A mechanics System with a configuration constraint: a particle on a circle of
    radius ell in gravity, coordinates x (independent), y (dependent)."""
    x, y, ux, uy, N, O, P = _plane_point()
    ms = MechanicsSystem(N, O)
    ms.add_coordinates(x)
    ms.add_coordinates(y, independent=False)
    ms.add_speeds(ux)
    ms.add_speeds(uy, independent=False)
    ms.add_kdes(x.diff() - ux, y.diff() - uy)
    ms.add_bodies(Particle("P", P, m))
    ms.add_holonomic_constraints(x**2 + y**2 - ell**2)
    ms.add_loads((P, -m * g * N.y))
    return ms


@pytest.fixture(scope="module")
def disc():
    km = rolling_disc()
    return km, jn.from_mechanics(km)


@pytest.fixture(scope="module")
def cart():
    ms = cart_pendulum()
    return ms, jn.from_mechanics(ms)


# ---------------------------------------------------------------------- agreement
def test_rolling_disc_agrees_with_kane(disc):
    km, s = disc
    assert s.speeds.names == ("u1", "u2", "u3", "u4", "u5")
    q1, q2, q3 = s.J.q[:3]
    q1_t, q2_t, q3_t = s.J.qd[:3]
    # the speeds are the body-frame angular velocity, read through the kinematic equations
    assert [sp.expand(e) for e in s.speeds.of_velocities[:3]] == [
        q2_t, q1_t * sp.sin(q2) + q3_t, q1_t * sp.cos(q2)]
    # gravity is potential here: it enters L, not the forces
    assert not s.forces and s.L.has(g)
    assert sp.expand(s.L.xreplace(dict.fromkeys(s.J.qd, 0)) + m * g * r * sp.cos(q2)) == 0
    assert not s.is_integrable()
    assert agreement(s, km, {r: 0.7, m: 1.3, g: 9.81}, points=3) < RTOL


def test_joint_built_system_with_loads_that_are_not_potential(cart):
    ms, s = cart
    s_, th = s.J.q
    # the damper and the torque are generalized forces; gravity is potential
    assert set(s.forces) == {s_, th} and not s.L.xreplace(dict.fromkeys(s.J.qd, 0)).has(c)
    assert sp.expand(s.forces[th] - tau) == 0
    assert agreement(s, ms, {M: 2.0, m: 0.7, ell: 1.1, g: 9.81, c: 0.3, tau: 0.4}) < RTOL


def test_joint_built_sleigh_with_a_nonholonomic_constraint():
    ms = planar_sleigh()
    s = jn.from_mechanics(ms)
    assert len(s.constraints) == 1 and not s.is_integrable() and s.forces
    assert agreement(s, ms, {m: 1.5, a: 0.4, c: 0.2}, seed=2) < RTOL


def test_configuration_constraints_agree_on_the_circle():
    ms = particle_on_circle()
    s = jn.from_mechanics(ms)
    x, y = s.J.q
    # the configuration constraint stays holonomic; the equations use its derivative
    assert s.holonomic == (x**2 + y**2 - ell**2,)
    assert len(s.constraints) == 1 and sp.expand(
        s.constraints[0] - 2 * (x * s.J.qd[0] + y * s.J.qd[1])) == 0
    assert s.is_integrable()

    def on_circle(rnd):
        phi = rnd.uniform(0.3, 1.3)
        return [1.1 * math.cos(phi), 1.1 * math.sin(phi)]

    assert agreement(s, ms, {m: 0.8, ell: 1.1, g: 9.81}, sample_q=on_circle) < RTOL
    # a start off the circle, keyed by the model's dynamicsymbols, is refused with the fix
    xs, ys = dynamicsymbols("x y")
    with pytest.raises(JetnhError, match="off the holonomic constraints.*complete=True"):
        jn.Scene(s, "chetaev", params={m: 1.0, ell: 1.0, g: 9.81},
                 initial={xs: 0.6, ys: 0.0, xs.diff(): 0.0})


def test_kanes_method_velocity_constraints_that_restate_the_configuration_constraint():
    """A KanesMethod's velocity constraints include D g; jetnh keeps D g once."""
    km = _on_circle_with(lambda x, y, ux, uy: x * ux + y * uy)
    s = jn.from_mechanics(km)
    X, Y = s.J.q
    assert s.holonomic == (X**2 + Y**2 - ell**2,)
    assert len(s.constraints) == 1 and s.is_integrable()
    assert agreement(s, km, {m: 0.8, ell: 1.1, g: 9.81},
                     sample_q=lambda rnd: [1.1 * math.cos(0.7), 1.1 * math.sin(0.7)]) < RTOL


# ---------------------------------------------------------------------- random rotations
ORDERS = ["123", "231", "312", "132", "213", "321", "121", "131", "212", "232", "313", "323"]


def heavy_top(kind, order, mix):
    """A rigid body pivoted at a fixed point, oriented by the rotation ``order`` (body- or
    space-fixed: ``kind``); its speeds are mix . (its angular velocity in body components)
    and a linear drag torque acts on it."""
    q = dynamicsymbols("q1:4")
    u = dynamicsymbols("u1:4")
    N = ReferenceFrame("N")
    B = ReferenceFrame("B")
    getattr(B, f"orient_{kind}_fixed")(N, q, order)
    comps = sp.Matrix(mix) * B.ang_vel_in(N).to_matrix(B)
    kd = [comps[i] - u[i] for i in range(3)]
    w = sp.Matrix(mix).LUsolve(sp.Matrix(u))
    B.set_ang_vel(N, w[0] * B.x + w[1] * B.y + w[2] * B.z)
    O = Point("O")
    O.set_vel(N, 0)
    G = O.locatenew("G", a * B.z + a / 3 * B.x)
    G.v2pt_theory(O, N, B)
    body = RigidBody("top", G, B, m, (inertia(B, 1, sp.Rational(3, 2), 2, sp.Rational(1, 5)), G))
    km = KanesMethod(N, q, u, kd_eqs=kd)
    km.kanes_equations([body], [(G, -m * g * N.z), (B, -c * B.ang_vel_in(N))])
    return km


@settings(max_examples=5)
@given(st.sampled_from(["body", "space"]), st.sampled_from(ORDERS),
       st.lists(st.integers(-2, 2), min_size=9, max_size=9), st.integers(0, 2**16))
def test_random_rotation_parametrised_speeds(kind, order, entries, seed):
    mix = sp.Matrix(3, 3, entries) + 5 * sp.eye(3)       # diagonally dominant: invertible
    km = heavy_top(kind, order, mix)
    s = jn.from_mechanics(km)
    # the speeds map both ways: U(V(u)) = u
    back = [e.xreplace(dict(zip(s.J.qd, s.speeds.velocities))) for e in s.speeds.of_velocities]
    rnd = random.Random(seed)
    pt = {q: rnd.uniform(0.3, 1.2) for q in s.J.q}
    pt.update({u: rnd.uniform(-1, 1) for u in s.speeds.symbols})
    assert all(abs(dag.evaluate(b, pt) - pt[u]) < 1e-20 for b, u in zip(back, s.speeds.symbols))
    # gravity is potential, the drag is a generalized force
    assert s.L.has(g) and s.forces and not any(Q.has(g) for Q in s.forces.values())
    # Euler angles away from their singular sets (middle angle in (0.3, 1.2))
    sample = lambda rnd: [rnd.uniform(-1, 1), rnd.uniform(0.3, 1.2), rnd.uniform(-1, 1)]  # noqa: E731
    assert agreement(s, km, {m: 1.2, a: 0.5, g: 9.81, c: 0.3}, sample_q=sample, points=1,
                     seed=seed) < RTOL


# ---------------------------------------------------------------------- loads: V or forces
# The terms of a load on a particle in polar coordinates (r, th), as (name, force in the
# inertial frame, its potential written by hand or None); each term has its own parameter.
def _polar_terms(N, P, r_, th_, e_r, e_th):
    k = sp.symbols("k_0:7", positive=True)
    return [
        ("spring", -k[0] * (r_ - ell) * e_r, k[0] * (r_ - ell) ** 2 / 2),
        ("gravity", -k[1] * N.y, k[1] * r_ * sp.sin(th_)),
        ("pendulum", -k[2] * sp.sin(th_) / r_ * e_th, -k[2] * sp.cos(th_)),
        ("torsion", -k[3] * th_ / r_ * e_th, k[3] * th_**2 / 2),
        ("torque", k[4] / r_ * e_th, -k[4] * th_),
        ("damper", -k[5] * P.vel(N), None),
        ("curl", k[6] * r_ * e_th, None),
    ]


def _polar_particle(loads):
    """A particle in polar coordinates under ``loads`` (lists of term names); the
    KanesMethod, its System and the terms."""
    r_, th_, ur, uth = dynamicsymbols("r th u_r u_th")
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    e_r, e_th = sp.cos(th_) * N.x + sp.sin(th_) * N.y, -sp.sin(th_) * N.x + sp.cos(th_) * N.y
    P = O.locatenew("P", r_ * e_r)
    P.set_vel(N, ur * e_r + r_ * uth * e_th)
    terms = {name: (F, V) for name, F, V in _polar_terms(N, P, r_, th_, e_r, e_th)}
    km = KanesMethod(N, q_ind=[r_, th_], u_ind=[ur, uth],
                     kd_eqs=[r_.diff() - ur, th_.diff() - uth])
    km.kanes_equations([Particle("P", P, m)],
                       [(P, sum((terms[n][0] for n in load), 0 * N.x)) for load in loads])
    return km, jn.from_mechanics(km), terms


def _is_potential(load) -> bool:
    """The rule: a load becomes V when V stands for its forces (no damper, no curl) and is
    a function of the configuration wherever its forces are: a torque on th does work
    2 pi tau a turn unless a torsion spring already makes the forces no function of the
    angle."""
    return (not {"damper", "curl"} & set(load)
            and not ("torque" in load and "torsion" not in load))


def _vanish(exprs, seed) -> bool:
    """Whether ``exprs`` vanish at three random points, in 30 digits (L is not
    trig-simplified: sin^2 + cos^2 stays)."""
    rnd = random.Random(seed)
    free = set().union(*(sp.sympify(e).free_symbols for e in exprs))
    for _ in range(3):
        point = {s: sp.Float(rnd.uniform(0.5, 1.5), PREC) for s in free}
        if any(abs(complex(v)) > 1e-24 for v in dag.evaluate(list(exprs), point, PREC)):
            return False
    return True


_TERM_NAMES = ["spring", "gravity", "pendulum", "torsion", "torque", "damper", "curl"]


@settings(max_examples=8, deadline=None, phases=[Phase.explicit, Phase.generate])
@given(st.lists(st.lists(st.sampled_from(_TERM_NAMES), min_size=1, max_size=4, unique=True),
                min_size=1, max_size=3),
       st.integers(0, 2**16))
def test_random_loads_become_potentials_by_one_rule(loads, seed):
    """Random sums of conservative and non-conservative loads: the equations equal
    KanesMethod's (route 2), L = T - V with V the hand-written potentials of exactly the
    loads the rule names (up to a constant), the other loads' generalized forces in
    ``forces`` (route 3: the sum of all of them, by hand, is -dV/dq + forces), and the
    energy is conserved exactly when every load is a potential."""
    km, S, terms = _polar_particle(loads)
    J = S.J
    (R, TH), (R_t, TH_t) = J.q, J.qd
    dyn = dict(zip(dynamicsymbols("r th"), J.q))
    as_jet = lambda e: sp.sympify(e).xreplace(dyn)    # noqa: E731
    V_hand = sum((as_jet(terms[n][1]) for load in loads if _is_potential(load)
                  for n in load), sp.S.Zero)
    T = m * (R_t**2 + R**2 * TH_t**2) / 2
    V = T - S.L
    assert _vanish([sp.diff(V - V_hand, q) for q in J.q], seed)
    # every load's generalized forces, by hand: F . dr/dq (the damper: -c qdot . dr/dq)
    pos = sp.Matrix([R * sp.cos(TH), R * sp.sin(TH), 0])
    vel = pos.jacobian(J.q) * sp.Matrix(J.qd)
    N = km._inertial
    total = [sp.S.Zero, sp.S.Zero]
    for load in loads:
        for n in load:
            F = terms[n][0]
            Fv = (sp.Matrix([as_jet(c) for c in F.to_matrix(N)]) if n != "damper"
                  else -sp.Symbol("k_5", positive=True) * vel)
            total = [a + (Fv.T * pos.diff(q))[0] for a, q in zip(total, J.q)]
    got = [-sp.diff(V, q) + S.forces.get(q, 0) for q in J.q]
    assert _vanish([a - b for a, b in zip(got, total)], seed)
    params = {ell: 1.1, m: 0.9, **{sp.Symbol(f"k_{i}", positive=True): 0.3 + 0.2 * i
                                   for i in range(7)}}
    rnd = random.Random(seed)
    assert agreement(S, km, params, points=2, seed=seed,
                     sample_q=lambda _: [rnd.uniform(0.5, 1.5), rnd.uniform(-3, 3)]) < RTOL
    reasons = changes(S, "chetaev", {p.name: v for p, v in params.items()})
    assert bool(reasons) == (not all(_is_potential(load) for load in loads))


# ---------------------------------------------------------------------- speeds on runs
def test_speeds_read_along_a_run(cart):
    ms, s = cart
    th, s_ = dynamicsymbols("theta s")
    scene = jn.Scene(s, "chetaev", params={M: 2.0, m: 0.7, ell: 1.1, g: 9.81, c: 0.3, tau: 0.0},
                     initial={s_: 0.0, th: 0.3, s_.diff(): 0.0, th.diff(): 0.0}, t_span=(0, 1))
    traj = scene.run(method="rk4", n_steps=200)
    u = s.speeds.read(traj)
    assert np.array_equal(u["omega"], traj["theta_t"]) and np.array_equal(u["v"], traj["s_t"])
    # dynamicsymbol keys give the same run as names
    by_name = jn.Scene(s, "chetaev", params={"M": 2.0, "m": 0.7, "ell": 1.1, "g": 9.81,
                                             "c": 0.3, "tau": 0.0},
                       initial={"s": 0.0, "theta": 0.3, "s_t": 0.0, "theta_t": 0.0},
                       t_span=(0, 1)).run(method="rk4", n_steps=200)
    assert np.array_equal(traj.y, by_name.y)
    assert np.array_equal(traj[th.diff()], by_name["theta_t"])
    again = scene.run(method="rk4", n_steps=200, y0={th: 0.3, s_.diff(): 0.0})
    assert np.array_equal(again.y, traj.y)


# ---------------------------------------------------------------------- refusals
def test_refusals_name_the_fix():
    with pytest.raises(JetnhError, match="LagrangesMethod, KanesMethod or System.*jetnh System"):
        jn.from_mechanics(sp.Matrix([1]))
    # a specified input r(t) in a load
    x, ux, f = dynamicsymbols("x u_x f")
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x)
    P.set_vel(N, ux * N.x)
    km = KanesMethod(N, [x], [ux], kd_eqs=[x.diff() - ux])
    km.kanes_equations([Particle("P", P, m)], [(P, f * N.x)])
    with pytest.raises(JetSpaceError, match="load on the point P.*substitute specified inputs"):
        jn.from_mechanics(km)
    # a contact point set at rest: the rolling constraint built into the kinematics
    q, u, A, C, D = _pivoted(N, "q u", r)
    km = KanesMethod(N, [q], [u], kd_eqs=[q.diff() - u])
    km.kanes_equations([Particle("D", D, m)], [])
    jn.from_mechanics(km)      # a point at rest that is a true pivot is fine
    Q = Point("Q")             # a point with a velocity but no position
    Q.set_vel(N, u * r * N.x)
    km = KanesMethod(N, [q], [u], kd_eqs=[q.diff() - u])
    km.kanes_equations([Particle("Q", Q, m)], [])
    with pytest.raises(JetnhError, match="not located from a point at rest.*velocity constraints"):
        jn.from_mechanics(km)
    # a velocity that is not the derivative of the position (rolling built in)
    E = O.locatenew("E", q * N.x)
    E.set_vel(N, 2 * u * N.x)
    km = KanesMethod(N, [q], [u], kd_eqs=[q.diff() - u])
    km.kanes_equations([Particle("E", E, m)], [])
    with pytest.raises(JetnhError, match="not the time derivative of its position"):
        jn.from_mechanics(km)
    # sympy's minimal rolling disc: the contact point set at rest builds the rolling
    # into the kinematics, which then hold only while rolling
    q1, q2, q3 = dynamicsymbols("q1:4")
    w1, w2, w3 = dynamicsymbols("w1:4")
    Yf = N.orientnew("Yf", "Axis", [q1, N.z])
    Lf = Yf.orientnew("Lf", "Axis", [q2, Yf.x])
    Rf = Lf.orientnew("Rf", "Axis", [q3, Lf.y])
    kd = [dot(Rf.ang_vel_in(N) - (w1 * Lf.x + w2 * Lf.y + w3 * Lf.z), e) for e in Lf]
    Rf.set_ang_vel(N, w1 * Lf.x + w2 * Lf.y + w3 * Lf.z)
    Cf = Point("Cf")
    Cf.set_vel(N, 0)
    Dmc = Cf.locatenew("Dmc", r * Lf.z)
    Dmc.v2pt_theory(Cf, N, Rf)
    km = KanesMethod(N, [q1, q2, q3], [w1, w2, w3], kd_eqs=kd)
    km.kanes_equations([RigidBody("disc", Dmc, Rf, m, (inertia(Lf, 1, 2, 1), Dmc))],
                       [(Dmc, -m * g * N.z)])
    with pytest.raises(JetnhError, match="velocity of Dmc.*not the time derivative.*"
                                         "velocity constraint"):
        jn.from_mechanics(km)
    # a body potential energy that KanesMethod would not read
    ms = particle_on_circle()
    ms.bodies[0].potential_energy = m * g * dynamicsymbols("y")
    with pytest.raises(JetnhError, match="potential_energy.*apply_uniform_gravity"):
        jn.from_mechanics(ms)
    # no bodies yet
    with pytest.raises(JetnhError, match="kanes_equations"):
        jn.from_mechanics(KanesMethod(N, [q], [u], kd_eqs=[q.diff() - u]))


def test_dynamicsymbols_name_their_jet_coordinates():
    from jetnh.geometry.jet import key_name

    x = dynamicsymbols("x")
    assert [key_name(k) for k in (x, x.diff(), x.diff(dynamicsymbols._t, 2), sp.Symbol("x"),
                                  "x_t")] == ["x", "x_t", "x_tt", "x", "x_t"]
    y = sp.Function("y")
    assert key_name(y(sp.Symbol("s"))) is None and key_name(x + 1) is None and key_name(3) is None
    # the refusal of a key that names nothing says what keys are
    s = jn.System(jn.JetSpace("x"), sp.Symbol("x_t") ** 2 / 2)
    with pytest.raises(JetnhError, match="keyed by Symbol, by name or by dynamicsymbol"):
        jn.Scene(s, "chetaev", initial={x + 1: 0.0, "x_t": 1.0})


def test_speeds_survive_another_split(disc):
    _, s = disc
    other = s.with_split(["x", "q3"])
    assert other.speeds is s.speeds and other.dependent != s.dependent


# ---------------------------------------------------------------------- read end to end
def _pivoted(N, names, length):
    """A frame turned about N.z by the angle q at the rate u (``names``: "q u"), a point at
    rest and a point ``length`` from it along the frame's x: (q, u, frame, pivot, point)."""
    q, u = dynamicsymbols(names)
    A = N.orientnew("A", "Axis", [q, N.z])
    A.set_ang_vel(N, u * N.z)
    C = Point("C")
    C.set_vel(N, 0)
    D = C.locatenew("D", length * A.x)
    D.v2pt_theory(C, N, A)
    return q, u, A, C, D


def test_inertia_about_the_pivot_agrees_with_kane():
    """A RigidBody whose inertia is given about a point other than its mass centre (the
    pivot): T holds the central inertia plus m |r|^2 (route 2: Kane)."""
    N = ReferenceFrame("N")
    th, w, B, O, G = _pivoted(N, "th w", ell)
    km = KanesMethod(N, [th], [w], kd_eqs=[th.diff() - w])
    km.kanes_equations([RigidBody("b", G, B, m, (inertia(B, 0, 0, m * ell**2 + a), O))],
                       [(G, -m * g * N.y)])
    s = jn.from_mechanics(km)
    TH, TH_t = s.J.q[0], s.J.qd[0]
    assert sp.expand(s.L - ((m * ell**2 + a) * TH_t**2 / 2 - m * g * ell * sp.sin(TH))) == 0
    assert agreement(s, km, {m: 1.2, g: 9.81, ell: 0.7, a: 0.3}) < RTOL


def _on_circle_with(velocity_constraint):
    x, y, ux, uy, N, O, P = _plane_point()
    km = KanesMethod(N, [x], [ux], kd_eqs=[x.diff() - ux, y.diff() - uy], q_dependent=[y],
                     configuration_constraints=[x**2 + y**2 - ell**2], u_dependent=[uy],
                     velocity_constraints=[velocity_constraint(x, y, ux, uy)])
    km.kanes_equations([Particle("P", P, m)], [(P, -m * g * N.y)])
    return km


def test_a_velocity_constraint_that_is_not_the_derivative_of_the_configuration_is_refused():
    """x u_x + y u_y + c = 0 with x^2 + y^2 = l^2: the velocity constraint has the
    direction of D g but not its value; leaving it out (as a restatement of D g) would
    give motions on the circle where Kane's leave it."""
    with pytest.raises(JetnhError, match="velocity constraint 1.*not.*configuration"):
        jn.from_mechanics(_on_circle_with(lambda x, y, ux, uy: x * ux + y * uy + c))
    # the restatement, scaled, is left out
    s = jn.from_mechanics(_on_circle_with(lambda x, y, ux, uy: 3 * (x * ux + y * uy)))
    assert len(s.constraints) == 1 and len(s.holonomic) == 1


def test_a_rigid_body_of_the_deprecated_body_class_is_checked_as_rigid():
    """sympy's Body is a RigidBody and a Particle; a rigid one's angular velocity is
    checked against its orientation as a RigidBody's is."""
    import warnings

    th, w = dynamicsymbols("th w")
    N = ReferenceFrame("N")
    B = N.orientnew("B", "Axis", [th, N.z])
    B.set_ang_vel(N, 2 * w * N.z)          # not the orientation's
    O = Point("O")
    O.set_vel(N, 0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from sympy.physics.mechanics import Body
        body = Body("b", O, m, B, inertia(B, 1, 1, 1))
    km = KanesMethod(N, [th], [w], kd_eqs=[th.diff() - w])
    km.kanes_equations([body], [])
    with pytest.raises(JetnhError, match="angular velocity of B.*orientation"):
        jn.from_mechanics(km)


def test_a_frame_without_an_orientation_is_refused_with_the_fix():
    th, w = dynamicsymbols("th w")
    N = ReferenceFrame("N")
    B = ReferenceFrame("B")
    B.set_ang_vel(N, w * N.z)
    O = Point("O")
    O.set_vel(N, 0)
    # (kanes_equations fails on it too; the import reads bodies given to KanesMethod)
    km = KanesMethod(N, [th], [w], kd_eqs=[th.diff() - w],
                     bodies=[RigidBody("b", O, B, m, (inertia(B, 1, 1, 1), O))])
    with pytest.raises(JetnhError, match="orientation of B.*orient"):
        jn.from_mechanics(km)


def test_a_body_potential_energy_in_a_kanes_method_is_refused():
    """KanesMethod does not read a body's potential_energy: refused as for a mechanics
    System (before: dropped without a word)."""
    x, ux = dynamicsymbols("x u_x")
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x)
    P.set_vel(N, ux * N.x)
    pa = Particle("P", P, m)
    pa.potential_energy = c * x**2 / 2
    km = KanesMethod(N, [x], [ux], kd_eqs=[x.diff() - ux])
    km.kanes_equations([pa], [])
    with pytest.raises(JetnhError, match="potential_energy.*load"):
        jn.from_mechanics(km)


def test_an_actuators_loads_are_judged_together():
    """A torsion spring between two frames (TorqueActuator: a torque on one, its reaction
    on the other) is conservative only as a whole: V = k q2^2 / 2 (before: each load
    alone has no symmetric Jacobian, two generalized forces); route 2: Kane."""
    q1, q2 = dynamicsymbols("q1 q2")
    w1, w2 = dynamicsymbols("w1 w2")
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    A = N.orientnew("A", "Axis", [q1, N.z])
    A.set_ang_vel(N, w1 * N.z)
    B = A.orientnew("B", "Axis", [q2, A.z])
    B.set_ang_vel(A, w2 * A.z)
    ms = MechanicsSystem(N, O)
    ms.add_coordinates(q1, q2)
    ms.add_speeds(w1, w2)
    ms.add_kdes(q1.diff() - w1, q2.diff() - w2)
    ms.add_bodies(RigidBody("a", O, A, m, (inertia(A, 1, 1, 1), O)),
                  RigidBody("b", O, B, m, (inertia(B, 1, 1, 2), O)))
    ms.add_actuators(TorqueActuator(-c * q2, N.z, B, A))
    s = jn.from_mechanics(ms)
    Q1, Q2 = s.J.q
    assert not s.forces
    assert sp.expand(s.L.xreplace(dict.fromkeys(s.J.qd, 0)) + c * Q2**2 / 2) == 0
    assert agreement(s, ms, {c: 2.0, m: 1.3}) < RTOL


def test_kinematic_equations_not_linear_are_refused_as_such():
    """x' = u^3 (a mechanics System reads its kdes raw): refused naming linearity, not
    as an unknown function of time u(t)."""
    x, u = dynamicsymbols("x u")
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x)
    P.set_vel(N, x.diff() * N.x)
    ms = MechanicsSystem(N, O)
    ms.add_coordinates(x)
    ms.add_speeds(u)
    ms.add_kdes(x.diff() - u**3)
    ms.add_bodies(Particle("P", P, m))
    with pytest.raises(JetnhError, match="not linear in the speeds"):
        jn.from_mechanics(ms)


def test_contact_forces_of_auxiliary_speeds_do_no_work():
    """KanesMethod's auxiliary speeds: contact forces f(t) (unknowns, functions of time)
    on a point moved only by them, and a normal force on a particle sliding along N.x,
    do no work in the equations; the import reads them as Kane does (before: refused
    as specified inputs).  Route 2: Kane."""
    x, ux, ua, ub = dynamicsymbols("x u_x u_a u_b")
    f1, f2 = dynamicsymbols("f1 f2")
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x)
    P.set_vel(N, ux * N.x + ua * N.y)
    C = O.locatenew("C", 0 * N.x)
    C.set_vel(N, ub * N.x)
    km = KanesMethod(N, [x], [ux], kd_eqs=[x.diff() - ux], u_auxiliary=[ua, ub])
    km.kanes_equations([Particle("P", P, m)],
                       [(P, -c * x * N.x + f1 * N.y), (C, f2 * N.x), (P, -m * g * N.y)])
    s = jn.from_mechanics(km)
    X, X_t = s.J.q[0], s.J.qd[0]
    assert not s.forces and sp.expand(s.L - (m * X_t**2 / 2 - c * X**2 / 2)) == 0
    assert agreement(s, km, {m: 1.2, c: 0.4, g: 9.81}) < RTOL
    # a specified input along a direction the point moves is still refused
    Q = O.locatenew("Q", x * N.x)
    Q.set_vel(N, ux * N.x)
    km = KanesMethod(N, [x], [ux], kd_eqs=[x.diff() - ux])
    km.kanes_equations([Particle("Q", Q, m)], [(Q, f1 * N.x)])
    with pytest.raises(JetSpaceError, match="load on the point Q.*substitute specified"):
        jn.from_mechanics(km)


def _spring_on_plane(spring, anchor_of_t=None):
    """A particle in the plane (x, y) and ``spring(A, P)``: its actuator between an anchor
    A (at rest at O, or at ``anchor_of_t`` N.x) and the particle P."""
    from sympy.physics.mechanics import LinearPathway

    x, y, ux, uy = dynamicsymbols("x y u_x u_y")
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x + y * N.y)
    P.set_vel(N, ux * N.x + uy * N.y)
    A = O
    if anchor_of_t is not None:
        A = O.locatenew("A", anchor_of_t * N.x)
        A.set_vel(N, anchor_of_t.diff(dynamicsymbols._t) * N.x)
    ms = MechanicsSystem(N, O)
    ms.add_coordinates(x, y)
    ms.add_speeds(ux, uy)
    ms.add_kdes(x.diff() - ux, y.diff() - uy)
    ms.add_bodies(Particle("P", P, m))
    ms.add_actuators(spring(LinearPathway(A, P)))
    return ms


def test_a_springs_potential_is_taken_from_its_actuator(monkeypatch):
    """A LinearSpring states V = k (L - l)^2 / 2 of its pathway's length: taken without
    integrating (route 1: it equals the integrated V up to a constant; route 2: Kane)."""
    from sympy.physics.mechanics import LinearSpring

    from jetnh.mechanics import kane_bridge

    ms = _spring_on_plane(lambda path: LinearSpring(c, path, ell))
    integrated = []
    monkeypatch.setattr(kane_bridge, "_bounded", lambda *a: integrated.append(a))
    s = jn.from_mechanics(ms)
    X, Y = s.J.q
    V = -s.L.xreplace(dict.fromkeys(s.J.qd, 0))
    assert not s.forces and not integrated
    assert sp.expand(V - c * (sp.sqrt(X**2 + Y**2) - ell) ** 2 / 2) == 0
    assert agreement(s, ms, {c: 2.0, ell: 0.7, m: 1.3}) < RTOL
    monkeypatch.undo()
    monkeypatch.setattr(kane_bridge, "_spring", lambda actuator: None)
    by_integral = jn.from_mechanics(_spring_on_plane(lambda path: LinearSpring(c, path, ell)))
    assert not by_integral.forces
    W = -by_integral.L.xreplace(dict.fromkeys(s.J.qd, 0))
    assert W != V and all(sp.expand(sp.diff(V - W, q)) == 0 for q in s.J.q)


def test_a_duffing_springs_potential_is_taken_from_its_actuator():
    """DuffingSpring (a x + b x^3, x = L - l): V = a x^2 / 2 + b x^4 / 4; route 2: Kane."""
    import sympy.physics.mechanics as me

    if not hasattr(me, "DuffingSpring"):
        pytest.skip("sympy < 1.13 has no DuffingSpring")
    ms = _spring_on_plane(lambda path: me.DuffingSpring(c, a, path, ell))
    s = jn.from_mechanics(ms)
    X, Y = s.J.q
    x = sp.sqrt(X**2 + Y**2) - ell
    assert not s.forces
    assert sp.expand(s.L.xreplace(dict.fromkeys(s.J.qd, 0)) + c * x**2 / 2 + a * x**4 / 4) == 0
    assert agreement(s, ms, {c: 2.0, a: 0.3, ell: 0.7, m: 1.3}) < RTOL


def test_a_spring_on_an_anchor_in_prescribed_motion_stays_a_force():
    """The spring's load depends on t (its anchor moves as sin t): no V(q) stands for it,
    so the actuator's potential is not taken and the load stays a force; route 2: Kane."""
    from sympy.physics.mechanics import LinearSpring

    t = dynamicsymbols._t
    ms = _spring_on_plane(lambda path: LinearSpring(c, path, ell), anchor_of_t=sp.sin(t))
    s = jn.from_mechanics(ms)
    assert set(map(str, s.forces)) == {"x", "y"}
    assert agreement(s, ms, {c: 2.0, ell: 0.7, m: 1.3}) < RTOL


def _chain_on_a_line(spring):
    """Two particles on a line (q1, q2) and ``spring(P1, P2)``: its actuator between
    them (the textbook two-mass chain)."""
    from sympy.physics.mechanics import LinearPathway

    q1, q2, u1, u2 = dynamicsymbols("q1 q2 u1 u2")
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    P1 = O.locatenew("P1", q1 * N.x)
    P1.set_vel(N, u1 * N.x)
    P2 = O.locatenew("P2", q2 * N.x)
    P2.set_vel(N, u2 * N.x)
    ms = MechanicsSystem(N, O)
    ms.add_coordinates(q1, q2)
    ms.add_speeds(u1, u2)
    ms.add_kdes(q1.diff() - u1, q2.diff() - u2)
    ms.add_bodies(Particle("P1", P1, m), Particle("P2", P2, M))
    ms.add_actuators(spring(LinearPathway(P1, P2)))
    return ms


@pytest.mark.parametrize("kind", ["linear", "duffing"])
def test_a_spring_on_a_line_takes_its_actuators_potential(monkeypatch, kind):
    """On a line the pathway's length is sqrt(w^2) (w = q2 - q1), whose derivative has
    1 / w^2 where the load has sqrt(w^2): the same zeros, so the actuator's V is taken
    (no integration, which gives no V here); route 2: Kane."""
    import sympy.physics.mechanics as me

    from jetnh.mechanics import kane_bridge

    if kind == "duffing" and not hasattr(me, "DuffingSpring"):
        pytest.skip("sympy < 1.13 has no DuffingSpring")
    spring = ((lambda path: me.LinearSpring(c, path, ell)) if kind == "linear"
              else (lambda path: me.DuffingSpring(c, a, path, ell)))
    integrated = []
    monkeypatch.setattr(kane_bridge, "_bounded", lambda *args: integrated.append(args))
    ms = _chain_on_a_line(spring)
    s = jn.from_mechanics(ms)
    Q1, Q2 = s.J.q
    x = sp.sqrt((Q2 - Q1) ** 2) - ell
    V = c * x**2 / 2 + (a * x**4 / 4 if kind == "duffing" else 0)
    assert not s.forces and not integrated
    assert sp.expand(s.L.xreplace(dict.fromkeys(s.J.qd, 0)) + V) == 0
    assert agreement(s, ms, {c: 2.0, a: 0.3, ell: 0.7, m: 1.3, M: 0.8}) < RTOL
