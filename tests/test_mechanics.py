"""The bridge to sympy.physics.mechanics: ``from_mechanics`` / ``to_mechanics``.

Route 1: jetnh's Chetaev accelerations of ``from_mechanics(lm)``.  Route 2: LagrangesMethod's
own equations, ``mass_matrix_full x = forcing_full`` with x = (q', q'', lambda), solved in
30-digit arithmetic at random states on the constraint manifold.
"""

from __future__ import annotations

import random

import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st
from sympy.physics.mechanics import (LagrangesMethod, Lagrangian, Point, ReferenceFrame,
                                     RigidBody, dynamicsymbols, inertia)

import jetnh as jn
import jetnh.strategies as jst
from jetnh import models
from jetnh.errors import JetnhError, JetSpaceError
from jetnh.mechanics.sympy_bridge import generalized_forces, to_mechanics

PREC = 30
RTOL = 1e-20


def manifold_point(system, rnd, params):
    """t, q, independent velocities at random; dependent velocities from phi."""
    J = system.J
    vals = {p: sp.Float(v, PREC) for p, v in params.items()}
    vals[J.t] = sp.Float(rnd.uniform(-1, 1), PREC)
    for s in J.q + system.independent_velocities:
        vals[s] = sp.Float(rnd.uniform(-1, 1), PREC)
    for v, phi in system.phi.items():
        vals[v] = phi.xreplace(vals).evalf(PREC)
    return vals


def lagranges_method_qdd(lm, J, vals):
    """q'' from LagrangesMethod's mass_matrix_full and forcing_full at ``vals``."""
    if lm.eom is None:
        lm.form_lagranges_equations()
    n = J.n
    M = lm.mass_matrix_full.applyfunc(J.from_dynamic).xreplace(vals).evalf(PREC)
    F = lm.forcing_full.applyfunc(J.from_dynamic).xreplace(vals).evalf(PREC)
    x = M.LUsolve(F)
    return [x[n + s] for s in range(n)]


def assert_chetaev_matches(system, lm, params, points=3, seed=0):
    acc = system.equations("chetaev").accelerations()
    J = system.J
    rnd = random.Random(seed)
    for _ in range(points):
        vals = manifold_point(system, rnd, params)
        ref = lagranges_method_qdd(lm, J, vals)
        for s, a in enumerate(J.qdd):
            va = acc[a].xreplace(vals).evalf(PREC)
            assert abs(va - ref[s]) <= RTOL * max(1, abs(ref[s])), (a, va, ref[s])


# ---------------------------------------------------------------------- models
m, I, a, R, I1, I2, g, ell = sp.symbols("m I a R I1 I2 g ell", positive=True)


def sleigh(forces=()):
    """The Chaplygin sleigh as a mechanics model: a rigid body, its blade at P."""
    x, y, th = dynamicsymbols("x y theta")
    N = ReferenceFrame("N")
    B = N.orientnew("B", "Axis", [th, N.z])
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x + y * N.y)
    P.set_vel(N, P.pos_from(O).dt(N))
    G = P.locatenew("G", a * B.x)
    G.v2pt_theory(P, N, B)
    body = RigidBody("body", G, B, m, (inertia(B, 0, 0, I), G))
    loads = [f(N, B, P) for f in forces]
    return LagrangesMethod(Lagrangian(N, body), [x, y, th],
                           nonhol_coneqs=[P.vel(N).dot(B.y)], forcelist=loads or None,
                           frame=N)


def rolling_disk():
    """The vertical rolling disk: heading psi, roll phi, contact point at rest."""
    x, y, phi, psi = dynamicsymbols("x y phi psi")
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [psi, N.z])
    D = A.orientnew("D", "Axis", [phi, A.y])
    O = Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", x * N.x + y * N.y)
    C.set_vel(N, C.pos_from(O).dt(N))
    disk = RigidBody("disk", C, D, 1, (I1 * (A.y | A.y) + I2 * ((A.x | A.x) + (A.z | A.z)), C))
    contact = C.vel(N) + D.ang_vel_in(N).cross(-R * A.z)
    return LagrangesMethod(Lagrangian(N, disk), [x, y, phi, psi],
                           nonhol_coneqs=[contact.dot(A.x), contact.dot(A.y)], frame=N)


def test_chaplygin_sleigh_from_mechanics():
    lm = sleigh()
    s = jn.from_mechanics(lm, dependent="y", name="sleigh")
    assert [q.name for q in s.J.q] == ["x", "y", "theta"] and s.name == "sleigh"
    x_t, y_t = s.J.qd[:2]
    theta = s.J.q[2]
    assert sp.simplify(s.constraints[0] - (y_t * sp.cos(theta) - x_t * sp.sin(theta))) == 0
    assert not s.is_integrable()
    assert_chetaev_matches(s, lm, {m: 1.3, I: 0.4, a: 0.7})


