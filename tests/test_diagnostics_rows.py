"""Over which rows a run's diagnostics are taken.

- ``save="final"`` stores t0 and the end alone: the residual and energy figures are then
  end-point differences, which the diagnostics say (``rows``, ``saved``, the printed
  summary).  On an inclined knife edge the drift over every step is 75 times the
  end-point one: the two figures are checked against the energy column of the run that
  stored every step (the rows of both runs are the same bits).
- A run stopped at a singular configuration keeps as its last row the stop, next to the
  singular set, where the dependent velocities are a near 0/0 (the Cartesian pendulum
  in the split y dependent stops at y = -1e-10 with y_t = 156 where the motion has
  6.66, from energy conservation): that row is left out of the figures and reported
  apart (``stop_row``), by single runs, ensembles and sweeps alike.
"""

import math

import numpy as np
import pytest
import sympy as sp

import jetnh as jn
from jetnh import models


@pytest.fixture(scope="module")
def knife():
    return jn.Scene(models.get("knife_edge"), "chetaev",
                    params={"I": 1.0, "alpha": 0.3, "g": 9.81, "m": 1.0},
                    initial={"x": 0.1, "y": 0.0, "phi": 0.2, "x_t": 0.5, "phi_t": 0.3},
                    t_span=(0, 30.0))


@pytest.fixture(scope="module")
def pendulum():
    J = jn.JetSpace("x y")
    x, y = J.q
    xt, yt = J.qd
    G, l = sp.symbols("G l", positive=True)
    system = jn.System(J, (xt**2 + yt**2) / 2 - G * y, [x**2 + y**2 - l**2])
    return jn.Scene(system, params={"l": 1.0, "G": 9.81},
                    initial={"x": 0.0, "y": -1.0, "x_t": 8.0}, t_span=(0, 1))


def test_save_final_is_an_end_point_difference_and_says_so(knife):
    steps = knife.run()
    final = knife.run(save="final")
    E = steps.energy
    d, f = steps.diagnostics, final.diagnostics
    assert (d.saved, d.rows) == ("steps", len(steps))
    assert d.energy_drift == np.max(np.abs(E - E[0]))
    assert (f.saved, f.rows) == ("final", 2) and len(final) == 2
    assert f.energy_drift == abs(E[-1] - E[0])          # the same end, bit for bit
    # the largest difference over the rows against the end's alone (1.6e-8 against
    # 1.5e-8 here; they differ wherever the drift is largest before the end)
    assert d.energy_drift >= f.energy_drift
    assert "over 2 rows (save='final')" in str(f) and f"its {d.steps} steps" in str(f)
    assert "these figures" not in str(d)
    html = final._repr_html_()       # the notebook view says it too
    assert "over 2 rows (save=&#x27;final&#x27;)" in html
    assert "these figures" not in steps._repr_html_()
    sampled = knife.run(t_eval=np.linspace(0, 30, 31)).diagnostics
    assert (sampled.saved, sampled.rows) == ("t_eval", 31)
    assert "over 31 rows (t_eval)" in str(sampled)
    # the ensemble's and the sweep's figure is the end-point one
    ens = knife.ensemble(initial={"phi_t": [0.3]}, save="final")
    assert ens.energy_drift[0] == pytest.approx(f.energy_drift, rel=1e-6)


@pytest.mark.parametrize("method, saved", [("radau", "final"), ("scipy-RK45", "steps")])
def test_saved_without_dense_output(knife, method, saved):
    """Methods without a re-takeable dense output: told by the rows against the steps."""
    tr = knife.run(method=method, save="final" if saved == "final" else "steps",
                   t_span=(0, 3.0))
    assert tr.diagnostics.saved == saved and tr.diagnostics.rows == len(tr)


def _speed_at(tr, row):
    """|y_t| the motion has at ``row`` by energy conservation: x_t^2 + y_t^2 =
    2 (E0 + G y), x_t from the constraint's own solution x x_t + y y_t = 0 (x_t ~ 0 at
    y ~ 0, where the split x independent is regular)."""
    E0 = tr.energy[0]
    return math.sqrt(2 * (E0 + 9.81 * tr["y"][row]) - tr["x_t"][row] ** 2)


