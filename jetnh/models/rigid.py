"""Rigid bodies in Euler angles: the rolling ball (also on a turntable) and Suslov's problem.

Euler angles are the classical z-x-z ones (phi precession, theta nutation, psi spin).
Angular velocity in the space frame::

    omega_x = thetadot cos(phi) + psidot sin(theta) sin(phi)
    omega_y = thetadot sin(phi) - psidot sin(theta) cos(phi)
    omega_z = phidot + psidot cos(theta)
and in the body frame:
    Omega_1 = phidot sin(theta) sin(psi) + thetadot cos(psi)
    Omega_2 = phidot sin(theta) cos(psi) - thetadot sin(psi)
    Omega_3 = phidot cos(theta) + psidot.
The chart is singular where sin(theta) = 0 (the mass matrix degenerates there).
"""

import math

import sympy as sp

from ..mechanics.system import System
from ..geometry.jet import JetSpace
from ._registry import model


def space_angular_velocity(phi, theta, psi, phid, thetad, psid):
    """(omega_x, omega_y, omega_z) in the space frame, z-x-z Euler angles."""
    return (thetad * sp.cos(phi) + psid * sp.sin(theta) * sp.sin(phi),
            thetad * sp.sin(phi) - psid * sp.sin(theta) * sp.cos(phi),
            phid + psid * sp.cos(theta))


def body_angular_velocity(phi, theta, psi, phid, thetad, psid):
    """(Omega_1, Omega_2, Omega_3) in the body frame, z-x-z Euler angles."""
    return (phid * sp.sin(theta) * sp.sin(psi) + thetad * sp.cos(psi),
            phid * sp.sin(theta) * sp.cos(psi) - thetad * sp.sin(psi),
            phid * sp.cos(theta) + psid)


_BALL0 = dict(x=0.0, y=0.0, phi=0.0, theta=math.pi / 2, psi=0.0,
              phi_t=0.3, theta_t=0.5, psi_t=0.8)


def _ball(turntable: bool) -> System:
    J = JetSpace("x y phi theta psi")
    x, y, phi, theta, psi = J.q
    xd, yd, phid, thetad, psid = J.qd
    m, r, I = sp.symbols("m r I")
    wx, wy, wz = space_angular_velocity(phi, theta, psi, phid, thetad, psid)
    L = m * (xd**2 + yd**2) / 2 + I * (phid**2 + thetad**2 + psid**2
                                       + 2 * phid * psid * sp.cos(theta)) / 2
    cons = [xd - r * wy, yd + r * wx]
    defaults = {m: 1.0, r: 1.0, I: 0.4}
    name = "homogeneous ball rolling on a plane"
    if turntable:
        Om = sp.Symbol("Omega")
        cons = [cons[0] + Om * y, cons[1] - Om * x]
        defaults[Om] = 1.0
        name = "homogeneous ball rolling on a rotating turntable"
    return System(J, L, cons, [x, y], defaults=defaults, name=name)


@model("rolling_ball", initial=_BALL0, t_end=1.0, tags=("affine", "nonholonomic", "Euler angles"))
def rolling_ball() -> System:
    """Homogeneous ball rolling without slipping on a horizontal plane, in Euler angles.

    Source: Neimark & Fufaev (1972), ch. III; Bloch (2003), ch. 1 (rolling ball).
    Coordinates (x, y, phi, theta, psi): centre of the ball over the plane and z-x-z
    Euler angles.  Mass m, radius r, moment of inertia I (solid ball: 2 m r^2/5):
    L = m (xdot^2 + ydot^2)/2 + I |omega|^2/2, |omega|^2 = phidot^2 + thetadot^2
    + psidot^2 + 2 phidot psidot cos(theta); constraints (contact point at rest)
    xdot - r omega_y = 0, ydot + r omega_x = 0; dependent x, y.

    Chetaev solution: the contact force vanishes, so the centre moves uniformly,
    x = x0 + xdot0 t, y = y0 + ydot0 t, and the spatial angular velocity omega is
    constant.  First integrals: omega_x, omega_y, omega_z, the energy, and
    Omega_3 = phidot cos(theta) + psidot (the spin about the body axis e3).  Vakonomic and
    Hoelder: I Omega_3 + r (lambda_x cos(phi) + lambda_y sin(phi)) sin(theta) and
    m r omega_x - lambda_y, m r omega_y + lambda_x (in Euler-angle form); Suslov: omega_z.
    """
    return _ball(False)


@model("ball_on_turntable", initial=_BALL0, t_end=1.0,
       tags=("affine", "nonholonomic", "inhomogeneous", "Euler angles"))
def ball_on_turntable() -> System:
    """Homogeneous ball rolling on a turntable rotating at the constant rate Omega.

    Source: Neimark & Fufaev (1972), ch. III; Bloch (2003), ch. 1 (the ball on a
    rotating table); Lewis & Murray's classic demonstration.  As ``rolling_ball`` but the
    contact point moves with the table: xdot - r omega_y + Omega y = 0,
    ydot + r omega_x - Omega x = 0 (affine, inhomogeneous, scleronomic).

    Chetaev solution: with kappa = I/(I + m r^2) the centre's velocity turns at the rate
    kappa Omega (2 Omega/7 for a solid ball): xdot + i ydot = (xdot0 + i ydot0)
    exp(i kappa Omega t), so the ball runs around a circle and never flies off.
    First integrals: omega_z, and the centre of that circle,
    (x + i y) - (xdot + i ydot)/(i kappa Omega).  The energy is not conserved (the table
    works on the ball).  Vakonomic and Hoelder: the rolling ball's first vakonomic
    integral I Omega_3 + r (lambda_x cos(phi) + lambda_y sin(phi)) sin(theta); Suslov: none
    of degree 1 in the velocities.
    """
    return _ball(True)


