"""Particles and blades in the plane (and the nonholonomic particle in space).

Every model: a ``System`` with its parameters' defaults; the docstring gives the source,
the closed-form Chetaev (Lagrange-d'Alembert) solution where one is known, and the first
integrals.  Each claim is checked in ``tests/test_models.py``.
"""

import sympy as sp

from ..mechanics.system import System
from ..geometry.jet import JetSpace
from ._registry import model


@model("knife_edge", initial=dict(x=0.0, y=0.0, phi=0.0, x_t=0.5, phi_t=1.0), t_end=1.0,
       tags=("affine", "nonholonomic"))
def knife_edge() -> System:
    """Knife edge (skate) on an inclined plane.

    Source: Neimark & Fufaev, *Dynamics of Nonholonomic Systems* (1972), ch. I; Bloch,
    *Nonholonomic Mechanics and Control* (2003), ch. 1 (the knife edge).

    Coordinates (x, y, phi): contact point (x down the slope) and heading.  Mass m, moment
    of inertia I about the vertical, slope alpha, gravity g:
    L = m (xdot^2 + ydot^2)/2 + I phidot^2/2 + m g sin(alpha) x;
    constraint sin(phi) xdot - cos(phi) ydot = 0 (no motion across the blade); dependent y.

    Chetaev solution: phi = phi0 + w t; the speed along the blade v (xdot = v cos phi,
    ydot = v sin phi) obeys dv/dt = g sin(alpha) cos(phi), so with c = g sin(alpha)/w and
    A = v0 - c sin(phi0): v = A + c sin(phi),
    x = x0 + [A sin(phi) + c sin(phi)^2/2]_{phi0}^{phi} / w,
    y = y0 + [-A cos(phi) + c (phi - sin(phi) cos(phi))/2]_{phi0}^{phi} / w
    (for phi0 = v0 = 0: x = g sin(alpha) sin(w t)^2/(2 w^2), the skate does not slide
    down the slope on average but drifts across it).
    First integrals: phidot; the energy m v^2/2 + I phidot^2/2 - m g sin(alpha) x
    (v^2 = xdot^2/cos(phi)^2).  Vakonomic, Hoelder and Suslov: the energy only.
    """
    J = JetSpace("x y phi")
    x, y, phi = J.q
    xd, yd, phid = J.qd
    m, I, g, alpha = sp.symbols("m I g alpha")
    L = m * (xd**2 + yd**2) / 2 + I * phid**2 / 2 + m * g * sp.sin(alpha) * x
    return System(J, L, [sp.sin(phi) * xd - sp.cos(phi) * yd], [y],
                  defaults={m: 1.0, I: 0.5, g: 9.81, alpha: 0.3},
                  name="knife edge on an inclined plane")


@model("chaplygin_sleigh", initial=dict(x=0.0, y=0.0, theta=0.0, x_t=0.2, theta_t=1.0),
       t_end=1.0, tags=("affine", "nonholonomic", "Chaplygin"))
def chaplygin_sleigh() -> System:
    """Chaplygin sleigh: a rigid body on a blade whose centre of mass is off the contact point.

    Source: Chaplygin (1911); Neimark & Fufaev (1972), ch. III; Bloch (2003), ch. 1
    (the Chaplygin sleigh).

    Coordinates (x, y, theta): contact point of the blade and heading; the centre of mass
    sits a distance a ahead of the contact point along the blade.  Mass m, moment of
    inertia I about the centre of mass:
    L = m ((xdot - a sin(theta) thetadot)^2 + (ydot + a cos(theta) thetadot)^2)/2 + I thetadot^2/2;
    constraint -sin(theta) xdot + cos(theta) ydot = 0; dependent y.

    With v = xdot cos(theta) + ydot sin(theta) (speed of the contact point along the blade)
    and w = thetadot the Chetaev equations are m dv/dt = m a w^2,
    (I + m a^2) dw/dt = -m a v w.  First integral: the energy
    E = m v^2/2 + (I + m a^2) w^2/2.  Closed form, with K = I + m a^2,
    V = sqrt(2E/m), c = artanh(v0/V), s = m a V t/K + c:
    v = V tanh(s), w = w0 cosh(c)/cosh(s) (the sleigh straightens out and moves forward
    with all its energy as translation).  Vakonomic and Hoelder: the energy and
    lambda_y^2 + 2 a m lambda_y thetadot - I m thetadot^2; Suslov: the energy and
    xdot/cos(theta)^2.
    """
    J = JetSpace("x y theta")
    x, y, th = J.q
    xd, yd, thd = J.qd
    m, I, a = sp.symbols("m I a")
    L = (m * ((xd - a * sp.sin(th) * thd)**2 + (yd + a * sp.cos(th) * thd)**2) / 2
         + I * thd**2 / 2)
    return System(J, L, [-sp.sin(th) * xd + sp.cos(th) * yd], [y],
                  defaults={m: 1.0, I: 0.2, a: 0.5}, name="Chaplygin sleigh")


