"""The start of the step in which a piece stopped at its chart's edge (or singular), as
the loops give it (row ``n_out`` of a stopped run: ``loop._solve``, ``radau``), is the
one the piece's rows give when the same loop runs again keeping every step: the same
time and state, bit for bit, for every method that switches charts and every way of
saving (every step, the two ends, ``t_eval``), over the runs that cross edges."""

import numpy as np
import pytest

import jetnh as jn
from jetnh import models
from jetnh.numeric import atlas
from jetnh.numeric.codegen import multiplier_names
from jetnh.numeric.methods._common import EVERY_STEP

W = 3.0


def rerun_step_start(chart, method, out, t, y, t_to, p, ctl, mode, newton, ce, watch, sens,
                     direction):
    """The step's start from the rows of the piece run again keeping every step (the
    independent route: no row ``n_out``)."""
    t_stop = float(out.t)
    if mode != EVERY_STEP:
        out, _ = chart.call(method, ce, watch, t, t_to, y, p, ctl, atlas._NO_TIMES,
                            EVERY_STEP, newton, None, sens, None)
    ts, n = out.ts, int(out.n_out)
    k = n - 1
    while k >= 0 and not direction * (t_stop - ts[k]) > 0.0:
        k -= 1
    if k <= 0:
        return t, np.ascontiguousarray(y), t_stop - t
    return float(ts[k]), np.ascontiguousarray(out.ys[k, :y.shape[0]]), t_stop - float(ts[k])


@pytest.fixture
def compared(monkeypatch):
    """``atlas._step_start`` checked against ``rerun_step_start`` at every call; the
    list of (t_k, span) it gave."""
    given = []
    loop_start = atlas._step_start

    def both(chart, method, out, t, y, t_to, p, ctl, mode, newton, ce, watch, sens,
             direction, halt):
        t_k, y_k, span = loop_start(chart, method, out, t, y, t_to, p, ctl, mode, newton,
                                    ce, watch, sens, direction, halt)
        r_t, r_y, r_span = rerun_step_start(chart, method, out, t, y, t_to, p, ctl, mode,
                                            newton, ce, watch, sens, direction)
        assert t_k == r_t and span == r_span
        assert y_k.shape == r_y.shape and np.array_equal(y_k, r_y)
        given.append((t_k, span))
        return t_k, y_k, span

    monkeypatch.setattr(atlas, "_step_start", both)
    # (every run piece by piece in Python: ``chart_driver``'s step starts are compared
    # with these in tests/test_atlas_driver.py)
    monkeypatch.setattr(atlas, "_driven", lambda *args: None)
    return given


def sleigh(x_t, T=10.0):
    return jn.Scene(models.get("chaplygin_sleigh"), "chetaev",
                    params={"I": 0.5, "a": 0.0, "m": 2.0},
                    initial={"x": 0, "y": 0, "theta": 0.0, "x_t": x_t, "theta_t": W},
                    t_span=(0, T))


def panel_scene(model, principle, T):
    """A switching run of the work-precision panels (their initial state; multipliers
    0.1, -0.1, ..)."""
    system = models.get(model)
    lam = {name: 0.1 * (-1) ** i
           for i, name in enumerate(multiplier_names(system, principle))}
    return jn.Scene(system, principle, initial={**models.initial(model), **lam},
                    t_span=(0.0, T))


def run_all(scene, given, **options):
    """The run in every way of saving (every step, the two ends, 9 points of ``t_eval``
    but with fixed steps): the same switches, final state and step starts."""
    saves = [dict(save="steps"), dict(save="final")]
    if "n_steps" not in options:
        saves.append(dict(t_eval=np.linspace(0, scene.t_span[1], 9)))
    ends, starts = [], []
    for save in saves:
        del given[:]
        tr = scene.run(**options, **save)
        assert tr.status == 0 and tr.switches
        ends.append((tr.switches, np.array(tr.y[-1])))
        starts.append(list(given))
    assert given, "no step reached an edge"
    for (sw, y_end), st in zip(ends[1:], starts[1:]):
        assert sw == ends[0][0] and np.array_equal(y_end, ends[0][1]) and st == starts[0]


@pytest.mark.parametrize("method", ["dop853", "dopri5", "radau"])
def test_adaptive_sleigh_spinning(compared, method):
    run_all(sleigh(1e-4, T=1.6), compared, method=method, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("method, tol", [("dop853", 1e-3), ("dopri5", 1e-8),
                                         ("radau", 1e-4)])
def test_adaptive_sleigh_circle(compared, method, tol):
    run_all(sleigh(0.2, T=1.6), compared, method=method, rtol=tol, atol=tol)


@pytest.mark.parametrize("n_steps", [10, 60])
def test_rk4_sleigh(compared, n_steps):
    run_all(sleigh(0.2, T=1.6), compared, method="rk4", n_steps=n_steps)


@pytest.mark.parametrize("model, principle, T", [("chaplygin_sleigh", "chetaev", 2.0),
                                                 ("chaplygin_sleigh", "vakonomic", 2.0),
                                                 ("knife_edge", "vakonomic", 0.8)])
@pytest.mark.parametrize("method", ["dop853", "dopri5"])
def test_switching_panels(compared, model, principle, T, method):
    """The three work-precision panels whose runs cross an edge, at their tolerances."""
    sc = panel_scene(model, principle, T)
    for tol in (1e-3, 1e-6, 1e-9):
        run_all(sc, compared, method=method, rtol=tol, atol=tol * 1e-3)
