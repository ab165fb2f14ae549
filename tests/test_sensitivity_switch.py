"""Runs with sensitivities across the edge of their split (``numeric.atlas``): the run
watches its chart's edge, stops there in a few steps (it ground through the split's
singular set before) and goes on in another chart, S = dy(t)/d(y0, p) carried by the
derivative of the chart change (``Chart.carry``, compiled from the graph).  Checked
against central differences of plain runs (which switch too) and of the chart change
itself.

The system: the damped sleigh with its blade's contact point b ahead of the point the
constraint is written at, -sin(th) x_t + cos(th) y_t - b th_t = 0, b a runtime parameter
(the chart change depends on it, so S's parameter column gets D_p).  With y dependent
the chart's measure is cos(th)^2 / (1 + b^2): its edge (1/12, three splits) lies near
th = 1.27; the run goes on with x dependent.
"""

import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from hypothesis import given
from hypothesis import strategies as st

import jetnh as jn
from jetnh.numeric import atlas, interrupt, loops, solve
from jetnh.numeric.methods._common import EVENT

PARAMS = {"m": 2.0, "a": 0.3, "I": 0.5, "c": 0.1, "b": 0.1}
ORIGIN = {"x": 0.0, "y": 0.0, "th": 0.0}
TIGHT = {"rtol": 1e-12, "atol": 1e-13}


def offset_sleigh() -> jn.System:
    J = jn.JetSpace("x y th")
    x, y, th = J.q
    xd, yd, thd = J.qd
    m, a, I, c, b = sp.symbols("m a I c b", positive=True)
    L = (m / 2 * ((xd - a * sp.sin(th) * thd) ** 2 + (yd + a * sp.cos(th) * thd) ** 2)
         + I / 2 * thd ** 2)
    return jn.System(J, L, constraints=[-sp.sin(th) * xd + sp.cos(th) * yd - b * thd],
                     forces={th: -c * thd}, dependent=[y])


@pytest.fixture(scope="module", params=[("chetaev", None), ("vakonomic", "explicit")],
                ids=["chetaev", "vakonomic-explicit"])
def scene(request):
    principle, form = request.param
    initial = {**ORIGIN, "x_t": 0.3, "th_t": 2.5}
    if principle == "vakonomic":
        initial["lambda_y"] = 0.2
    return jn.Scene(offset_sleigh(), principle, params=PARAMS, initial=initial,
                    t_span=(0.0, 1.0), form=form, runtime_params=["b"])


def central(scene, y0, p, h=1e-6, t_eval=None):
    """dy/d(y0, p) of plain runs by central differences: [rows, n, n + n_p]."""
    def end(y, q):
        tr = scene.run(y0=y, params=q, t_eval=t_eval, **TIGHT)
        assert tr.status == 0 and tr.switches
        return tr.y if t_eval is not None else tr.y[-1:]

    cols = []
    for j in range(len(y0) + len(p)):
        e = np.zeros(len(y0) + len(p))
        e[j] = h
        cols.append((end(y0 + e[:len(y0)], p + e[len(y0):])
                     - end(y0 - e[:len(y0)], p - e[len(y0):])) / (2 * h))
    return np.stack(cols, axis=-1)


@given(th_t=st.floats(2.2, 4.0), x_t=st.floats(-0.5, 0.5), b=st.floats(0.05, 0.2))
def test_sensitivities_across_a_switch_are_central_differences(scene, th_t, x_t, b):
    y0 = scene.y0.copy()
    y0[scene.state_names.index("th_t")] = th_t
    y0[scene.state_names.index("x_t")] = x_t
    p = np.array([b])
    tr = scene.run(y0=y0, params=p, sensitivities=True, **TIGHT)
    assert tr.status == 0 and tr.switches
    assert tr.sensitivity_columns == scene.state_names + ("b",)
    S = tr.sensitivities[-1]
    D = central(scene, y0, p)[0]
    assert np.abs(S - D).max() < 1e-7 * max(1.0, np.abs(D).max())
    # the parameter's column: D_p of the chart change counts (without it it is off)
    assert np.abs(D[:, -1]).max() > 1e-3
    # the state is the plain run's
    assert np.abs(tr.y[-1] - scene.run(y0=y0, params=p, **TIGHT).y[-1]).max() < 1e-10


def test_sensitivities_at_output_times_and_between_rows(scene):
    """t_eval rows in both charts; the dense output of the every-step run (steps
    re-taken in each chart, S mapped home) gives the same S between its rows."""
    times = np.linspace(0.0, 1.0, 9)
    at_times = scene.run(t_eval=times, sensitivities=True, **TIGHT)
    assert at_times.switches and at_times.sensitivities.shape[0] == times.size
    D = central(scene, scene.y0.copy(), scene.p, t_eval=times)
    assert np.abs(at_times.sensitivities - D).max() < 1e-7 * max(1.0, np.abs(D).max())
    every = scene.run(sensitivities=True, **TIGHT)
    from jetnh.numeric.dense import evaluate

    seg = every._segments
    Y = seg.evaluate(every, times, full=True)
    n = len(scene.state_names)
    assert np.abs(Y[:, :n] - at_times.y).max() < 1e-10
    assert np.abs(Y[:, n:].reshape(at_times.sensitivities.shape)
                  - at_times.sensitivities).max() < 1e-8
    assert np.array_equal(evaluate(every, times), Y[:, :n])
    assert np.abs(every.at(times).to_numpy() - at_times.y).max() < 1e-10


