"""Accuracy of runs that change chart, in proportion to the tolerance (or to h^4).

Near its singular set a chart's right-hand side has a pole (the dependent velocity
y_t = -x x_t / y of the Cartesian pendulum, y_t = x_t tan theta of the sleigh); a step
whose length is comparable to its distance from the pole has a local error that the
embedded estimate misses, and the step before each edge came back at the same phase
every turn.  Two routes each: the pendulum against its angle ODE (scipy, tight) and its
energy (a closed-form first integral); the sleigh (a = 0) against its closed-form circle
and against scipy's RK45 on the chart-free body-frame equations at the same tolerance.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import jetnh as jn
from jetnh import models

from holonomic_systems import pendulum_xy

G, V0, T = 9.81, 8.0, 50.0      # rotating: 203 chart switches in 50 s


@pytest.fixture(scope="module")
def pendulum():
    return jn.Scene(pendulum_xy(), params={"l": 1.0, "G": G},
                    initial={"x": 0.0, "y": -1.0, "x_t": V0}, t_span=(0, T))


@pytest.fixture(scope="module")
def angle():
    """The angle from the bottom along the exact motion (th'' = -G sin th, tight)."""
    sol = solve_ivp(lambda t, s: [s[1], -G * np.sin(s[0])], (0, T), [0.0, V0],
                    method="DOP853", rtol=1e-13, atol=1e-13, dense_output=True)
    return lambda t: sol.sol(t)[0]


def _errors(tr, angle):
    """Max angle error and max energy error over the rows of a pendulum run."""
    th = np.unwrap(np.arctan2(tr["x"], -tr["y"]))
    energy = (tr["x_t"] ** 2 + tr["y_t"] ** 2) / 2 + G * tr["y"]
    return (float(np.max(abs(th - angle(tr.t)))),
            float(np.max(abs(energy - (V0 ** 2 / 2 - G)))))


def test_dop853_pendulum_in_proportion(pendulum, angle):
    """dop853 rtol 1e-9 ended 2.7e-5 from the motion (energy 5e-6 off), rtol 1e-11
    9e-7: the step before each edge ran within a step of the pole (its estimate 0.01
    of the tolerance, its error 1.1 times it).  The angle form of the same pendulum
    gives 1e-6 and 1.4e-8."""
    (e9, E9), (e11, E11) = (_errors(pendulum.run(rtol=r, atol=r), angle)
                            for r in (1e-9, 1e-11))
    assert e9 < 3e-6 and E9 < 1e-6
    assert e11 < 1e-7 and E11 < 2e-8
    assert e11 < e9 / 10


def test_rk4_stages_past_the_edge_switch(pendulum, angle):
    """rk4 with n = 600 or 800 took steps whose stages crossed the whole edge band
    and ended regular (garbage: no edge crossed), and blew up (NONFINITE).  Now such
    a step stops at its start and the run switches there.  Runs that coarse lose turns
    by rk4's own error (n = 600: 178 switches of 203, n = 1200: 202); n = 1275 and 1650
    keep every turn and still have steps with a stage past the edge (without the stage
    check they end elsewhere; n = 1025 blew up): each run keeps all 203 switches, its
    error on the h^4 trend of the runs with twice the steps."""
    err = {}
    for n in (1275, 1650, 2550, 3300):
        tr = pendulum.run(method="rk4", n_steps=n)
        assert tr.success and tr.t[-1] == T and len(tr.switches) == 203
        err[n] = _errors(tr, angle)[0]
    assert 8 < err[1275] / err[2550] < 64          # (2^4 = 16)
    assert 8 < err[1650] / err[3300] < 64


def test_dopri5_sleigh_loose_tolerance():
    """dopri5 rtol 1e-4 on the sleigh circle (R = v/w, 191 switches in 100 s) ended
    0.14 R off, against 1.6e-3 R for scipy's RK45 on the body-frame equations at the
    same tolerance (and 4e-4 R for the same dopri5, or scipy's RK45, in one chart up to
    its first edge): an edge effect, the steps of 1 rad next to each edge."""
    M = models.get("chaplygin_sleigh")
    I, a, m = M.parameters
    v, w, t1 = 0.2, 3.0, 100.0
    R = v / w
    sc = jn.Scene(M, "chetaev", params={I: 0.5, a: 0.0, m: 2.0},
                  initial={"x": 0, "y": 0, "theta": 0, "x_t": v, "theta_t": w},
                  t_span=(0, t1))
    tr = sc.run(method="dopri5", rtol=1e-4, atol=1e-4)
    assert tr.success and len(tr.switches) == 191
    ours = np.max(np.hypot(tr["x"] - R * np.sin(w * tr.t),
                           tr["y"] - R * (1 - np.cos(w * tr.t)))) / R
    body = solve_ivp(lambda t, u: [u[2] * np.cos(u[3]), u[2] * np.sin(u[3]), 0.0, u[4], 0.0],
                     (0, t1), [0, 0, v, 0, w], method="RK45", rtol=1e-4, atol=1e-4)
    theirs = np.max(np.hypot(body.y[0] - R * np.sin(w * body.t),
                             body.y[1] - R * (1 - np.cos(w * body.t)))) / R
    assert ours < 1e-3 and ours < theirs