def chaplygin_sleigh_lagranges():
    """The Chaplygin sleigh written independently in ``sympy.physics.mechanics`` (the
    Lagrangian of :func:`chaplygin_sleigh` with its default m, I, a), Lagrange's equations
    formed: ``(LagrangesMethod, (x, y, theta), (xdot, ydot, thetadot))`` as
    dynamicsymbols; the constraint makes ydot dependent.  A second route to the sleigh's
    equations, for cross-checks and benchmarks."""
    import sympy.physics.mechanics as me

    x, y, th = me.dynamicsymbols("x y theta")
    xd, yd, thd = me.dynamicsymbols("x y theta", 1)
    d = {s.name: v for s, v in chaplygin_sleigh().defaults.items()}
    m, I, a = d["m"], d["I"], d["a"]
    L = (m * ((xd - a * sp.sin(th) * thd)**2 + (yd + a * sp.cos(th) * thd)**2) / 2
         + I * thd**2 / 2)
    lm = me.LagrangesMethod(L, [x, y, th], nonhol_coneqs=[-sp.sin(th) * xd + sp.cos(th) * yd])
    lm.form_lagranges_equations()
    return lm, (x, y, th), (xd, yd, thd)


@model("nonholonomic_particle", initial=dict(x=0.0, y=0.2, z=0.0, x_t=1.0, y_t=0.5),
       t_end=1.0, tags=("affine", "nonholonomic", "sub-Riemannian"))
def nonholonomic_particle() -> System:
    """Nonholonomic particle: zdot = y xdot (a Heisenberg-type distribution).

    Source: Rosenberg, *Analytical Dynamics of Discrete Systems* (1977); Bloch (2003),
    ch. 1 (the nonholonomic particle); Bloch, Krishnaprasad, Marsden & Murray (1996).
    The distribution ker(dz - y dx) is the contact (Heisenberg) distribution of R^3: its
    vakonomic extremals are sub-Riemannian geodesics.

    Coordinates (x, y, z), mass m: L = m (xdot^2 + ydot^2 + zdot^2)/2; constraint
    zdot - y xdot = 0; dependent z.

    Chetaev solution: (1 + y^2) xddot = -y xdot ydot and yddot = 0, so with
    y = y0 + u t (u = ydot0) and c = xdot0 sqrt(1 + y0^2):
    xdot = c/sqrt(1 + y^2), x = x0 + (c/u)(asinh(y) - asinh(y0)),
    z = z0 + (c/u)(sqrt(1 + y^2) - sqrt(1 + y0^2)).
    First integrals (Chetaev): the energy m ((1 + y^2) xdot^2 + ydot^2)/2, ydot and
    xdot sqrt(1 + y^2).  Vakonomic (F = L + lambda (zdot - y xdot)): x and z are cyclic,
    so m xdot - lambda y and m zdot + lambda are conserved, with the energy.
    Chetaev also (1 + y^2) xdot - z ydot; Suslov: (1 + y^2) xdot and the energy, not
    ydot.  Noether: d/dz is a vakonomic symmetry and no Chetaev one, d/dy the reverse.
    """
    J = JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    m = sp.Symbol("m")
    L = m * (xd**2 + yd**2 + zd**2) / 2
    return System(J, L, [zd - y * xd], [z], defaults={m: 1.0}, name="nonholonomic particle")


@model("isokinetic_particle", initial=dict(x=0.0, y=0.0, y_t=0.0), t_end=1.0,
       tags=("nonlinear", "nonholonomic"))
