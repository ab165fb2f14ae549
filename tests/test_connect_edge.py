"""connect where the motion crosses the edge of the scene's split: the damped sleigh
(y dependent, singular at cos th = 0) from th = 0 to th = 2.0, past pi / 2.  Its
shooting runs carry their sensitivities across the switch (``Shot._across``), so Newton
goes from the straight line; checked against scipy's least_squares around scene.run
(plain runs, which change split too, and finite differences) -- an independent route.
"""

import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import simpson
from scipy.optimize import least_squares

import jetnh as jn

sys.path.insert(0, str(Path(__file__).parent))
from damped_sleigh import ORIGIN, PARAMS, damped_sleigh  # noqa: E402

TIGHT = {"rtol": 1e-12, "atol": 1e-13}


@pytest.fixture(scope="module")
def sleigh():
    return damped_sleigh()


def _least_squares(scene, unknowns, end, guess):
    def miss(u):
        tr = scene.run(y0={**ORIGIN, **dict(zip(unknowns, u))}, **TIGHT)
        assert tr.status == 0
        return [tr[c][-1] - v for c, v in end.items()]

    fit = least_squares(miss, guess, xtol=1e-15, ftol=1e-15, gtol=1e-15)
    assert np.abs(fit.fun).max() < 1e-10
    return fit.x


@pytest.mark.parametrize("principle, end, unknowns", [
    ("chetaev", {"x": 0.2, "th": 2.0}, ("x_t", "th_t")),
    ("vakonomic", {"x": 0.2, "y": 0.5, "th": 2.0}, ("x_t", "th_t", "lambda_y"))])
def test_connect_across_the_edge_is_least_squares_on_scene_run(sleigh, principle, end,
                                                              unknowns):
    c = jn.connect(sleigh, principle, ORIGIN, end, (0.0, 1.0), params=PARAMS, tol=1e-10)
    assert c.residual < 1e-10
    tr = c.trajectory
    assert tr.switches and tr.switches[0]["from"] == ["y"] and tr.switches[0]["to"] == ["x"]
    assert abs(tr["th"][-1] - 2.0) < 1e-10 and tr.status == 0
    scene = jn.Scene(sleigh, principle, params=PARAMS, t_span=(0.0, 1.0),
                     initial={**ORIGIN, **{u: 0.0 for u in unknowns}})
    u = _least_squares(scene, unknowns, end, [c.initial[k] for k in unknowns])
    # from the straight line too: the same motion
    line = [end["x"], end["th"]] + [0.0] * (len(unknowns) - 2)
    assert np.abs(_least_squares(scene, unknowns, end, line) - u).max() < 1e-8
    assert max(abs(c.initial[k] - u[i]) for i, k in enumerate(unknowns)) < 1e-8
    # the verdicts on the stitched motion: the endpoint map has full rank, no conjugate
    # time; the cost is the action of the plain run (Simpson's rule on a fine t_eval,
    # L written out here)
    assert c.normal is True and c.conjugate_times == ()
    assert c.rank == len(unknowns)
    fine = scene.run(y0={**ORIGIN, **dict(zip(unknowns, u))}, **TIGHT,
                     t_eval=np.linspace(0.0, 1.0, 4001))
    assert fine.switches
    m, a, inertia = PARAMS["m"], PARAMS["a"], PARAMS["I"]
    th, xd, yd, thd = (np.asarray(fine[k]) for k in ("th", "x_t", "y_t", "th_t"))
    L = (m / 2 * ((xd - a * np.sin(th) * thd) ** 2 + (yd + a * np.cos(th) * thd) ** 2)
         + inertia / 2 * thd ** 2)
    assert c.cost == pytest.approx(simpson(L, x=fine.t), abs=1e-9)


def test_the_answers_sensitivities_are_central_differences(sleigh):
    """dq(t1)/du of the answer (the stitched run's S in the scene's states) against
    central differences of plain runs; the shooting Jacobian is its block."""
    end = {"x": 0.2, "th": 2.0}
    c = jn.connect(sleigh, "chetaev", ORIGIN, end, (0.0, 1.0), params=PARAMS)
    u = np.array([c.initial["x_t"], c.initial["th_t"]])
    scene = jn.Scene(sleigh, "chetaev", params=PARAMS, t_span=(0.0, 1.0),
                     initial={**ORIGIN, "x_t": u[0], "th_t": u[1]})
    tr = scene.run(sensitivities=True, **TIGHT)
    assert tr.switches
    h = 1e-6

    def q(v):
        run = scene.run(y0={**ORIGIN, "x_t": v[0], "th_t": v[1]}, **TIGHT)
        return np.array([run[k][-1] for k in ("x", "y", "th")])

    fd = np.array([(q(u + h * e) - q(u - h * e)) / (2 * h) for e in np.eye(2)]).T
    S = np.array([[tr.sensitivity(a, b)[-1] for b in ("x_t", "th_t")]
                  for a in ("x", "y", "th")])
    assert np.abs(S - fd).max() < 1e-7
    assert np.allclose(sorted(c.singular_values), sorted(np.linalg.svd(
        S[[0, 2]], compute_uv=False)), rtol=1e-6)


@pytest.mark.parametrize("th0", [0.0, 1.45], ids=["crossing", "past-the-edge-at-t0"])
def test_a_shot_across_the_edge_is_the_scenes_run(sleigh, th0):
    """A shooting run that reaches the edge of the scene's split (or starts past it)
    goes on as scene.run does: the Shot's end and sensitivities are the stitched run's,
    bit for bit, and its Trajectory is that run."""
    from jetnh.numeric import solve
    from jetnh.numeric.connect.problem import _scene
    from jetnh.numeric.connect.solve import Search

    start = {**ORIGIN, "th": th0}
    scene = _scene(sleigh, "chetaev", PARAMS, {**start, "x_t": 0.0, "th_t": 0.0},
                   (0.0, 1.0))
    sh = Search(scene, start, {"x": 0.2, "th": 2.0}, ("x_t", "th_t"), {}, 1e-10, 1e-12,
                "dop853", 1e-9)
    for save in ("steps", "final"):
        y = sh.state(np.array([0.3, 2.5]))
        shot = sh.start(y.copy(), sh.span, save)
        tr = solve.run(scene, sh.plan(sh.span, save), y.copy(), scene._p)
        assert tr.status == 0 and tr.switches and shot is not None
        assert shot.t == tr.t[-1] and np.array_equal(shot.y, tr.y[-1])
        assert np.array_equal(shot.S, tr.sensitivities[-1])
        assert np.array_equal(shot.trajectory.y, tr.y)
        assert shot.trajectory.switches == tr.switches
