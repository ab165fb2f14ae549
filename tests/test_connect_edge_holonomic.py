"""Vakonomic and Hoelder free ends on a system with holonomic constraints g = 0: the
boundary term of the action's variation vanishes for every variation tangent to g = 0
that keeps the named coordinates, i.e. the reduced momenta P_R - G_R^T G_D^-T P_D = 0
(``problem.tangent_transversality``).

The knife edge with a slider z = a sin(th) (``holonomic_systems.knife_slider``) whose
kinetic energy couples the slider to the cart (b x_t z_t: P_z then need not vanish where
P_th does), from the origin to x, y named: th and z are free, z follows th on g = 0, so
the condition is P_th + a cos(th) P_z = 0.  Two routes that do not share connect's code:
P from sympy (d(L + lambda f)/dqdot with the dependent velocities from the
constraints), and the fixed-end actions C(th1) (th1 and z = a sin th1 named)
stationary at the answer's th.
"""

import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import jetnh as jn
from jetnh.errors import JetnhError
from jetnh.mechanics import principles

sys.path.insert(0, str(Path(__file__).parent))
from holonomic_systems import KNIFE  # noqa: E402

PARAMS = {**KNIFE, "b": 0.5}
START = {"x": 0.0, "y": 0.0, "th": 0.0, "z": 0.0}
END = {"x": 0.5, "y": 0.1}


@pytest.fixture(scope="module")
def slider():
    J = jn.JetSpace("x y th z")
    x, y, th, z = J.q
    xt, yt, tht, zt = J.qd
    a, k, inertia, b = sp.symbols("a k I b", positive=True)
    L = (xt**2 + yt**2 + inertia * tht**2 + zt**2) / 2 + b * xt * zt - k * z**2 / 2
    return jn.System(J, L, [sp.sin(th) * xt - sp.cos(th) * yt, z - a * sp.sin(th)],
                     dependent=["y", "z"])


def _momenta(system, principle, tr):
    """P_s at the end of ``tr`` by sympy (every coordinate, in order)."""
    mults = principles.get(principle).multiplier_symbols(system)
    composite = system.L + sum(lam * f for lam, f in zip(mults, system.constraints))
    point = {**{s: float(tr[s.name][-1]) for s in (*system.J.q, *system.J.qd, *mults)},
             **{sp.Symbol(k, positive=True): v for k, v in PARAMS.items()}}
    return [float(sp.diff(composite, v).xreplace(point)) for v in system.J.qd]


@pytest.mark.parametrize("principle", ["vakonomic", "holder"])
def test_free_end_on_g_meets_the_reduced_transversality(slider, principle):
    a = KNIFE["a"]
    f = jn.connect(slider, principle, START, END, (0.0, 1.0), params=PARAMS, tol=1e-12)
    assert f.conditions == ("x", "y", "p_th") and f.residual < 1e-12
    tr = f.trajectory
    th = float(tr["th"][-1])
    assert abs(tr["z"][-1] - a * np.sin(th)) < 1e-12
    P = dict(zip(("x", "y", "th", "z"), _momenta(slider, principle, tr)))
    assert abs(P["th"] + a * np.cos(th) * P["z"]) < 1e-10
    # neither P_th nor P_z vanishes alone: the projection onto g = 0 is what holds
    assert abs(P["th"]) > 1e-2 and abs(P["z"]) > 1e-2
    # the fixed-end actions C(th1), z = a sin(th1) named, are stationary at th
    h = 1e-3
    cost = []
    for d in (-h, h):
        c = jn.connect(slider, principle, START,
                       {**END, "th": th + d, "z": a * np.sin(th + d)}, (0.0, 1.0),
                       params=PARAMS, tol=1e-12, guess=[f.initial[k] for k in f.unknowns])
        cost.append(c.cost)
    assert abs(cost[1] - cost[0]) / (2 * h) < 1e-5 < abs(P["th"]) * 1e-2


def test_free_coordinates_that_g_does_not_move_are_refused(slider):
    """th and z named, x and y free: g = z - a sin(th) involves neither, so the named
    coordinates fix g and no variation of the free ones moves along it."""
    a = KNIFE["a"]
    with pytest.raises(JetnhError, match=r"cannot be solved for any of them"):
        jn.connect(slider, "vakonomic", START, {"th": 0.3, "z": a * np.sin(0.3)},
                   (0.0, 1.0), params=PARAMS)