def isokinetic_particle() -> System:
    """A particle in uniform gravity kept at constant speed: xdot^2 + ydot^2 = v^2.

    Source: the constraint nonlinear in the velocities that Gauss's principle of least
    constraint and Chetaev's definition of virtual displacements treat alike (Neimark &
    Fufaev 1972, ch. III); in molecular dynamics it is the Gaussian isokinetic
    thermostat (Evans & Morriss, *Statistical Mechanics of Nonequilibrium Liquids*,
    1990, ch. 5).

    Coordinates (x, y), mass m: L = m (xdot^2 + ydot^2)/2 - m g y; the constraint written
    explicitly on the branch xdot > 0: xdot - sqrt(v^2 - ydot^2) = 0; dependent x.
    The Chetaev reaction is parallel to the velocity (a thrust), so only the normal part
    of gravity turns the velocity: with xdot = v cos(theta), ydot = v sin(theta),
    dtheta/dt = -(g/v) cos(theta).  Closed form: s = artanh(ydot0/v) - g t/v,
    ydot = v tanh(s), xdot = v sech(s), x = x0 - (v^2/g)(gd(s) - gd(s0)),
    y = y0 - (v^2/g)(log cosh(s) - log cosh(s0)), gd(s) = atan(sinh(s)).
    First integrals: the speed (the constraint itself) and, depending on time,
    artanh(ydot/v) + g t/v.  The energy is not conserved (the thrust works).  None is
    polynomial in ydot: no principle has one of degree <= 2.
    Suslov's equations (31) are singular everywhere: L~ = m v^2/2 - m g y does not
    depend on ydot, so they reduce to -m g = 0 and determine no acceleration.
    """
    J = JetSpace("x y")
    x, y = J.q
    xd, yd = J.qd
    m, g, v = sp.symbols("m g v")
    L = m * (xd**2 + yd**2) / 2 - m * g * y
    return System(J, L, [xd - sp.sqrt(v**2 - yd**2)], [x], defaults={m: 1.0, g: 1.0, v: 1.0},
                  name="isokinetic particle (constant speed)")


@model("rheonomic_knife_edge", initial=dict(x=0.0, y=0.0, x_t=0.3), t_end=1.0,
       tags=("affine", "nonholonomic", "rheonomic"))
def rheonomic_knife_edge() -> System:
    """Knife edge with a prescribed heading phi = w t, on a belt moving at speed U.

    Source: the knife edge of ``knife_edge`` (Neimark & Fufaev 1972, ch. I; Bloch 2003,
    ch. 1) made time-dependent (rheonomic, affine inhomogeneous): its heading is driven
    and its support moves along x.  Coordinates (x, y), mass m, slope alpha:
    L = m (xdot^2 + ydot^2)/2 + m g sin(alpha) x;
    constraint sin(w t)(xdot - U) - cos(w t) ydot = 0; dependent y.  The constraint
    1-form sin(w t) dx - cos(w t) dy - U sin(w t) dt is not integrable (w != 0).

    Chetaev solution: in the belt frame X = x - U t the motion is the knife edge's with
    phi0 = 0: the speed along the blade is v = v0 + (g sin(alpha)/w) sin(w t) (v0 = xdot0 - U),
    x = U t + x0 + [A sin(w t) + c sin(w t)^2/2]/w,
    y = y0 + [c (w t - sin(w t) cos(w t))/2 - A (cos(w t) - 1)]/w
    with c = g sin(alpha)/w, A = v0.  First integral (Jacobi's, in the belt frame):
    m ((xdot - U)^2 + ydot^2)/2 - m g sin(alpha) (x - U t); the energy itself is not
    conserved when U != 0 (the belt works on the skate).  Suslov:
    (xdot - U)/cos(w t)^2 - g sin(alpha) t; vakonomic and Hoelder: none of degree <= 2
    with the coefficients 1/cos(w t)^2, x, t.
    """
    J = JetSpace("x y")
    x, y = J.q
    xd, yd = J.qd
    t = J.t
    m, g, alpha, w, U = sp.symbols("m g alpha w U")
    L = m * (xd**2 + yd**2) / 2 + m * g * sp.sin(alpha) * x
    return System(J, L, [sp.sin(w * t) * (xd - U) - sp.cos(w * t) * yd], [y],
                  defaults={m: 1.0, g: 9.81, alpha: 0.3, w: 1.0, U: 0.5},
                  name="knife edge with prescribed heading on a moving belt")


@model("bead_on_parabola", initial=dict(x=0.5, y=0.25, x_t=0.0), t_end=1.0,
       tags=("affine", "integrable"))
