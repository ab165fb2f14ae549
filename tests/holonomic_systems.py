"""Systems with a holonomic constraint g(t, q) = 0, each next to the same system with a
coordinate eliminated by hand: the two routes of the holonomic tests
(``test_holonomic.py``, ``test_linearize_holonomic.py``).

The pendulum in Cartesian coordinates (x, y) on x^2 + y^2 = l^2 against the pendulum in
its angle; a knife edge (x, y, theta) carrying a slider z = a sin(theta) on a spring
against the knife edge with z substituted.  And a Kane four-bar (two loop-closure
constraints) brought in from sympy's ``KanesMethod``.
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


FOURBAR = {"l1": 1.0, "l2": 3.0, "l3": 2.0, "l4": 3.0, "m": 1.0, "g": 9.81}


def kane_fourbar():
    """Three links l1, l2, l3 from the origin closing on (l4, 0), point masses at the
    two free joints under gravity: one degree of freedom, two loop-closure constraints
    (``configuration_constraints`` of a ``KanesMethod``, ``jn.from_mechanics``)."""
    import sympy.physics.mechanics as me

    q1, q2, q3 = me.dynamicsymbols("q1 q2 q3")
    u1, u2, u3 = me.dynamicsymbols("u1 u2 u3")
    l1, l2, l3, l4, m, g = sp.symbols("l1 l2 l3 l4 m g", positive=True)
    N = me.ReferenceFrame("N")
    A, B, C = (N.orientnew(n, "Axis", [q, N.z]) for n, q in zip("ABC", (q1, q2, q3)))
    for F, u in zip((A, B, C), (u1, u2, u3)):
        F.set_ang_vel(N, u * N.z)
    P1 = me.Point("P1")
    P1.set_vel(N, 0)
    P2 = P1.locatenew("P2", l1 * A.x)
    P2.v2pt_theory(P1, N, A)
    P3 = P2.locatenew("P3", l2 * B.x)
    P3.v2pt_theory(P2, N, B)
    P4 = P3.locatenew("P4", l3 * C.x)
    P4.v2pt_theory(P3, N, C)
    loop = P4.pos_from(P1) - l4 * N.x
    conf = [loop.dot(N.x), loop.dot(N.y)]
    t = me.dynamicsymbols._t
    vel = [sp.diff(e, t).subs({q1.diff(): u1, q2.diff(): u2, q3.diff(): u3}) for e in conf]
    km = me.KanesMethod(N, q_ind=[q1], u_ind=[u1],
                        kd_eqs=[q1.diff() - u1, q2.diff() - u2, q3.diff() - u3],
                        q_dependent=[q2, q3], configuration_constraints=conf,
                        u_dependent=[u2, u3], velocity_constraints=vel)
    km.kanes_equations([me.Particle("pa", P2, m), me.Particle("pb", P3, m)],
                       [(P2, -m * g * N.y), (P3, -m * g * N.y)])
    return jn.from_mechanics(km)