@model("suslov_rigid_body", initial=dict(phi=0.0, theta=1.2, psi=0.3, phi_t=0.5, theta_t=0.4),
       t_end=1.0, tags=("affine", "nonholonomic", "Euler angles"))
def suslov_rigid_body() -> System:
    """Suslov's problem: a rigid body about a fixed point with Omega_3 = 0 in the body frame.

    Source: Suslov, *Theoretical Mechanics* (1902; 1946 ed.); Fedorov & Kozlov (1995),
    "Various aspects of n-dimensional rigid body dynamics"; Bloch (2003), the
    Euler-Poincare-Suslov equations.  Coordinates z-x-z Euler angles (phi, theta, psi);
    inertia tensor with entries I1, I2, I3 and I13 (the constraint axis e3 is not a
    principal axis; I23 = 0 loses no generality, by a rotation of the body axes about
    e3): L = (I1 Omega_1^2 + I2 Omega_2^2 + I3 Omega_3^2)/2 + I13 Omega_1 Omega_3;
    constraint Omega_3 = phidot cos(theta) + psidot = 0; dependent psi.

    Chetaev (Euler-Suslov) equations: I1 dOmega_1/dt = -I13 Omega_1 Omega_2,
    I2 dOmega_2/dt = I13 Omega_1^2.  First integral: the energy
    h = (I1 Omega_1^2 + I2 Omega_2^2)/2.  Closed form: with W = sqrt(2 h/I2),
    c = artanh(Omega_2(0)/W), s = I13 W t/I1 + c: Omega_2 = W tanh(s),
    Omega_1 = Omega_1(0) cosh(c)/cosh(s); the body tends to a steady rotation about
    its second axis.  Vakonomic and Hoelder: the same energy (and one more whose constants
    are not polynomial in the inertia); Suslov: Omega_1 and Omega_2 themselves.
    """
    J = JetSpace("phi theta psi")
    phi, theta, psi = J.q
    phid, thetad, psid = J.qd
    I1, I2, I3, I13 = sp.symbols("I1 I2 I3 I13")
    O1, O2, O3 = body_angular_velocity(phi, theta, psi, phid, thetad, psid)
    L = (I1 * O1**2 + I2 * O2**2 + I3 * O3**2) / 2 + I13 * O1 * O3
    return System(J, L, [O3], [psi], defaults={I1: 1.0, I2: 2.0, I3: 3.0, I13: 0.5},
                  name="Suslov's rigid body")


@model("rolling_coin",
       initial=dict(x=0.0, y=0.0, psi=0.0, theta=0.1, phi=0.0, psi_t=0.0, theta_t=0.0,
                    phi_t=8.0),
       t_end=2.0, tags=("affine", "nonholonomic", "3-D"))
def rolling_coin() -> System:
    """Disk rolling without slipping on a plane, free to lean (a coin).

    Source: Neimark & Fufaev, *Dynamics of Nonholonomic Systems* (1972), ch. II (the
    rolling disk); Bloch (2003), section 1.4; O'Reilly, "The dynamics of rolling disks and
    sliding disks", Nonlinear Dynamics 10 (1996).

    Coordinates (x, y, psi, theta, phi): contact point, heading (yaw) psi of the line of
    rolling e1 = (cos psi, sin psi, 0), lean theta about e1 (0 upright), spin phi about
    the disk's axis n = cos(theta) (-sin psi, cos psi, 0) + sin(theta) e_z.  Centre
    C = (x, y, 0) + r u with u = e1 x n = (sin theta sin psi, -sin theta cos psi,
    cos theta).  Angular velocity psidot e_z + thetadot e1 + phidot n, with components
    (thetadot, phidot + psidot sin theta, psidot cos theta) on (e1, n, u).  Mass m,
    radius r, moments A about the axis and B about a diameter (a thin homogeneous disk:
    A = m r^2/2, B = m r^2/4):
    L = m |C'|^2/2 + (A (phidot + psidot sin theta)^2 + B (thetadot^2
    + psidot^2 cos(theta)^2))/2 - m g r cos(theta).
    Rolling (the material point at the contact at rest) moves the contact point along e1
    at r phidot: xdot = r cos(psi) phidot, ydot = r sin(psi) phidot; dependent x, y.

    Steady motions: upright rolling in a straight line (theta = 0, psidot = thetadot = 0,
    phidot = Omega), stable for Omega^2 > m g r B / (A (A + m r^2)) (g/(3 r) for a thin
    disk; checked in ``tests/test_linearize.py``); steady turning at constant lean.
    First integral: the energy m |C'|^2/2 + ... + m g r cos(theta) (Chetaev).
    """
    J = JetSpace("x y psi theta phi")
    x, y, psi, theta, phi = J.q
    xd, yd, psid, thetad, phid = J.qd
    m, r, A, B, g = sp.symbols("m r A B g")
    C = (x + r * sp.sin(theta) * sp.sin(psi), y - r * sp.sin(theta) * sp.cos(psi),
         r * sp.cos(theta))
    vC = [sum(sp.diff(c, q) * v for q, v in zip(J.q, J.qd)) for c in C]
    L = (m * sum(v**2 for v in vC) / 2
         + (A * (phid + psid * sp.sin(theta))**2
            + B * (thetad**2 + psid**2 * sp.cos(theta)**2)) / 2
         - m * g * r * sp.cos(theta))
    cons = [xd - r * sp.cos(psi) * phid, yd - r * sp.sin(psi) * phid]
    return System(J, L, cons, [x, y],
                  defaults={m: 1.0, r: 1.0, A: 0.5, B: 0.25, g: 9.81},
                  name="rolling coin (disk free to lean)")
