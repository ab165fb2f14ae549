"""Blades with viscous friction: systems with non-potential generalized forces.

Every model: a ``System`` whose friction is a Rayleigh dissipation function D (generalized
forces Q_s = -dD/dqdot^s), with its parameters' defaults; the docstring gives the source,
the Chetaev (Lagrange-d'Alembert) equations and their closed-form solution.  Each claim
is checked in ``tests/test_forces.py``.
"""

import sympy as sp

from ..mechanics.system import System
from ..geometry.jet import JetSpace
from ._registry import model


@model("damped_knife_edge", initial=dict(x=0.0, y=0.0, phi=0.0, x_t=0.5, phi_t=1.0),
       t_end=1.0, tags=("affine", "nonholonomic", "Chaplygin", "dissipative"))
def damped_knife_edge() -> System:
    """Knife edge (skate) on a horizontal plane with viscous friction.

    Source: the knife edge of Neimark & Fufaev, *Dynamics of Nonholonomic Systems* (1972),
    ch. I, and Bloch, *Nonholonomic Mechanics and Control* (2003), ch. 1, with the
    friction of a Rayleigh dissipation function (Rayleigh, *The Theory of Sound*, 1877,
    vol. I).

    Coordinates (x, y, phi): contact point and heading.  Mass m, moment of inertia I:
    L = m (xdot^2 + ydot^2)/2 + I phidot^2/2; constraint sin(phi) xdot - cos(phi) ydot = 0;
    dependent y; D = c (xdot^2 + ydot^2)/2 + c_r phidot^2/2 (drag c on the contact
    point, c_r on the turning).

    Chetaev solution: the speed along the blade v (xdot = v cos phi, ydot = v sin phi) and
    the heading rate w decay independently, v = v0 exp(-c t/m), w = w0 exp(-c_r t/I),
    phi = phi0 + w0 (I/c_r)(1 - exp(-c_r t/I)).  When c/m = c_r/I = gamma (the defaults)
    the path is the frictionless one in the time tau = (1 - exp(-gamma t))/gamma: an arc
    of radius v0/w0, x = x0 + (v0/w0)(sin(phi) - sin(phi0)),
    y = y0 - (v0/w0)(cos(phi) - cos(phi0)), left after turning w0/gamma in all.
    First integrals (time-dependent): v exp(c t/m) and phidot exp(c_r t/I); the energy
    m v^2/2 + I phidot^2/2 decays at the rate 2 D.  The other principles: none with these
    coefficient functions.
    """
    J = JetSpace("x y phi")
    x, y, phi = J.q
    xd, yd, phid = J.qd
    m, I, c, c_r = sp.symbols("m I c c_r")
    L = m * (xd**2 + yd**2) / 2 + I * phid**2 / 2
    return System(J, L, [sp.sin(phi) * xd - sp.cos(phi) * yd], [y],
                  dissipation=c * (xd**2 + yd**2) / 2 + c_r * phid**2 / 2,
                  defaults={m: 1.0, I: 0.5, c: 0.4, c_r: 0.2},
                  name="knife edge with viscous friction")


@model("damped_chaplygin_sleigh", initial=dict(x=0.0, y=0.0, theta=0.0, x_t=0.2, theta_t=1.0),
       t_end=1.0, tags=("affine", "nonholonomic", "Chaplygin", "dissipative"))
def damped_chaplygin_sleigh() -> System:
    """Chaplygin sleigh with viscous friction at its centre of mass.

    Source: the Chaplygin sleigh (Chaplygin 1911; Neimark & Fufaev 1972, ch. III; Bloch
    2003, ch. 1) with the friction of a Rayleigh dissipation function (Rayleigh, *The
    Theory of Sound*, 1877, vol. I).

    Coordinates (x, y, theta): contact point of the blade and heading; the centre of mass
    a distance a ahead of it, with velocity u = (xdot - a sin(theta) thetadot,
    ydot + a cos(theta) thetadot).  L = m |u|^2/2 + I thetadot^2/2; constraint
    -sin(theta) xdot + cos(theta) ydot = 0; dependent y; D = c |u|^2/2 + c_r thetadot^2/2
    (drag c at the centre of mass, c_r on the turning).

    With v = xdot cos(theta) + ydot sin(theta), w = thetadot and K = I + m a^2 the
    Chetaev equations are m dv/dt = m a w^2 - c v, K dw/dt = -m a v w - (c a^2 + c_r) w.
    When c/m = c_r/I = gamma (the defaults) D = gamma T and the motion is the
    frictionless one in the time tau = (1 - exp(-gamma t))/gamma, its velocities scaled
    by exp(-gamma t): with E0 = m v0^2/2 + K w0^2/2, V = sqrt(2 E0/m), s0 = artanh(v0/V),
    s = m a V tau/K + s0: v = exp(-gamma t) V tanh(s), w = exp(-gamma t) w0 cosh(s0)/cosh(s),
    theta = theta0 + (w0 cosh(s0) K/(m a V)) (gd(s) - gd(s0)), gd(s) = 2 atan(tanh(s/2)).
    First integral (time-dependent, for c/m = c_r/I): exp(2 gamma t) (m v^2 + K w^2)/2;
    none at generic parameters, under any principle.
    """
    J = JetSpace("x y theta")
    x, y, th = J.q
    xd, yd, thd = J.qd
    m, I, a, c, c_r = sp.symbols("m I a c c_r")
    u2 = (xd - a * sp.sin(th) * thd)**2 + (yd + a * sp.cos(th) * thd)**2
    L = m * u2 / 2 + I * thd**2 / 2
    return System(J, L, [-sp.sin(th) * xd + sp.cos(th) * yd], [y],
                  dissipation=c * u2 / 2 + c_r * thd**2 / 2,
                  defaults={m: 1.0, I: 0.2, a: 0.5, c: 0.5, c_r: 0.1},
                  name="Chaplygin sleigh with viscous friction")