@pytest.mark.parametrize("method", ["dop853", "scipy-DOP853"])
def test_singular_stop_row_left_out_of_the_figures(pendulum, method):
    tr = pendulum.run(method=method, rtol=1e-9, atol=1e-9, split="fixed")
    assert tr.status == jn.numeric.SINGULAR
    d = tr.diagnostics
    E = tr.energy
    # the row is kept: where the run stopped, with its 0/0-evaluated velocity
    assert abs(tr["y"][-1]) < 1e-9 and tr.t[-1] == d.stop_row["t"] == tr.t_final
    assert abs(tr["y_t"][-1]) > 10 * _speed_at(tr, -1)          # 156 against 6.66
    # ... and left out of the figures, reported apart
    assert d.rows == len(tr) - 1
    assert d.energy_drift == np.max(np.abs(E[:-1] - E[0])) < 1e-6
    assert d.energy_drift_relative == d.energy_drift / abs(E[0])
    assert d.stop_row["energy_drift"] == abs(E[-1] - E[0]) > 1e3
    assert d.residual_max == np.max(np.abs(tr.residual[:-1]))
    text = str(d)
    assert "leave out the last row, the singular stop" in text
    assert f"energy drift {d.stop_row['energy_drift']:.3e}" in text
    assert f"drift {d.energy_drift:.3e}" in text


def test_a_stop_after_the_last_row_leaves_out_nothing(pendulum):
    """With t_eval the stop is after the last row: every row counts."""
    tr = pendulum.run(rtol=1e-9, atol=1e-9, split="fixed", t_eval=np.linspace(0, 1, 11))
    d = tr.diagnostics
    assert tr.status == jn.numeric.SINGULAR and tr.t_final > tr.t[-1]
    assert d.stop_row is None and d.rows == len(tr)
    assert d.energy_drift == np.max(np.abs(tr.energy - tr.energy[0]))


def test_ensemble_and_sweep_leave_the_stop_row_out(pendulum):
    opts = dict(split="fixed", rtol=1e-9, atol=1e-9)
    ens = pendulum.ensemble(initial={"x_t": [8.0, 1.0]}, save="final", **opts)
    assert list(ens.status) == [jn.numeric.SINGULAR, 0]
    # run 0's one row is its singular stop: no figure; run 1 swings, regular
    assert np.isnan(ens.energy_drift[0]) and np.isnan(ens.residual_max[0])
    assert np.isnan(ens.holonomic_residual_max[0])
    one = pendulum.run(y0={"x_t": 1.0}, save="final", **opts)
    assert ens.energy_drift[1] == pytest.approx(one.diagnostics.energy_drift, abs=1e-14)
    assert 0 < ens.energy_drift[1] < 1e-8
    sampled = pendulum.ensemble(initial={"x_t": [8.0, 1.0]},
                                t_eval=np.linspace(0, 1, 11), **opts)
    single = pendulum.run(t_eval=np.linspace(0, 1, 11), **opts).diagnostics
    assert sampled.energy_drift[0] == single.energy_drift < 1e-6
    table = jn.sweep(pendulum, {"x_t": [8.0, 1.0]}, **opts)
    assert np.isnan(table["energy_drift"].iloc[0])
    assert table["energy_drift"].iloc[1] == pytest.approx(ens.energy_drift[1], abs=1e-14)


def test_energy_zero_at_the_start_has_no_relative_drift():
    """A run whose energy is 0 at its start (a body released at rest where its potential
    is counted from) has no scale for a relative drift: NaN, said in words, never
    drift / 1e-300."""
    J = jn.JetSpace("q")
    (q,), (q_t,) = J.q, J.qd
    scene = jn.Scene(jn.System(J, q_t**2 / 2 - sp.Rational(3, 7) * q),
                     initial={"q": 0.0, "q_t": 0.0}, t_span=(0, 3))
    d = scene.run(method="rk4", n_steps=7).diagnostics
    assert d.energy_initial == 0.0 and d.energy_drift > 0.0
    assert np.isnan(d.energy_drift_relative)
    assert "relative: undefined" in str(d) and "e+2" not in str(d)
