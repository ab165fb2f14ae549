"""The one driver (``jetnh.numeric.solve``): Scene.run, ensembles, sweeps and
Trajectory.at plan and dispatch through it; options are checked once, with one message
wherever they are given; plans are kept on the scene and handed on by ``replace``."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import jetnh as jn
from jetnh import models
from jetnh.errors import JetnhError
from jetnh.numeric import Scene
from jetnh.numeric.ensemble import run_ensemble

DISK0 = dict(x=0.1, y=-0.2, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7)


@pytest.fixture(scope="module")
def disk():
    return Scene(models.get("rolling_disk"), "chetaev", initial=DISK0, t_span=(0.0, 2.0),
                 runtime_params=["R"], cache=False).compile()


@pytest.mark.parametrize("options, match", [
    (dict(max_step=0.0), "max_step must be a positive"),
    (dict(singular_tol=2.0), r"singular_tol must be in \[0, 1\)"),
    (dict(n_steps=10), "n_steps is not an option of the dop853 method"),
    (dict(newton_tol=1e-9), "newton_tol is not an option of the dop853 method"),
    (dict(rtol=1e-20), "float64 cannot honour"),
    (dict(timeout=-1.0), "timeout must be a positive"),
])
def test_one_message_per_option_everywhere(disk, options, match):
    """A bad option gets the same message from a run, an ensemble and a sweep."""
    with pytest.raises(JetnhError, match=match) as a:
        disk.run(save="final", **options)
    with pytest.raises(JetnhError, match=match) as b:
        run_ensemble(disk, {"phi_t": [1.0, 2.0]}, **options)
    assert str(a.value) == str(b.value)
    with pytest.raises(JetnhError, match=match) as c:
        jn.sweep(disk, {"phi_t": [1.0, 2.0]}, **options)
    assert str(c.value) == str(a.value)


def test_kept_plans_still_check_types(disk):
    """A plan kept for atol=1 is not handed to atol=True (the options' types are part of
    the key), and an unhashable option (an array) is planned afresh."""
    one = disk.run(rtol=1e-8, save="final")
    assert np.array_equal(disk.run(rtol=1e-8, save="final").y, one.y)
    disk.run(rtol=1e-3, atol=1, save="final")
    with pytest.raises(JetnhError, match="atol must hold real numbers"):
        disk.run(rtol=1e-3, atol=True, save="final")
    again = disk.run(rtol=1e-8, atol=np.full(6, 1e-12), save="final")
    assert np.array_equal(again.y, one.y)


@settings(max_examples=10, deadline=None)
@given(phi_t=st.floats(0.2, 2.0), psi_t=st.floats(-1.0, 1.0), t1=st.floats(0.1, 3.0),
       R=st.floats(0.5, 2.0))
def test_replace_run_y0_and_ensemble_of_one_agree(disk, phi_t, psi_t, t1, R):
    """``replace(initial=..., t_span=...).run()``, ``run(y0=..., t_span=...)``, a fresh
    Scene's run and an ensemble of one give the same bits; replace hands the kernels'
    key on."""
    ini = {**DISK0, "phi_t": phi_t, "psi_t": psi_t}
    par = {"R": R}
    a = disk.replace(initial=ini, t_span=(0.0, t1), params=par).run(save="final")
    b = disk.run(y0=ini, t_span=(0.0, t1), params=par, save="final")
    fresh = Scene(models.get("rolling_disk"), "chetaev", initial=ini, t_span=(0.0, t1),
                  params=par, runtime_params=["R"], cache=False)
    c = fresh.run(save="final")
    e = disk.replace(t_span=(0.0, t1)).ensemble({k: [v] for k, v in ini.items()},
                                                {"R": [R]})
    assert np.array_equal(a.y, b.y) and np.array_equal(a.y, c.y)
    assert np.array_equal(e.y[0, -1], a.y[-1])
    assert a.diagnostics.steps == b.diagnostics.steps == e.steps[0]


def test_replace_hands_on_the_kernels_only_when_they_stay(disk):
    sc = disk.replace(initial={**DISK0, "phi_t": 2.0})
    assert sc._memo.get("key") == disk.key
    other = disk.replace(runtime_params=())        # R compiled in: other kernels
    assert other.key != disk.key
    assert "plans" not in other._memo


def test_at_retakes_the_steps_through_the_driver(disk):
    """Trajectory.at re-takes a step of the run: bit for bit what t_eval gives, with and
    without sensitivities."""
    times = np.array([0.3, 1.1, 1.7])
    for kw in ({}, {"sensitivities": True}):
        tr = disk.run(**kw)
        te = disk.run(t_eval=times, **kw)
        assert np.array_equal(tr.at(times).to_numpy(), te.y)
