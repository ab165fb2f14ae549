"""A Chaplygin sleigh with its mass offset by a from the blade and a viscous torque
-c theta_t on the heading, with parameter values and a start at the origin: a system
outside the catalogue for the input and verdict tests."""

import sympy as sp

import jetnh as jn

PARAMS = {"m": 2.0, "a": 0.3, "I": 0.5, "c": 0.1}
ORIGIN = {"x": 0.0, "y": 0.0, "th": 0.0}


def damped_sleigh() -> jn.System:
    J = jn.JetSpace("x y th")
    x, y, th = J.q
    xd, yd, thd = J.qd
    m, a, I, c = sp.symbols("m a I c", positive=True)
    L = (m / 2 * ((xd - a * sp.sin(th) * thd) ** 2 + (yd + a * sp.cos(th) * thd) ** 2)
         + I / 2 * thd ** 2)
    return jn.System(J, L, constraints=[-sp.sin(th) * xd + sp.cos(th) * yd],
                     forces={th: -c * thd})