def test_rolling_disk_from_mechanics_matches_the_catalogue_model():
    lm = rolling_disk()
    s = jn.from_mechanics(lm, dependent=["x", "y"])
    params = {R: 1.2, I1: 0.5, I2: 0.3}
    assert_chetaev_matches(s, lm, params, points=2)
    # a third route: the catalogue's disk (explicit constraints, m = 1), same Chetaev q''
    cat = models.get("rolling_disk")
    by_name = {p.name: p for p in cat.parameters}
    acc, ref = s.equations("chetaev").accelerations(), cat.equations("chetaev").accelerations()
    vals = manifold_point(s, random.Random(5), params)
    cat_vals = {**vals, **{by_name[p.name]: v for p, v in vals.items() if p in params}}
    for q in s.J.qdd:
        d = acc[q].xreplace(vals).evalf(PREC) - ref[q].xreplace(cat_vals).evalf(PREC)
        assert abs(d) < 1e-20


def test_holonomic_constraints_enter_differentiated():
    x, y = dynamicsymbols("x y")
    xd, yd = dynamicsymbols("x y", 1)
    lm = LagrangesMethod(m * (xd**2 + yd**2) / 2 - m * g * y, [x, y],
                         hol_coneqs=[x**2 + y**2 - ell**2])
    s = jn.from_mechanics(lm)
    X, Y = s.J.q
    assert sp.expand(s.constraints[0] - (2 * X * s.J.qd[0] + 2 * Y * s.J.qd[1])) == 0
    assert s.holonomic == (X**2 + Y**2 - ell**2,)        # kept at position level too
    assert s.is_integrable()
    assert_chetaev_matches(s, lm, {m: 1.1, g: 9.81, ell: 1.0})
    # nonholonomic constraints first, then the differentiated holonomic ones
    z = dynamicsymbols("z")
    zd = dynamicsymbols("z", 1)
    lm2 = LagrangesMethod((xd**2 + yd**2 + zd**2) / 2, [x, y, z], hol_coneqs=[x - y],
                          nonhol_coneqs=[zd - y * xd])
    s2 = jn.from_mechanics(lm2)
    J = s2.J
    assert s2.constraints == (J.qd[2] - J.q[1] * J.qd[0], J.qd[0] - J.qd[1])
    assert s2.holonomic == (J.q[0] - J.q[1],) and s2.holonomic_rows == (1,)
    back = jn.from_mechanics(to_mechanics(s2))
    assert back.holonomic == s2.holonomic and back.constraints == s2.constraints


# ---------------------------------------------------------------------- random systems
@given(jst.systems(min_n=2, max_n=4, affine=None))
def test_round_trip_through_lagranges_method(s):
    back = jn.from_mechanics(to_mechanics(s), dependent=s.dependent)
    assert back.J == s.J and back.L == s.L and back.constraints == s.constraints
    assert back.dependent == s.dependent


@settings(max_examples=4)
@given(jst.constrained_systems(min_n=2, max_n=3, affine=True), st.integers(0, 2**16))
def test_random_affine_systems_match_lagranges_method(case, seed):
    J, L, constraints, dependent = case
    lm = LagrangesMethod(J.to_dynamic(L), [J.to_dynamic(q) for q in J.q],
                         nonhol_coneqs=[J.to_dynamic(f) for f in constraints])
    s = jn.from_mechanics(lm, dependent=dependent)
    assert_chetaev_matches(s, lm, {}, points=1, seed=seed)


# ---------------------------------------------------------------------- forces, refusals
F, T = sp.symbols("F T")


def test_forces_become_generalized_forces():
    pull = lambda N, B, P: (P, F * B.x)          # noqa: E731
    turn = lambda N, B, P: (B, T * N.z)          # noqa: E731
    lm = sleigh([pull, turn])
    forced = jn.from_mechanics(lm)
    assert_chetaev_matches(forced, lm, {m: 2, I: sp.Rational(3, 2), a: sp.Rational(1, 2),
                                        F: sp.Rational(3, 7), T: sp.Rational(-2, 5)},
                           points=2, seed=3)
    J = jn.from_mechanics(sleigh()).J
    Q = generalized_forces(lm, J)
    th = J.q[2]
    assert [sp.simplify(q - e) for q, e in zip(Q, [F * sp.cos(th), F * sp.sin(th), T])] == [0] * 3
    # second route: the forcing of LagrangesMethod with and without the loads differs by Q
    free = sleigh()
    for x in (lm, free):
        x.form_lagranges_equations()
    diff = (lm.forcing - free.forcing).applyfunc(J.from_dynamic)
    assert [sp.simplify(d - q) for d, q in zip(diff, Q)] == [0] * 3
    assert generalized_forces(free, J) == (0, 0, 0)
    assert forced.Q == Q


def test_refusals_name_the_problem():
    with pytest.raises(JetnhError, match="takes a sympy.physics.mechanics LagrangesMethod"):
        jn.from_mechanics(models.get("rolling_disk"))
    x = dynamicsymbols("x")
    u = dynamicsymbols("u")
    lm = LagrangesMethod(x.diff() ** 2 / 2 + u * x, [x])
    with pytest.raises(JetSpaceError, match="the Lagrangian of the LagrangesMethod.*substitute"):
        jn.from_mechanics(lm)


def test_to_mechanics_refuses_forces():
    with pytest.raises(JetnhError, match="generalized forces"):
        to_mechanics(models.get("damped_knife_edge"))
