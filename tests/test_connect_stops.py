"""Why connect's shooting runs stopped before t1, named in its ``ConnectError``:

* a stiff motion (x'' = -c x' - x, c = 1e6: dop853's Hairer test stops every run as
  STIFF after a few thousand steps) -- "stopped as stiff" at the time it stopped, and
  what connect's explicit integrators cannot do;
* a run that crawls toward a singular set: Suslov's equations (the paper's convention,
  which cannot change split) for a sleigh in centre-of-mass coordinates with
  dependent=[Y] run into cos(th) = 0; a shooting run that does not watch the split's
  edge crawls there until the loop stops it, counted and named as a crawl (the
  indicator's value relative to its start, checked against cos(th) itself).
"""

import math

import numpy as np
import pytest
import sympy as sp

import jetnh as jn
from jetnh.errors import ConnectError
from jetnh.numeric import Status
from jetnh.numeric.connect.problem import Unknowns, _scene
from jetnh.numeric.connect.solve import Search

SLEIGH_PARAMS = {"m": 2.0, "I": 0.7, "a": 0.4}
SLEIGH_START = {"X": 0.1, "Y": -0.2, "th": 0.3}


@pytest.fixture(scope="module")
def damped():
    J = jn.JetSpace("x")
    (x,), (xd,) = J.q, J.qd
    c = sp.Symbol("c", positive=True)
    return jn.System(J, xd**2 / 2 - x**2 / 2, forces={"x": -c * xd})


@pytest.fixture(scope="module")
def sleigh():
    J = jn.JetSpace("X Y th")
    _, _, th = J.q
    Xt, Yt, tht = J.qd
    m, inertia, a = sp.symbols("m I a", positive=True)
    L = m / 2 * (Xt**2 + Yt**2) + inertia / 2 * tht**2
    f = [-sp.sin(th) * Xt + sp.cos(th) * Yt - a * tht]
    return jn.System(J, L, f, dependent=[J.q[1]])


def test_a_stiff_motion_is_named_as_stiff(damped):
    with pytest.raises(ConnectError) as err:
        jn.connect(damped, "chetaev", {"x": 1.0}, {"x": 0.5}, (0.0, 10.0),
                   params={"c": 1e6}, timeout=60)
    msg = str(err.value)
    assert err.value.best is None
    assert " stopped as stiff (the last at t = " in msg and "method='radau'" in msg
    assert "crawled" not in msg and "singular" not in msg.split("stopped as stiff")[1][:200]
    # every run stopped as stiff: "n of the n runs stopped before t1: n stopped as stiff"
    head = msg.split(" runs stopped before t1: ")[0].split("; ")[-1]
    k, _, _, n = head.split()
    assert k == n and f"{k} stopped as stiff" in msg
    # the time named is where scene.run stops as stiff from such a start
    t_named = float(msg.split("stopped as stiff (the last at t = ")[1].split(":")[0])
    assert 0.0 < t_named < 0.1


def _shooter(system, end):
    shape = Unknowns.of(system, "suslov")
    scene = _scene(system, "suslov", SLEIGH_PARAMS,
                   {**SLEIGH_START, **{u: 0.0 for u in shape.unknowns}, **shape.fixed},
                   (0.0, 3.0))
    return Search(scene, SLEIGH_START, end, shape.unknowns, shape.fixed, 1e-11, 1e-12,
                  "dop853", 1e-9)


def test_a_crawl_toward_a_singular_set_is_named_as_such(sleigh):
    sh = _shooter(sleigh, {"X": 1.0, "th": 2.5})
    sh.watch_edge = False            # the runs as they were: into the singular set
    u = np.array([0.8, 0.5])
    assert sh.run(u) is None
    assert sh.stops == {Status.SINGULAR: 1, "crawl": 1, "edge": 1}
    t, y, _, index, plan = sh.last_stops["crawl"]
    th = y[sh.scene.state_names.index("th")]
    assert plan.kern.layout.indicators[index] == "cos(th)" and 1.3 < t < 1.321
    # the relative value named is cos(th) there over cos(th) at the start
    rel = math.cos(th) / math.cos(SLEIGH_START["th"])
    assert 0 < rel < 1e-2
    note = sh.stops_note()
    assert note.startswith("1 of the 1 runs stopped before t1: 1 crawled toward the "
                           "singular set cos(th) = 0 and stopped there (the last at t = ")
    named = float(note.split(f"where cos(th) is ")[1].split(" ")[0])
    assert named == pytest.approx(rel, rel=1e-2)
    assert "stiff" not in note and "1 of them stopped at the edge" in note


