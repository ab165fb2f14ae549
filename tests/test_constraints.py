"""System: split, explicit and affine forms, L~, T, classification, bad input."""

import pytest
import sympy as sp
from hypothesis import given, settings

import jetnh.strategies as jst
from jetnh import ConstraintError, JetSpace, JetSpaceError, LagrangianError
from jetnh.mechanics.system import System
from jetnh.mechanics.equivalence import frobenius_T
from jetnh.algebra.zero import vanishes
from jetnh.models import rolling_disk

R, I1, I2 = sp.symbols("R I1 I2")


def disk(dependent=("x", "y")):
    return rolling_disk().with_split(dependent)


def test_disk_explicit_affine_forms_and_T():
    s = disk()
    J = s.J
    x, y, phi, psi = J.q
    xd, yd, phid, psid = J.qd
    assert s.phi == {xd: R * sp.cos(psi) * phid, yd: R * sp.sin(psi) * phid}
    assert s.B == sp.Matrix([[0, R * sp.cos(psi), 0], [0, R * sp.sin(psi), 0]])
    assert sp.trigsimp(s.L_tilde - ((R**2 + I1) * phid**2 + I2 * psid**2) / 2) == 0
    T = s.T()
    psid_, phid_ = psid, phid
    assert sp.expand(T[0, 0] + R * sp.sin(psi) * psid_) == 0
    assert sp.expand(T[0, 1] - R * sp.sin(psi) * phid_) == 0
    assert sp.expand(T[1, 0] - R * sp.cos(psi) * psid_) == 0
    assert sp.expand(T[1, 1] + R * sp.cos(psi) * phid_) == 0
    c = s.classify()
    assert c.affine and not c.integrable and c.chaplygin and c.regular and not c.rheonomic


def test_auto_split_prefers_linear_constant_coefficients():
    J = JetSpace("x y z")
    x, y, z = J.q
    s = System(J, sum(v**2 for v in J.qd) / 2, [J.qd[2] - y * J.qd[0]])
    assert s.dependent == (z,) and s.independent == (x, y)


def test_rheonomic_split_has_no_spurious_singularity():
    J = JetSpace("x y")
    x, y = J.q
    s = System(J, (J.qd[0]**2 + J.qd[1]**2) / 2, [J.qd[0] - J.t * J.qd[1]], [x])
    acc = s.equations("chetaev").accelerations()
    for e in acc.values():      # every denominator stays nonzero at t = 0: no 1/t
        den = sp.denom(sp.together(e)).subs({J.t: 0, J.qd[1]: 1, J.q[0]: 1, J.q[1]: 1})
        assert den != 0 and den.is_number


def test_nonlinear_constraint_with_two_branches_asks_for_one():
    J = JetSpace("x y z")
    a, b = sp.symbols("a b", positive=True)
    xd, yd, zd = J.qd
    L = sum(v**2 for v in J.qd) / 2
    f = a**2 * zd**2 - b**2 * (xd**2 + yd**2)
    with pytest.raises(ConstraintError, match="branch"):
        System(J, L, [f], ["z"]).phi
    s = System(J, L, [f], ["z"], branch=1)
    assert sp.simplify(s.phi[zd] - b / a * sp.sqrt(xd**2 + yd**2)) == 0
    assert not s.is_affine and not s.is_integrable()


@settings(max_examples=15)
@given(jst.systems(max_n=4))
def test_explicit_form_solves_the_constraints(s):
    for f in s.constraints:
        assert vanishes(s.on_constraints(f))


@settings(max_examples=15)
@given(jst.systems(max_n=4, affine=True))
def test_T_is_the_frobenius_curvature_contracted_with_velocities(s):
    D = s.T() - frobenius_T(s)
    assert all(vanishes(e, s) for e in D)


@settings(max_examples=10)
@given(jst.systems(max_n=4, affine=True))
def test_split_choice_keeps_the_constraint_manifold(s):
    auto = s.replace(dependent=None)
    for f in s.constraints:
        assert vanishes(auto.on_constraints(f))


def test_integrable_constraints_written_in_differential_form():
    J = JetSpace("x y")
    x, y = J.q
    xd, yd = J.qd
    L = (xd**2 + yd**2) / 2
    assert System(J, L, [yd - 2 * x * xd], [y]).is_integrable()          # bead on a parabola
    assert System(J, L, [y * xd - x * yd], [x]).is_integrable()          # x/y constant
    J3 = JetSpace("x y z")
    L3 = sum(v**2 for v in J3.qd) / 2
    assert not System(J3, L3, [J3.qd[2] - J3.q[1] * J3.qd[0]], ["z"]).is_integrable()


def test_bad_input_is_named():
    J = JetSpace("x y")
    x, y = J.q
    xd, yd = J.qd
    L = (xd**2 + yd**2) / 2
    assert System(J, L, [x - y]).holonomic == (x - y,)       # kept at position level
    with pytest.raises(ConstraintError, match="time only"):
        System(J, L, [J.t - 1])
    with pytest.raises(ConstraintError, match="dependent"):
        System(J, L, [xd - y * yd, 2 * xd - 2 * y * yd], [x, y])
    with pytest.raises(ConstraintError, match="not a coordinate"):
        System(J, L, [xd - yd], ["w"])
    with pytest.raises(ConstraintError, match="one per constraint"):
        System(J, L, [xd - yd], [x, y])
    with pytest.raises(ConstraintError, match="cannot be solved"):
        System(J, L, [xd - x * y], [y])
    with pytest.raises(ConstraintError, match="accelerations"):
        System(J, L, [J.qdd[0] - yd])
    with pytest.raises(JetSpaceError):
        System(J, L, [sp.Symbol("x_t", real=True) - yd])
    with pytest.raises(JetSpaceError):
        System(J, "x_t**2", [])
    with pytest.raises(LagrangianError):
        # singular on the admissible velocities: qdot = (-1, 1) ydot lies in ker d2L/dqdot2
        System(J, (xd + yd)**2 / 2, [xd + yd], [x]).equations("chetaev").accelerations()
