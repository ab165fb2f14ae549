"""Systems with a holonomic constraint g(t, q) = 0, each next to the same system with a
coordinate eliminated by hand: the two routes of the holonomic tests
(``test_holonomic.py``, ``test_linearize_holonomic.py``).

The pendulum in Cartesian coordinates (x, y) on x^2 + y^2 = l^2 against the pendulum in
its angle; a knife edge (x, y, theta) carrying a slider z = a sin(theta) on a spring
against the knife edge with z substituted.
"""

import sympy as sp

import jetnh as jn

l_, G_ = sp.symbols("l G", positive=True)
a_, k_, I_ = sp.symbols("a k I", positive=True)
KNIFE = {"a": 0.4, "k": 3.0, "I": 0.7}


def pendulum_xy():
    J = jn.JetSpace("x y")
    x, y = J.q
    xt, yt = J.qd
    return jn.System(J, (xt**2 + yt**2) / 2 - G_ * y, [x**2 + y**2 - l_**2])


def pendulum_angle():
    J = jn.JetSpace("th")
    (th,), (tht,) = J.q, J.qd
    return jn.System(J, l_**2 * tht**2 / 2 + G_ * l_ * sp.cos(th))


def knife_slider():
    """A knife edge (x, y, th) with a slider z = a sin(th) on a spring: one nonholonomic
    and one holonomic constraint."""
    J = jn.JetSpace("x y th z")
    x, y, th, z = J.q
    xt, yt, tht, zt = J.qd
    L = (xt**2 + yt**2 + I_ * tht**2 + zt**2) / 2 - k_ * z**2 / 2
    return jn.System(J, L, [sp.sin(th) * xt - sp.cos(th) * yt, z - a_ * sp.sin(th)],
                     dependent=["y", "z"])


def knife_reduced():
    """The knife edge of :func:`knife_slider` with z = a sin(th) substituted."""
    J = jn.JetSpace("x y th")
    x, y, th = J.q
    xt, yt, tht = J.qd
    z, zt = a_ * sp.sin(th), a_ * sp.cos(th) * tht
    L = (xt**2 + yt**2 + I_ * tht**2 + zt**2) / 2 - k_ * z**2 / 2
    return jn.System(J, L, [sp.sin(th) * xt - sp.cos(th) * yt], dependent=["y"])
