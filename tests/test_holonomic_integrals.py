"""Integrals and Noether symmetries with a holonomic constraint g = 0: g itself (constant
on every motion) and the zero generator are trivial and left out; the energy stays.
Second route: the Cartesian pendulum's energy on the circle is the angle pendulum's."""

import os
import sys

import pytest
import sympy as sp

import jetnh as jn

sys.path.insert(0, os.path.dirname(__file__))
from holonomic_systems import G_, l_, pendulum_angle, pendulum_xy  # noqa: E402


def _audit_pendulum():
    J = jn.JetSpace("x y")
    x, y = J.q
    xt, yt = J.qd
    g = sp.Symbol("g")
    return jn.System(J, (xt**2 + yt**2) / 2 - g * y, [x**2 + y**2 - 1])


def _on_circle(s, I, th, tht, radius):
    """I at the state of angle th, rate tht on the circle of ``radius``."""
    x, y = s.J.q
    xt, yt = s.J.qd
    pt = {x: radius * sp.sin(th), y: -radius * sp.cos(th),
          xt: radius * sp.cos(th) * tht, yt: radius * sp.sin(th) * tht}
    return sp.expand(I.xreplace(pt))


@pytest.mark.parametrize("principle", ["chetaev", "vakonomic"])
@pytest.mark.parametrize("build", [_audit_pendulum, pendulum_xy])
def test_constraint_is_no_integral_energy_is(build, principle):
    s = build()
    x, y = s.J.q
    ints = jn.conserved_quantities(s, principle, degree=2)
    assert len(ints) == 1
    (I,) = ints
    # not constant on the circle: two states of the motion give different values
    r = 1 if build is _audit_pendulum else l_
    assert sp.simplify(_on_circle(s, I, sp.Rational(1, 3), 2, r)
                       - _on_circle(s, I, sp.Rational(1, 3), 1, r)) != 0
    # and g itself is not in the span: the answer is the energy up to a factor
    E = (s.J.qd[0]**2 + s.J.qd[1]**2) / 2 + (G_ if build is pendulum_xy else sp.Symbol("g")) * y
    ratio = sp.cancel(I / E)
    assert not ratio.free_symbols & {*s.J.q, *s.J.qd}


def test_energy_matches_the_angle_pendulum():
    s, a = pendulum_xy(), pendulum_angle()
    (I,) = jn.conserved_quantities(s, "chetaev", degree=2)
    (Ia,) = jn.conserved_quantities(a, "chetaev", degree=2, coefficients=[1, sp.cos(a.J.q[0])])
    th, tht = sp.symbols("th th_t")
    # I on the circle is a constant multiple of the angle energy
    ratio = sp.simplify(_on_circle(s, I, th, tht, l_) / Ia.xreplace(
        {a.J.q[0]: th, a.J.qd[0]: tht}))
    assert not ratio.free_symbols & {th, tht}


@pytest.mark.parametrize("build", [_audit_pendulum, pendulum_xy])
def test_no_zero_generator(build):
    s = build()
    syms = jn.noether_symmetries(s, "chetaev", degree=1)
    assert syms, "time translation must stay"
    for sym in syms:
        assert sym.xi0 != 0 or any(e != 0 for e in sym.xi.values())
    assert any(sym.xi0 != 0 for sym in syms)
    # no quantity is g up to a constant
    x, y = s.J.q
    for sym in syms:
        assert sp.simplify(sym.quantity - (x**2 + y**2)).free_symbols & {*s.J.q, *s.J.qd}
