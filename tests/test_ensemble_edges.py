"""Ensemble runs that change split (``numeric.atlas``) are the single runs, bit for bit.

The knife edge from phi = 0 with phi_t = 1 leaves its home split (y dependent) near
phi = 1.21 and comes back near phi = 2.78 (two switches on [0, 3]).  Two cases a single
run handled and an ensemble did not:

- rows at ``t_eval`` that all lie before the run's last switch (its last piece has no
  rows): the ensemble's final time and state come from that piece's loop, not its rows;
- ``sensitivities=True``: the runs watch their chart's edge and go on across it with S
  carried by the chart change (``Chart.carry``), as ``Scene.run`` does.
"""

import numpy as np
import sympy as sp
import pytest

import jetnh as jn
from jetnh import models
from jetnh.cli import main

INIT = {"x": 0.0, "y": 0.0, "phi": 0.0, "x_t": 1.0, "phi_t": 1.0}


@pytest.fixture(scope="module")
def knife():
    return jn.Scene(models.get("knife_edge"), "chetaev", initial=INIT, t_span=(0, 3.0))


def single(scene, phi_t, **kw):
    return scene.replace(initial={**INIT, "phi_t": phi_t}).run(**kw)


def same_bits(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape
    assert np.array_equal(a.view(np.int64), b.view(np.int64)), (a, b)


def assert_run(ens, r, tr):
    """Run ``r`` of ``ens`` against the single run ``tr``: rows, counts, status."""
    n = len(tr.t)
    same_bits(ens.t[r, :n], tr.t)
    same_bits(ens.y[r, :n], tr.y)
    assert np.all(np.isnan(ens.t[r, n:]))
    assert (ens.status[r], ens.steps[r], ens.rejected[r], ens.nfev[r], ens.rows[r]) == (
        tr.status, tr._info["steps"], tr._info["rejected"], tr._info["nfev"], n)
    assert ens.stop_reason(r) == tr.stop_reason
    assert list(ens.switches[r]) == list(tr.switches)
    same_bits(ens.aux[r, :n], tr.aux)


@pytest.mark.parametrize("te", [[1.0], [2.0], [1.0, 2.0], [0.5, 2.9]])
def test_rows_before_the_last_switch(knife, te):
    phi_t = [1.0, 0.5, 2.0]
    ens = knife.ensemble(initial={"phi_t": np.array(phi_t)}, t_eval=te)
    full = knife.ensemble(initial={"phi_t": np.array(phi_t)})      # save="final"
    for r, v in enumerate(phi_t):
        tr = single(knife, v, t_eval=te)
        assert len(tr.switches) == {1.0: 2, 0.5: 1, 2.0: 4}[v]
        assert_run(ens, r, tr)
        # the final time and state: the end of the run, as with save="final"
        same_bits(ens.t_final[r], 3.0)
        same_bits(ens.y_final[r], full.y_final[r])
        same_bits(full.y_final[r], single(knife, v).y[-1])


def test_sweep_and_cli_with_times_before_the_last_switch(knife, capsys):
    df = jn.sweep(knife, {"phi_t": [0.5, 1.0, 2.0]}, times=[1.0, 2.9])
    for i, v in enumerate([0.5, 1.0, 2.0]):
        tr = single(knife, v, t_eval=[1.0, 2.9])
        row = df.iloc[i]
        for j, t in enumerate([1.0, 2.9]):
            for name in ("x", "phi", "y_t"):            # (y_t: an aux row of a chart)
                same_bits(row[f"{name}(t={t:g})"], tr[name][j])
        assert (row["status"], row["steps"], row["switches"], row["t_final"]) == (
            tr.status, tr._info["steps"], len(tr.switches), 3.0)
    code = main(["sweep", "knife_edge", "--grid", "phi_t=0.5:2:3", "--t-end", "3",
                 "--times", "1.0"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "internal error" not in err


@pytest.mark.parametrize("rtol", [1e-8, 1e-11])
def test_sensitivities_switch_as_single_runs(knife, rtol):
    te = np.linspace(0, 3.0, 7)
    phi_t = [1.0, 1.001, 0.5]
    kw = dict(sensitivities=True, rtol=rtol, atol=1e-12, t_eval=te)
    ens = knife.ensemble(initial={"phi_t": np.array(phi_t)}, **kw)
    assert ens.sensitivity_columns
    for r, v in enumerate(phi_t):
        tr = single(knife, v, **kw)
        assert len(tr.switches) == (1 if v == 0.5 else 2)
        assert_run(ens, r, tr)
        assert ens.sensitivity_columns == tr.sensitivity_columns
        same_bits(ens.sensitivities[r], tr.sensitivities)
    one = knife.ensemble(initial={"phi_t": np.array([1.0])}, **kw)
    same_bits(one.sensitivities[0], ens.sensitivities[0])
    same_bits(one.y[0], ens.y[0])


def test_sensitivities_across_the_switches_are_derivatives(knife):
    """Second route: dx/dphi_t by central differences of plain runs (which switch)."""
    te = np.linspace(0, 3.0, 7)
    ens = knife.ensemble(initial={"phi_t": np.array([1.0])}, sensitivities=True,
                         rtol=1e-11, atol=1e-12, t_eval=te)
    assert len(ens.switches[0]) == 2
    h = 1e-6
    fd = (single(knife, 1 + h, rtol=1e-12, atol=1e-13, t_eval=te)["x"]
          - single(knife, 1 - h, rtol=1e-12, atol=1e-13, t_eval=te)["x"]) / (2 * h)
    np.testing.assert_allclose(ens.sensitivity("x", "phi_t")[0], fd, atol=1e-6)


def test_sensitivities_from_past_the_edge(knife):
    """Runs that start past their split's edge begin in another chart with S(t0)
    carried there, as the single run does."""
    phis = [1.4, 0.0]
    kw = dict(sensitivities=True, rtol=1e-10, atol=1e-12, t_eval=np.linspace(0, 3, 5))
    ens = knife.ensemble(initial={"phi": np.array(phis)}, **kw)
    for r, phi in enumerate(phis):
        tr = knife.replace(initial={**INIT, "phi": phi}).run(**kw)
        assert_run(ens, r, tr)
        same_bits(ens.sensitivities[r], tr.sensitivities)
    assert ens.switches[0][0]["t"] == 0.0


def test_holonomic_pendulum_with_sensitivities_switches_as_single_runs():
    """A holonomic constraint (rows moved onto g = 0) and many switches: the pendulum
    x^2 + y^2 = l^2 whirling over the top changes split at every quarter turn."""
    import math

    import sympy as sp

    J = jn.JetSpace("x y")
    (x, y), (xt, yt) = J.q, J.qd
    G, l = sp.symbols("G l", positive=True)
    pend = jn.System(J, (xt**2 + yt**2) / 2 - G * y, [x**2 + y**2 - l**2])
    init = {"x": math.sin(0.3), "y": -math.cos(0.3), "x_t": 7.0}
    sc = jn.Scene(pend, "chetaev", params={"G": 9.81, "l": 1.0}, initial=init,
                  t_span=(0, 2.0), runtime_params=["G"])
    for kw in (dict(t_eval=np.linspace(0, 2, 5)), {}):
        kw.update(sensitivities=True, rtol=1e-10, atol=1e-12)
        ens = sc.ensemble(initial={"x_t": np.array([7.0, 7.5])}, **kw)
        for r, v in enumerate([7.0, 7.5]):
            tr = sc.replace(initial={**init, "x_t": v}).run(**kw)
            assert len(tr.switches) >= 6
            rows = slice(None) if "t_eval" in kw else slice(-1, None)
            assert list(ens.switches[r]) == list(tr.switches)
            assert ens.steps[r] == tr._info["steps"]
            same_bits(ens.y[r], tr.y[rows])
            same_bits(ens.sensitivities[r], tr.sensitivities[rows])


@pytest.mark.parametrize("length", [1.0, 1e-5, 1e5])
def test_ensemble_refuses_a_start_off_the_holonomic_constraint_in_any_unit(length):
    """An ensemble judges g = 0 as a single run does, relative to g's own terms: a start
    off the hyperbola x y = l^2 by half is refused in every unit of length (it was accepted
    below l ~ 3e-5, where |g| fell under an absolute 1e-9), and starts on it are run."""
    J = jn.JetSpace("x y")
    x, y = J.q
    xt, yt = J.qd
    G, l = sp.symbols("G l")
    S = jn.System(J, (xt**2 + yt**2) / 2 - G * y, [x * y - l**2], dependent=[y])
    sc = jn.Scene(S, "chetaev", params={G: 9.81, l: length},
                  initial={"x": length, "y": length, "x_t": 0.0}, t_span=(0, 1e-3))
    Y = np.tile(sc.y0, (3, 1))
    i, j = sc.state_names.index("x"), sc.state_names.index("y")
    Y[2, i], Y[2, j] = 2 * length, 0.5 * length          # on it
    assert len(sc.ensemble(Y)) == 3
    Y[1, j] = 0.5 * length                              # x y = l^2 / 2
    with pytest.raises(jn.ConstraintError, match="run 1: the initial configuration is off"):
        sc.ensemble(Y)


def test_rk4_stage_check_in_the_ensemble_driver():
    """A fixed-step ensemble that changes chart runs the loop's stage check against the
    edge (``Control.edge``, ``loop.past_edge``) in its compiled driver, as a single run
    does (the adaptive ensembles' driver is compiled without that code): the rotating
    Cartesian pendulum with rk4 n = 600 has steps whose stages cross the edge band (the
    run blew up without the check), its runs are the single runs bit for bit."""
    from holonomic_systems import pendulum_xy

    sc = jn.Scene(pendulum_xy(), params={"l": 1.0, "G": 9.81},
                  initial={"x": 0.0, "y": -1.0, "x_t": 8.0}, t_span=(0, 50.0))
    ens = sc.ensemble({"x_t": [8.0, 7.5]}, method="rk4", n_steps=600, save="final")
    for r, v in enumerate((8.0, 7.5)):
        tr = sc.replace(initial={"x": 0.0, "y": -1.0, "x_t": v}).run(
            method="rk4", n_steps=600)
        assert tr.success and ens.status[r] == tr.status
        assert list(ens.switches[r]) == list(tr.switches) and len(tr.switches) > 100
        same_bits(ens.y[r, 0], tr.y[-1])