def test_a_start_past_the_edge_starts_in_the_other_chart(scene):
    """th = 1.45 (cos^2 = 0.014 of a measure 1/12 at the edge): the run starts with x
    dependent, S(t0) = D there (the identity in the scene's states)."""
    y0 = scene.y0.copy()
    y0[scene.state_names.index("th")] = 1.45
    tr = scene.run(y0=y0, sensitivities=True, **TIGHT)
    assert tr.switches[0]["t"] == 0.0 and tr.switches[0]["to"] == ["x"]
    m = len(tr.sensitivity_columns)
    assert np.abs(tr.sensitivities[0] - np.eye(len(y0), m)).max() < 1e-12
    D = central(scene, y0, scene.p)[0]
    assert np.abs(tr.sensitivities[-1] - D).max() < 1e-7 * max(1.0, np.abs(D).max())


@given(th=st.floats(0.9, 1.4), xd=st.floats(-1.0, 1.0), thd=st.floats(-2.0, 2.0),
       lam=st.floats(-1.0, 1.0), b=st.floats(0.05, 0.3))
def test_chart_change_derivative_is_central_differences(scene, th, xd, thd, lam, b):
    """D = d(state with x dependent)/d(state with y dependent, b), compiled from the
    graph, against central differences of the chart change as the atlas makes it
    (``Chart.point`` then ``Chart.state_at``: the aux kernel's velocities, the
    multipliers through df/dqdot in the explicit form)."""
    at = atlas.atlas(scene)
    own = at.own
    y = np.array([0.1, -0.2, th, xd, thd] + [lam] * (len(scene.state_names) - 5))
    other = at.chart(("x",), 0.0, y)

    def change(y, p):
        point = own.point(0.3, np.ascontiguousarray(y), np.array([p]))
        return at.maps[("x",)].state_at(*point)

    S = np.eye(len(y), len(y) + 1)[None]
    D = own.carry(other, 0.3, y, S, np.array([b]))[0]
    h = 1e-6
    fd = np.empty_like(D)
    for j in range(len(y)):
        e = np.zeros(len(y))
        e[j] = h
        fd[:, j] = (change(y + e, b) - change(y - e, b)) / (2 * h)
    fd[:, -1] = (change(y, b + h) - change(y, b - h)) / (2 * h)
    assert np.abs(D - fd).max() < 1e-7 * max(1.0, np.abs(fd).max())
    if scene.principle == "chetaev":      # y_t = (sin th x_t + b th_t) / cos th
        row = list(other.scene.state_names).index("y_t")
        s_, c_ = np.sin(th), np.cos(th)
        assert D[row, 4] == pytest.approx(b / c_, rel=1e-12)
        assert D[row, 5] == pytest.approx(thd / c_, rel=1e-12)


def test_an_edge_stopped_run_stops_in_a_few_steps(scene):
    """The loop of a run with sensitivities (what connect's shooting calls) watches the
    edge of the scene's split as a terminal event: it stops there, at measure 1/12, in a
    few steps (in the split's singular set it took 128 633 steps); the run goes on in the
    other chart in a few more."""
    plan = solve.plan(scene, sensitivities=True)
    assert plan.switch and plan.ce.names[-1] == atlas.EDGE
    y = solve.augmented(scene, plan, scene.y0, scene.p)
    halt = np.zeros(1, dtype=np.int64)
    out = loops.result(interrupt.call(
        plan.entry, halt, None, (*plan.prefix, plan.t0, plan.t1, y, scene.p, *plan.suffix,
                                 halt)))
    assert int(out.status) == EVENT and int(out.ev_i[int(out.n_ev) - 1]) == len(plan.ce) - 1
    assert out.stats[0] < 40
    th = out.y[scene.state_names.index("th")]
    assert np.cos(th) ** 2 / (1 + PARAMS["b"] ** 2) == pytest.approx(atlas.atlas(scene).eps,
                                                                      rel=1e-6)
    tr = scene.run(sensitivities=True)
    assert tr.status == 0 and tr.switches and tr.diagnostics.steps < 100


def test_holonomic_sensitivities_across_two_switches():
    """The knife edge with a slider on g = z - a sin(th) = 0 (``holonomic_systems``):
    y dependent until cos(th) is small, then x, then y again; the projected
    sensitivities (``methods.projection``, also where the run reaches an edge) against
    central differences of plain runs, in initial values g does not involve, along
    g = 0 (th with z = a sin th) and in the runtime parameter k."""
    sys.path.insert(0, str(Path(__file__).parent))
    from holonomic_systems import KNIFE, knife_slider

    a = KNIFE["a"]
    ini = {"x": 0.1, "y": -0.2, "th": 0.3, "z": a * np.sin(0.3), "x_t": 1.0, "th_t": 2.0}
    sc = jn.Scene(knife_slider(), "chetaev", params=KNIFE, initial=ini, t_span=(0.0, 1.5),
                  runtime_params=["k"])
    kw = dict(rtol=1e-12, atol=1e-14)
    tr = sc.run(sensitivities=True, **kw)
    assert [s["to"] for s in tr.switches] == [["x", "z"], ["y", "z"]]
    names, y0, p, h = sc.state_names, sc.y0.copy(), sc.p.copy(), 1e-6

    def end(col, d):
        y, q = y0.copy(), p.copy()
        if col == "k":
            q[0] += d
        else:
            y[names.index(col)] += d
            if col == "th":                 # along g = 0
                y[names.index("z")] = a * np.sin(y[names.index("th")])
        run = sc.run(y0=y, params=q, save="final", **kw)
        assert len(run.switches) == 2
        return run.y[-1]

    S = tr.sensitivities[-1]
    col = {c: S[:, tr.sensitivity_columns.index(c)] for c in tr.sensitivity_columns}
    col["th"] = col["th"] + col["z"] * a * np.cos(ini["th"])
    for c in ("x", "y", "x_t", "th_t", "th", "k"):
        fd = (end(c, h) - end(c, -h)) / (2 * h)
        assert np.abs(col[c] - fd).max() < 1e-7, c
