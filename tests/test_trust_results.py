"""Results that cannot lie: finals of runs that stopped early are NaN (ensembles and
sweeps), and every array a frozen result hands out is read-only."""

import warnings

import numpy as np
import pytest

import jetnh as jn
from jetnh.errors import JetnhWarning
from jetnh.models import appell_hamel
from jetnh.numeric import Scene
from jetnh.numeric.methods._common import FINISHED, SINGULAR


@pytest.fixture(scope="module")
def scene():
    return Scene(appell_hamel(), "chetaev", initial=dict(x=0, y=0, z=0, x_t=0.6, y_t=0.8),
                 t_span=(0.0, 0.5), cache=False)


SPEEDS = np.array([0.5, 3.0])          # the first stops singular at t = 0.2, the second ends


def test_ensemble_final_of_a_stopped_run_is_nan(scene):
    ens = scene.ensemble({"x_t": 0.6 * SPEEDS, "y_t": 0.8 * SPEEDS}, rtol=1e-10, atol=1e-12,
                         save="final")
    assert list(ens.status) == [SINGULAR, FINISHED]
    with pytest.warns(JetnhWarning, match="1 of the 2 runs did not reach the final time"):
        final = ens.final
    assert all(np.isnan(final[n][0]) for n in ens.names)
    assert all(np.isfinite(final[n][1]) for n in ens.names)
    # the stopped run's last row is still there, under its own name
    assert np.isfinite(ens["x"][0, -1]) and ens.t_final[0] < 0.5
    tr = scene.run(rtol=1e-10, atol=1e-12, y0={"x_t": 0.6 * SPEEDS[1], "y_t": 0.8 * SPEEDS[1]})
    assert final["x"][1] == tr.final["x"]


def test_sweep_final_columns_of_a_stopped_run_are_nan(scene):
    for method in ("dop853", "scipy-RK45"):
        df = jn.sweep(scene, [{"x_t": 0.6 * s, "y_t": 0.8 * s} for s in SPEEDS],
                      method=method, rtol=1e-10, atol=1e-12)
        assert list(df["success"]) == [False, True], method
        for n in ("x", "y", "z", "x_t", "y_t", "z_t"):
            assert np.isnan(df[n][0]) and np.isfinite(df[n][1]), (method, n)
        assert df["t_final"][0] < 0.5


def _assert_read_only(a, what):
    assert isinstance(a, np.ndarray), what
    with pytest.raises(ValueError, match="read-only"):
        a[...] = 0


def test_trajectory_and_scene_arrays_are_read_only(scene):
    tr = scene.run(rtol=1e-10, atol=1e-12)
    before = tr.final
    for what in ("t", "y", "aux", "energy", "residual"):
        _assert_read_only(getattr(tr, what), what)
    for name in tr.names:
        _assert_read_only(tr[name], name)
    for name, d in tr.events.items():
        for k, v in d.items():
            _assert_read_only(v, f"{name}:{k}")
    _assert_read_only(scene.y0, "y0")
    d = tr.diagnostics
    with pytest.raises(AttributeError):
        d.success = False
    with pytest.raises(jn.JetnhError):
        d.integral_drift["x"] = 1.0
    xs = tr["x"]
    with pytest.raises(ValueError):
        xs -= xs[0]
    assert tr.final == before
    # the scene's initial state is still what runs start from
    assert scene.run(rtol=1e-10, atol=1e-12).final == before


def test_ensemble_arrays_are_read_only(scene):
    ens = scene.ensemble({"x_t": 0.6 * SPEEDS, "y_t": 0.8 * SPEEDS}, rtol=1e-10, atol=1e-12,
                         t_eval=np.linspace(0, 0.5, 5))
    for what in ("t", "y", "status", "steps", "t_final", "y_final", "initial", "params",
                 "aux", "aux_initial"):      # (residual_max, ...: fresh copies)
        _assert_read_only(getattr(ens, what), what)
    for name in ens.names:
        _assert_read_only(ens[name], name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", JetnhWarning)
        for name, v in ens.final.items():
            _assert_read_only(v, name)
