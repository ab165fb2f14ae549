"""Scalable families for benchmarks: N trailers, N coupled nonholonomic particles."""

import math

import sympy as sp

from ..mechanics.system import System
from ..errors import ModelFileError
from ..geometry.jet import JetSpace
from ._registry import model


def _count(N, least=0) -> int:
    if isinstance(N, bool) or not isinstance(N, int) or N < least:
        raise ModelFileError(f"N must be an integer >= {least}, got {N!r}")
    return N


def n_trailer_turning(N: int, d: float = 1.0, Omega: float = 0.5) -> dict:
    """The steadily turning N-trailer: every body on a circle about the origin, rate Omega.

    Car at (0, -R0) heading along +x; trailer i on the circle of radius
    R_i = sqrt(R0^2 - i d^2), heading theta_i = theta_{i-1} - atan(d/R_i); R0 = d sqrt(N + 4).
    """
    R = [d * math.sqrt(N + 4 - i) for i in range(N + 1)]
    st = dict(x=0.0, y=-R[0], theta0=0.0, x_t=Omega * R[0], theta0_t=Omega)
    th = 0.0
    for i in range(1, N + 1):
        th -= math.atan(d / R[i])
        st[f"theta{i}"] = th
    return st


@model("n_trailer", initial=lambda N: n_trailer_turning(N), t_end=1.0, options={"N": 2},
       tags=("affine", "nonholonomic", "scalable"))
def n_trailer(N: int = 2) -> System:
    """A car pulling N trailers, each hitched at the centre of the axle in front of it.

    Source: Murray & Sastry, "Nonholonomic motion planning: steering using sinusoids",
    IEEE TAC 38 (1993); Sordalen (1993); Bloch (2003), ch. 1 (kinematic form).  Here with
    dynamics: every body is a point mass m at its axle with moment of inertia I.

    Coordinates (x, y, theta0, ..., thetaN): the car's axle p_0 = (x, y) and the headings;
    trailer i's axle is p_i = p_{i-1} - d (cos theta_i, sin theta_i).
    L = sum_i [m |p_i dot|^2/2 + I theta_i dot^2/2]; constraints (no axle slides
    sideways) sin(theta_i) p_i,x dot - cos(theta_i) p_i,y dot = 0, i = 0..N; dependent
    y, theta1..thetaN (the inputs of the kinematic car are xdot and theta0dot).

    Closed forms (Chetaev): the rig moving straight (all theta_i = 0, theta0dot = 0,
    xdot = v) keeps going; the rig turning steadily is a relative equilibrium: with every
    body on a circle about the origin, R_i^2 = R_{i-1}^2 - d^2, theta_i = theta_{i-1}
    - atan(d/R_i), and all headings turning at the rate Omega, the car's axle follows
    x = R0 sin(Omega t), y = -R0 cos(Omega t) (hitch forces vanish; every wheel's
    reaction is centripetal).  N = 0 is the knife edge on a level plane (a circle).
    First integrals: the energy; for N = 1 also theta0dot (Chetaev only).
    """
    N = _count(N)
    names = ["x", "y"] + [f"theta{i}" for i in range(N + 1)]
    J = JetSpace(names)
    x, y, *th = J.q
    xd, yd, *thd = J.qd
    m, I, d = sp.symbols("m I d")
    px, py = xd, yd
    L = sp.S.Zero
    cons = []
    for i in range(N + 1):
        if i > 0:
            px = px + d * sp.sin(th[i]) * thd[i]
            py = py - d * sp.cos(th[i]) * thd[i]
        L += m * (px**2 + py**2) / 2 + I * thd[i]**2 / 2
        cons.append(sp.sin(th[i]) * px - sp.cos(th[i]) * py)
    defaults = {m: 1.0, I: 0.1, d: 1.0} if N else {m: 1.0, I: 0.1}
    return System(J, L, cons, [y] + th[1:], defaults=defaults,
                  name=f"car with {N} trailer{'s' if N != 1 else ''}")


def _chain_initial(N):
    st = {}
    for i in range(1, N + 1):
        st.update({f"x{i}": 0.1 * i, f"y{i}": 0.1 * i, f"z{i}": 0.0,
                   f"x{i}_t": 1.0 - 0.1 * i, f"y{i}_t": 0.2 + 0.1 * i})
    return st


@model("particle_chain", initial=_chain_initial, t_end=1.0, options={"N": 3},
       tags=("affine", "nonholonomic", "scalable"))
def particle_chain(N: int = 3) -> System:
    """N nonholonomic particles (zdot_i = y_i xdot_i) coupled by springs along x.

    Source: a scalable version of ``nonholonomic_particle`` (Rosenberg 1977; Bloch 2003,
    ch. 1) for benchmarks: 3N coordinates, N constraints.  Coordinates x1..xN, y1..yN, z1..zN,
    mass m, spring constant k between neighbours:
    L = sum_i m (xdot_i^2 + ydot_i^2 + zdot_i^2)/2 - k sum_i (x_{i+1} - x_i)^2/2;
    constraints zdot_i - y_i xdot_i = 0; dependent z_i.

    Chetaev: yddot_i = 0 for every k (y_i = y_i0 + ydot_i0 t); for k = 0 each particle
    follows the closed form of ``nonholonomic_particle``.  First integral: the energy
    sum_i m ((1 + y_i^2) xdot_i^2 + ydot_i^2)/2 + k sum_i (x_{i+1} - x_i)^2/2, and ydot_i.
    Vakonomic and Hoelder: the energy, m zdot_i + lambda_i and the total x-momentum
    sum_i (m xdot_i - lambda_i y_i); Suslov: the energy and sum_i (1 + y_i^2) xdot_i.
    """
    N = _count(N, 1)
    J = JetSpace([f"{c}{i}" for c in "xyz" for i in range(1, N + 1)])
    xs, ys, zs = J.q[:N], J.q[N:2 * N], J.q[2 * N:]
    xds, yds, zds = J.qd[:N], J.qd[N:2 * N], J.qd[2 * N:]
    m, k = sp.symbols("m k")
    L = sum(m * (a**2 + b**2 + c**2) / 2 for a, b, c in zip(xds, yds, zds))
    L -= sum(k * (xs[i + 1] - xs[i])**2 / 2 for i in range(N - 1))
    cons = [zds[i] - ys[i] * xds[i] for i in range(N)]
    defaults = {m: 1.0, k: 1.0} if N > 1 else {m: 1.0}
    return System(J, L, cons, list(zs), defaults=defaults,
                  name=f"chain of {N} nonholonomic particle{'s' if N != 1 else ''}")