def bead_on_parabola() -> System:
    """A bead on the parabola y = a x^2 + const, its constraint written as ydot = 2 a x xdot.

    Source: an integrable constraint in differential form (Neimark & Fufaev 1972, ch. I: a
    holonomic constraint differentiated once).  Coordinates (x, y), mass m, gravity g
    along -y: L = m (xdot^2 + ydot^2)/2 - m g y; constraint ydot - 2 a x xdot = 0;
    dependent y.  Integrable (Frobenius), so every principle with lambda = 0 and Chetaev
    give the motion of the bead on the curve.

    Chetaev equation: (1 + 4 a^2 x^2) xddot + 4 a^2 x xdot^2 + 2 a g x = 0 (no
    elementary closed form: the period is an elliptic-type integral; small oscillations
    have angular frequency sqrt(2 a g)).  First integrals: y - a x^2 (the holonomic
    constraint) and the energy m (1 + 4 a^2 x^2) xdot^2/2 + m g y, under every principle;
    vakonomic and Hoelder also a m x xdot + g m t/2 + lambda_y/2.
    """
    J = JetSpace("x y")
    x, y = J.q
    xd, yd = J.qd
    m, g, a = sp.symbols("m g a")
    L = m * (xd**2 + yd**2) / 2 - m * g * y
    return System(J, L, [yd - 2 * a * x * xd], [y], defaults={m: 1.0, g: 9.81, a: 1.0},
                  name="bead on a parabola")


@model("radial_line", initial=dict(x=1.0, y=0.5, x_t=0.2), t_end=1.0,
       tags=("affine", "integrable"))
def radial_line() -> System:
    """A particle held on a line through the origin: y xdot - x ydot = 0 (integrable).

    Source: an integrable constraint in differential form (Neimark & Fufaev 1972, ch. I):
    y xdot - x ydot = -x^2 d(y/x)/dt, so y/x is constant.  Coordinates (x, y), mass m,
    in the repulsive radial field of potential -m k (x^2 + y^2)/2:
    L = m (xdot^2 + ydot^2)/2 + m k (x^2 + y^2)/2; dependent y (ydot = y xdot / x,
    singular on x = 0).

    Chetaev solution: the reaction is normal to the line and the force along it, so
    xddot = k x, yddot = k y: x = x0 cosh(sqrt(k) t) + xdot0 sinh(sqrt(k) t)/sqrt(k),
    y = (y0/x0) x.  First integrals: y/x, and the energy
    m (xdot^2 + ydot^2)/2 - m k (x^2 + y^2)/2, under every principle; vakonomic and
    Hoelder also lambda_y x^2.
    """
    J = JetSpace("x y")
    x, y = J.q
    xd, yd = J.qd
    m, k = sp.symbols("m k")
    L = m * (xd**2 + yd**2) / 2 + m * k * (x**2 + y**2) / 2
    return System(J, L, [y * xd - x * yd], [y], defaults={m: 1.0, k: 1.0},
                  name="particle on a line through the origin")



@model("heisenberg", initial=dict(x=0.0, y=0.2, z=0.0, x_t=1.0, y_t=0.5), t_end=1.0,
       tags=("affine", "nonholonomic", "sub-Riemannian"))
def heisenberg() -> System:
    """Heisenberg system: a particle in the plane whose z records the swept area.

    Source: Brockett, "Control theory and singular Riemannian geometry" (1981); Bloch
    (2003), ch. 1 (the Heisenberg system); Montgomery, *A Tour of Subriemannian
    Geometries* (2002), ch. 1.  Coordinates (x, y, z), mass m: L = m (xdot^2 + ydot^2)/2
    (z carries no kinetic energy); constraint zdot - (x ydot - y xdot) = 0; dependent z.
    The distribution is the symmetric contact distribution of the Heisenberg group; its
    vakonomic extremals are sub-Riemannian geodesics (circles in the (x, y) plane).

    Chetaev: the reaction is along (y, -x, 1), so m xddot = nu y, m yddot = -nu x with
    nu = 0 (L does not involve zdot): the projection moves on straight lines,
    x = x0 + xdot0 t, y = y0 + ydot0 t.  Vakonomic (F = L + lambda f): lambdadot = 0 and
    m xddot = -2 lambda ydot, m yddot = 2 lambda xdot: circles of angular rate
    2 lambda/m.
    First integrals.  Chetaev and Suslov (L~ = L): xdot, ydot, the angular momentum
    x ydot - y xdot, and the energy m (xdot^2 + ydot^2)/2.  Vakonomic (and Hoelder):
    lambda, m xdot + 2 lambda y, m ydot - 2 lambda x (the momenta of the translations
    x -> x + a, z -> z + a y and y -> y + b, z -> z - b x) and the energy.
    """
    J = JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    m = sp.Symbol("m")
    L = m * (xd**2 + yd**2) / 2
    return System(J, L, [zd - (x * yd - y * xd)], [z], defaults={m: 1.0},
                  name="Heisenberg system")
