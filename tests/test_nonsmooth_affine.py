"""A velocity under Abs or sign makes a constraint piecewise affine only: not affine, no
B^alpha_rho (it would hold nan at the kink and differ on either side), not Chaplygin.
Abs/sign of coordinates keeps a constraint affine."""

import pytest
import sympy as sp

import jetnh as jn
from jetnh.errors import ConstraintError

J = jn.JetSpace("x y z")
x, y, z = J.q
xd, yd, zd = J.qd
L = (xd**2 + yd**2 + zd**2) / 2


@pytest.mark.parametrize("f", [zd - y * sp.Abs(xd), zd - sp.sign(xd) * yd,
                               zd - sp.sign(xd) * x * yd, zd - sp.Abs(xd)])
def test_velocity_under_abs_or_sign_is_not_affine(f):
    s = jn.System(J, L, [f], dependent=[z])
    assert not s.is_affine
    assert not s.is_chaplygin()
    assert not s.classify().affine
    with pytest.raises(ConstraintError, match="piecewise affine"):
        s.B                                                     # noqa: B018


def test_abs_of_a_coordinate_stays_affine():
    s = jn.System(J, L, [zd - sp.Abs(x) * yd - sp.sign(y) * xd], dependent=[z])
    assert s.is_affine
    B = list(s.B)
    assert not any(e.has(sp.nan) for e in B)
    assert B[0] == 0
    assert sp.simplify(B[1] - s.phi[zd].diff(xd)) == 0
    assert not (set().union(*(e.free_symbols for e in B)) & set(J.qd))


def test_smooth_affine_unchanged():
    s = jn.System(J, L, [zd - y * xd], dependent=[z])
    assert s.is_affine and s.is_chaplygin() and list(s.B) == [0, y, 0]