def test_the_scene_run_stops_where_the_shot_does(sleigh):
    """The same run by ``scene.run`` (with sensitivities): SINGULAR, as a crawl."""
    sh = _shooter(sleigh, {"X": 1.0, "th": 2.5})
    sh.watch_edge = False
    assert sh.run(np.array([0.8, 0.5])) is None
    t = sh.last_stops["crawl"][0]
    tr = sh.scene.run(y0=sh.state(np.array([0.8, 0.5])), rtol=1e-11, atol=1e-12,
                      sensitivities=True)
    assert tr.status == Status.SINGULAR and "cannot step closer" in tr.stop_reason
    assert tr.t[-1] == pytest.approx(t, abs=1e-12)


def test_a_shot_that_cannot_change_split_stops_at_its_edge(sleigh):
    """The default shooter watches the edge of the split (Suslov's runs cannot change
    split): the same run stops as a terminal event where cos(th)^2 = EDGE_STOP (1 +
    a^2) (the measure det(A_Y)^2 / det(A A^T) with A = (-sin th, cos th, -a)), counted
    as "edge", never as a crawl; connect's error then names the edge alone."""
    from jetnh.numeric.connect.shooting import EDGE_STOP

    sh = _shooter(sleigh, {"X": 1.0, "th": 2.5})
    assert sh.run(np.array([0.8, 0.5])) is None
    assert sh.stops == {Status.EVENT: 1, "edge": 1}
    t, y, *_ = sh.last_stops[Status.EVENT]
    th = y[sh.scene.state_names.index("th")]
    a = SLEIGH_PARAMS["a"]
    assert math.cos(th) ** 2 == pytest.approx(EDGE_STOP * (1 + a * a), rel=1e-8)
    crawl = _shooter(sleigh, {"X": 1.0, "th": 2.5})
    crawl.watch_edge = False
    assert crawl.run(np.array([0.8, 0.5])) is None
    assert t < crawl.last_stops["crawl"][0] - 1e-3           # before the crawl
    with pytest.raises(ConnectError) as err:
        jn.connect(sleigh, "suslov", SLEIGH_START, {"X": 1.0, "th": 2.5}, (0.0, 3.0),
                   params=SLEIGH_PARAMS, timeout=60)
    msg = str(err.value)
    assert "runs stopped at the edge of the scene's split (dependent velocities Y_t" in msg
    assert "crawled" not in msg and "stiff" not in msg


def test_runs_that_change_split_watch_no_extra_edge():
    """Chetaev's runs change split at their edge (the atlas): no event of the
    shooter's own (the damped sleigh's plan is the atlas's)."""
    import sys
    from pathlib import Path

    from jetnh.numeric.connect.shooting import edge_event

    sys.path.insert(0, str(Path(__file__).parent))
    from damped_sleigh import ORIGIN, PARAMS, damped_sleigh

    scene = jn.Scene(damped_sleigh(), "chetaev", params=PARAMS, t_span=(0.0, 1.0),
                     initial={**ORIGIN, "x_t": 0.2, "th_t": 2.5})
    assert edge_event(scene) is None


def test_a_motion_that_stays_off_the_edge_is_found_and_shows_no_edge(sleigh):
    """An end the Suslov motion reaches before cos(th) = 0 (its own run from X_t =
    0.8, th_t = 0.5 to T = 1): connect finds those velocities, and its trajectory
    reports no event (the edge it watched is the shooter's, not the user's)."""
    shape = Unknowns.of(sleigh, "suslov")
    scene = _scene(sleigh, "suslov", SLEIGH_PARAMS,
                   {**SLEIGH_START, **{u: 0.0 for u in shape.unknowns}, **shape.fixed},
                   (0.0, 3.0))
    run = scene.run(y0={**SLEIGH_START, "X_t": 0.8, "th_t": 0.5, **shape.fixed},
                    t_span=(0.0, 1.0), rtol=1e-12, atol=1e-13)
    assert run.status == Status.FINISHED
    end = {"X": float(run["X"][-1]), "th": float(run["th"][-1])}
    c = jn.connect(sleigh, "suslov", SLEIGH_START, end, (0.0, 1.0), params=SLEIGH_PARAMS)
    assert abs(c.initial["X_t"] - 0.8) < 1e-8 and abs(c.initial["th_t"] - 0.5) < 1e-8
    tr = c.trajectory
    assert tr.status == Status.FINISHED and tr.event_names == () and tr.t_events == []
