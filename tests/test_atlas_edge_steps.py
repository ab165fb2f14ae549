"""A step that reaches the edge of a split's chart is not kept: the piece ends at the
step's start, where the chart is regular, and the run changes chart there (fixed steps,
on their grid) or at the edge reached in shorter steps (adaptive ones); a run stopped
singular past the edge is taken on the same way.  Checked against closed forms (the
sleigh spinning in place, theta = w t; the sleigh on its circle of radius v / w; the flat
knife edge on its circle) and an independent route (the pendulum in its angle, by scipy).
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import jetnh as jn
from jetnh import models

from holonomic_systems import pendulum_xy

W = 3.0


def sleigh(x_t, T=10.0):
    """The Chaplygin sleigh with its contact point at the centre of mass (a = 0): heading
    theta = W t, a circle of radius x_t / W at constant speed x_t (19 chart edges in
    T = 10)."""
    return jn.Scene(models.get("chaplygin_sleigh"), "chetaev",
                    params={"I": 0.5, "a": 0.0, "m": 2.0},
                    initial={"x": 0, "y": 0, "theta": 0.0, "x_t": x_t, "theta_t": W},
                    t_span=(0, T))


def circle_error(tr, v):
    """max |position - closed form| / R on the sleigh's circle."""
    R = v / W
    return max(np.abs(tr["x"] - R * np.sin(W * tr.t)).max(),
               np.abs(tr["y"] - R * (1 - np.cos(W * tr.t))).max()) / R


@pytest.mark.parametrize("method", ["dop853", "dopri5", "radau"])
def test_sleigh_spinning_in_place_goes_through_every_edge(method):
    """Spinning in place (x_t = 1e-4 at rtol 1e-6: steps of a radian and more jump the
    edge band |cos theta| < 1/sqrt(8); before, the runs stopped singular at pi/2)."""
    tr = sleigh(1e-4).run(method=method, rtol=1e-6, atol=1e-6)
    assert tr.status == 0 and tr.t[-1] == 10.0
    assert len(tr.switches) == 19
    assert np.abs(tr["theta"] - W * tr.t).max() < 1e-9
    assert circle_error(tr, 1e-4) * 1e-4 / W < 2e-5           # (R = 3.3e-5: ~ 10 atol)
    assert np.abs(np.hypot(tr["x_t"], tr["y_t"]) - 1e-4).max() < 3e-5


def test_sleigh_spinning_at_default_tolerances():
    tr = sleigh(0.0).run()
    assert tr.status == 0 and tr.t[-1] == 10.0
    assert np.abs(tr["theta"] - W * tr.t).max() < 1e-9
    assert np.abs(tr["x"]).max() == 0.0 and np.abs(tr["y"]).max() == 0.0


@pytest.mark.parametrize("method, rtol, bound", [("dop853", 1e-3, 1e-5),
                                                 ("radau", 1e-4, 0.03)])
def test_sleigh_circle_at_loose_tolerance(method, rtol, bound):
    """Loose tolerances: dop853 at 1e-3 stopped singular at the first edge, radau at
    1e-4 gained 10 % of the (constant) speed; now both keep to the circle."""
    tr = sleigh(0.2).run(method=method, rtol=rtol, atol=rtol)
    assert tr.status == 0 and len(tr.switches) == 19
    assert circle_error(tr, 0.2) < bound
    speed = np.hypot(tr["x_t"], tr["y_t"])
    assert np.abs(speed - 0.2).max() < 0.2 * bound


@pytest.mark.parametrize("n_steps, tol", [(60, 0.05), (120, 5e-3), (240, 5e-4)])
def test_rk4_sleigh_switches_on_its_grid(n_steps, tol):
    """rk4 with 18..72 steps a turn: the speed (exactly 0.2) and the circle to about
    RK4's order (before: 70 % of the speed lost at 18 steps a turn); every step no
    longer than h, the switches on the grid of h."""
    h = 10.0 / n_steps
    tr = sleigh(0.2).run(method="rk4", n_steps=n_steps)
    assert tr.status == 0 and tr.t[-1] == 10.0 and len(tr.switches) == 19
    assert np.diff(tr.t).max() <= h * (1 + 1e-12)
    assert circle_error(tr, 0.2) < tol
    assert abs(np.hypot(tr["x_t"][-1], tr["y_t"][-1]) - 0.2) < 0.2 * tol
    k = np.array([s["t"] for s in tr.switches]) / h
    assert np.abs(k - np.round(k)).max() < 1e-9


