"""The two examples of Zhao et al. (2008), section 5."""

import sympy as sp

from ..mechanics.system import System
from ..geometry.jet import JetSpace


def rolling_disk() -> System:
    """Vertical rolling disk (Example 1; Bloch 2003, section 1.4).

    Coordinates (x, y, phi, psi): contact point, rolling angle, heading.  Unit mass,
    L = (xdot^2 + ydot^2)/2 + (I1 phidot^2 + I2 psidot^2)/2, constraints (40)
    xdot = R cos(psi) phidot, ydot = R sin(psi) phidot; dependent x, y.  Chaplygin.

    Chetaev (nonholonomic) solution: phidot, psidot constant, and for psidot != 0
    x = x0 + R phidot/psidot (sin psi - sin psi0), y = y0 - R phidot/psidot (cos psi - cos psi0).
    First integrals: energy ((R^2 + I1) phidot^2 + I2 psidot^2)/2, phidot, psidot
    (Chetaev and Suslov, with the time-dependent phi - phidot t, psi - psidot t);
    vakonomic and Hoelder: the energy only (phidot is not conserved).
    """
    J = JetSpace("x y phi psi")
    x, y, phi, psi = J.q
    xd, yd, phid, psid = J.qd
    R, I1, I2 = sp.symbols("R I1 I2")
    L = (xd**2 + yd**2) / 2 + (I1 * phid**2 + I2 * psid**2) / 2
    return System(J, L, [xd - R * sp.cos(psi) * phid, yd - R * sp.sin(psi) * phid], [x, y],
                  defaults={R: 1.0, I1: 0.5, I2: 0.25}, name="vertical rolling disk")


def appell_hamel() -> System:
    """Appell-Hamel system (Example 2; Neimark & Fufaev 1972, ch. III).

    A particle of mass m in gravity with the nonlinear constraint
    zdot = (b/a) sqrt(xdot^2 + ydot^2); dependent z.  Chetaev solution: the horizontal
    velocity keeps its direction and its speed v decays linearly,
    (1 + b^2/a^2) dv/dt = -(b/a) g, until v = 0, where the constraint is singular.
    First integral (every principle): the energy m (xdot^2 + ydot^2 + zdot^2)/2 + m g z;
    the vakonomic motion has two more whose constants are not polynomial in the
    parameters (on the branch lambda_z = a m v/b, see ``compare``).
    """
    J = JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    m, g, a, b = sp.symbols("m g a b")
    L = m * (xd**2 + yd**2 + zd**2) / 2 - m * g * z
    return System(J, L, [zd - b / a * sp.sqrt(xd**2 + yd**2)], [z],
                  defaults={m: 1.0, g: 9.81, a: 1.0, b: 0.5}, name="Appell-Hamel system")