def test_rk4_knife_edge_coarse_steps_stay_bounded():
    """The flat knife edge (a circle of radius 0.5 at speed 0.5) with 8 rk4 steps a turn
    for 20 turns: before, status 0 with speeds of 1e53; the ensemble's row is the single
    run's."""
    sc = jn.Scene(models.get("knife_edge"), "chetaev",
                  params={"I": 1.0, "alpha": 0.0, "g": 9.81, "m": 1.0},
                  initial={"x": 0, "y": 0, "phi": 0, "x_t": 0.5, "phi_t": 1.0},
                  t_span=(0, 40 * np.pi))
    tr = sc.run(method="rk4", n_steps=160)
    assert tr.status == 0 and len(tr.switches) == 80
    speed = np.hypot(tr["x_t"], tr["y_t"])
    assert np.abs(speed - 0.5).max() < 0.1
    assert np.hypot(tr["x"][-1], tr["y"][-1]) < 0.1
    ens = sc.ensemble({"phi_t": [1.0, 1.0]}, method="rk4", n_steps=160, save="final")
    assert list(ens.status) == [0, 0]
    for name in ("x", "y", "x_t", "phi"):
        assert np.array_equal(ens.final_values()[name], [tr[name][-1]] * 2), name


def test_cartesian_pendulum_accuracy_follows_rtol():
    """The rotating pendulum in (x, y) (x_t(0) = 8, 80 switches in 20 s) against its
    angle form by scipy at rtol 1e-12: the error falls with rtol (before: ~4e-3 from
    rtol 1e-6 to 1e-8)."""
    T, v0 = 20.0, 8.0
    ref = solve_ivp(lambda t, s: [s[1], -9.81 * np.sin(s[0])], (0, T), [0.0, v0],
                    method="DOP853", rtol=1e-12, atol=1e-12, dense_output=True)
    sc = jn.Scene(pendulum_xy(), params={"l": 1.0, "G": 9.81},
                  initial={"x": 0.0, "y": -1.0, "x_t": v0}, t_span=(0, T))
    errors = []
    for rtol in (1e-6, 1e-8):
        tr = sc.run(rtol=rtol, atol=rtol)
        assert tr.status == 0 and len(tr.switches) > 70
        th = np.unwrap(np.arctan2(tr["x"], -tr["y"]))
        errors.append(np.abs(th - ref.sol(tr.t)[0]).max())
    assert errors[1] < 2e-4 and errors[1] < errors[0] / 20


@pytest.mark.parametrize("offset", [-100.0, 100.0])
def test_fixed_steps_without_the_edge_do_not_read_a_user_event_as_it(offset):
    """A fixed-step piece that goes on without watching the chart's edge (no better split
    there) has no stage check against it: its last event is the user's, whose sign says
    nothing of the chart (a user event x - 100, negative all along, once stopped such a
    piece "singular" at its first step)."""
    import sympy as sp

    from jetnh.numeric import atlas
    from jetnh.numeric.events import as_events

    scene = jn.Scene(models.knife_edge(), "chetaev", t_span=(0.0, 1.0),
                     initial=dict(x=0, y=0, phi=0, x_t=0.5, phi_t=0.3))
    user = as_events([jn.Event(sp.Symbol("x") + offset, direction=1)])
    plan = scene._plan(None, None, None, "rk4", "steps", user, None, None, False, None,
                       None, "stop", None, None, False, True, {"n_steps": 20})
    at = atlas.atlas(scene)
    parts, _ = atlas.follow(at, "rk4", at.own, 0.0, scene.y0.copy(), 1.0, scene._p, user,
                            np.zeros(1, np.int64), plan.ctl, 10**6, plan.te, plan.mode,
                            None, True, 1e-8, None, None, None, first=False, edge=False)
    out = parts[-1][1]
    assert int(out.status) == 0 and float(out.t) == 1.0 and int(out.stats[0]) == 20
