"""Ensembles: every run bit-for-bit the single run; parameters and initial states as
arrays; per-run diagnostics, singular stops and events; the error paths."""

import numpy as np
import pytest
import sympy as sp

import jetnh as jn
from jetnh.mechanics.system import System
from jetnh.errors import ConstraintError, IntegrationError, JetnhError, JetnhWarning
from jetnh import models
from jetnh.models import appell_hamel
from jetnh.numeric import Event, Scene
from jetnh.numeric.methods._common import EVENT, FINISHED, NONFINITE, SINGULAR

DISK0 = dict(x=0.1, y=-0.2, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7)
N = 12


@pytest.fixture(scope="module")
def disk():
    """The catalogue's vertical rolling disk (without its defaults) with R a run-time
    parameter."""
    s = models.rolling_disk().replace(defaults=None)
    return Scene(s, "chetaev", params={"R": 1.5, "I1": 0.5, "I2": 0.25}, initial=DISK0,
                 t_span=(0.0, 5.0), runtime_params=["R"], cache=False).compile()


def inputs():
    rng = np.random.default_rng(0)
    return ({"phi_t": rng.uniform(0.5, 1.5, N), "psi_t": rng.uniform(-1.0, 1.0, N)},
            {"R": rng.uniform(0.5, 2.0, N)})


@pytest.mark.parametrize("parallel", ["prange", "threads", "serial"])
def test_ensemble_equals_single_runs_bitwise(disk, parallel):
    ini, par = inputs()
    te = np.linspace(0.0, 5.0, 11)
    ens = disk.ensemble(ini, par, rtol=1e-10, atol=1e-12, t_eval=te, parallel=parallel,
                        workers=2)
    assert ens.y.shape == (N, 11, 6) and ens.t.shape == (N, 11)
    assert ens["x"].shape == (N, 11) and ens["x_t"].shape == (N, 11)
    assert np.all(ens.status == FINISHED) and ens.success.all()
    for r in (0, 5, N - 1):
        tr = disk.run(rtol=1e-10, atol=1e-12, t_eval=te, y0=ens.initial[r],
                      params=ens.params[r])
        assert np.array_equal(tr.y, ens.y[r])          # to the last bit
        assert np.array_equal(tr["x_t"], ens["x_t"][r])
        assert tr.diagnostics.steps == ens.steps[r]
        assert tr.diagnostics.rhs_evaluations == ens.nfev[r]
    # the inputs went where they belong
    assert np.array_equal(ens.initial[:, disk.state_names.index("phi_t")], ini["phi_t"])
    assert np.array_equal(ens.params[:, 0], par["R"])


@pytest.mark.parametrize("n, method", [(1, "dop853"), (3, "dop853"), (40, "dop853"),
                                       (5, "radau")])
def test_prange_takes_every_run_once(disk, n, method):
    """The parallel driver's threads take the runs one by one (fewer runs than threads,
    one, many of uneven cost; the explicit methods' driver and radau's): every run is
    done once, as the serial driver does it, with the array of one run or its row as
    ``initial``."""
    rng = np.random.default_rng(n)
    Y0 = np.tile(disk.y0, (n, 1))
    Y0[:, 4] = rng.uniform(0.2, 3.0, n)         # phi_t: uneven step counts
    kw = dict(rtol=1e-10, atol=1e-12, save="final", method=method)
    ser = disk.ensemble(Y0, parallel="serial", **kw)
    par = disk.ensemble(Y0, parallel="prange", workers=2, **kw)
    assert np.array_equal(par.y, ser.y) and np.array_equal(par.nfev, ser.nfev)
    assert np.all(par.status == FINISHED)
    one = disk.ensemble(Y0[0], parallel="prange", workers=2, **kw)
    assert np.array_equal(one.y[0], ser.y[0]) and np.array_equal(one.initial[0], Y0[0])


def test_take_next_hands_out_every_index_once():
    """The atomic counter of the parallel drivers over numba's threads: each index taken
    exactly once (a plain read and write of the counter, tried in its place, handed some
    out twice in every one of five tries)."""
    import numba

    from jetnh.numeric.methods._common import take_next

    @numba.njit(parallel=True)
    def share(n):
        taken = np.zeros(1, dtype=np.int64)
        seen = np.zeros(n)
        for _ in numba.prange(n):
            r = take_next(taken)
            while r < n:
                acc = 0.0
                for k in range(100):    # some work: the threads take runs side by side
                    acc += np.sin(r + k)
                seen[r] += 1.0 + 0.0 * acc
                r = take_next(taken)
        return seen

    for n in (1, 20_000):
        assert np.array_equal(share(n), np.ones(n))


def test_ensemble_final_and_closed_form(disk):
    ini, par = inputs()
    ens = disk.ensemble(ini, par, rtol=1e-11, atol=1e-13, save="final")
    assert ens.y.shape == (N, 1, 6) and np.all(ens.t_final == 5.0)
    u, w, R = ini["phi_t"], ini["psi_t"], par["R"]
    psi = 0.4 + w * 5.0
    x = 0.1 + R * u / w * (np.sin(psi) - np.sin(0.4))
    assert np.max(np.abs(ens.final["x"] - x)) < 1e-9 * np.max(np.abs(x))
    d = ens.diagnostics()
    assert np.all(d["residual_max"] < 1e-12)
    assert np.all(d["energy_drift"] < 1e-10)
    assert np.all(d["rhs_evaluations"] == 12 * (d["steps"] + d["rejected"]) + 2)


def test_compiled_in_parameters_become_runtime(disk):
    """Varying a parameter the scene compiled in builds a scene with it at run time."""
    ens = disk.ensemble(params={"I2": [0.25, 0.5]}, rtol=1e-10, atol=1e-12, save="final")
    assert ens.scene.runtime_params == ("R", "I2") and ens.n_runs == 2
    # psi_t is constant whatever I2 (no torque): same x at the end for both runs
    assert ens.final["x"][0] == pytest.approx(ens.final["x"][1], rel=1e-12)


def test_array_initial_and_broadcast(disk):
    Y0 = np.tile(disk.y0, (3, 1))
    Y0[:, 4] = [0.5, 1.0, 2.0]
    ens = disk.ensemble(Y0, {"R": 1.0}, rtol=1e-10, atol=1e-12, save="final",
                        parallel="serial")
    assert ens.n_runs == 3 and np.all(ens.params[:, 0] == 1.0)
    assert np.allclose(ens.final["phi"], 0.3 + Y0[:, 4] * 5.0, rtol=1e-12)


def test_ensemble_singular_stops_per_run():
    """Appell-Hamel from several speeds (one of them zero: singular at t0)."""
    sc = Scene(appell_hamel(), "chetaev", initial=dict(x=0, y=0, z=0, x_t=0.6, y_t=0.8),
               t_span=(0.0, 0.5), cache=False)
    speeds = np.array([0.0, 0.5, 1.0, 3.0])
    ens = sc.ensemble({"x_t": 0.6 * speeds, "y_t": 0.8 * speeds}, rtol=1e-10, atol=1e-12,
                      save="final")
    decel = 9.81 * 0.5 / 1.25
    assert list(ens.status) == [SINGULAR, SINGULAR, SINGULAR, FINISHED]
    assert ens.t_final[0] == 0.0 and "initial state" in ens.stop_reason(0)
    for r in (1, 2):
        t_hit = speeds[r] / decel - np.sqrt(1e-10) * speeds[r] / decel
        assert abs(ens.t_final[r] - t_hit) < 1e-9
        assert "x_t**2 + y_t**2" in ens.stop_reason(r)
    assert ens.stop_reason(3) == "reached the end of the interval"
    assert ens.stop_reasons == [ens.stop_reason(r) for r in range(4)]


def test_ensemble_events(disk):
    ini, par = inputs()
    psi = disk.system.J.q[3]
    ev = [Event(sp.sin(psi), name="sin psi"), Event(sp.cos(psi), terminal=True)]
    ens = disk.ensemble(ini, par, rtol=1e-10, atol=1e-12, save="final", events=ev)
    assert ens.event_names == ("sin psi", "cos(psi)")
    for r in range(N):
        tr = disk.run(rtol=1e-10, atol=1e-12, y0=ens.initial[r], params=ens.params[r],
                      events=ev, save="final")
        assert ens.status[r] == tr.status
        assert ens.t_final[r] == tr.t[-1]
        for k in range(2):
            assert ens.event_counts[r, k] == len(tr.t_events[k])
            if len(tr.t_events[k]):
                assert ens.event_first[r, k] == tr.t_events[k][0]
    assert (ens.status == EVENT).any()
    assert ens.stop_reasons == [ens.stop_reason(r) for r in range(N)]


def test_nonfinite_runs():
    J = jn.JetSpace("x")
    (x,), (xd,) = J.q, J.qd
    sc = Scene(System(J, xd**2 / 2 + x**4 / 4, []), "chetaev", initial=dict(x=1.0, x_t=0.1),
               t_span=(0.0, 5.0), cache=False)
    ini = {"x": [0.0, 1.0], "x_t": [0.0, 3.0]}   # rest at x = 0; xdd = x^3 blows up
    with pytest.raises(IntegrationError, match=r"ensemble run 1.*on_error='record'"):
        sc.ensemble(ini, method="rk4", n_steps=50, parallel="serial")
    ens = sc.ensemble(ini, method="rk4", n_steps=50, parallel="serial", on_error="record")
    assert list(ens.status) == [FINISHED, NONFINITE]
    with pytest.warns(JetnhWarning, match=r"1 of the 2 runs did not reach.*run 1"):
        final = ens.final["x"]
    assert np.isfinite(final[0]) and np.isnan(final[1])


def test_ensemble_errors(disk):
    with pytest.raises(JetnhError, match="different numbers of runs"):
        disk.ensemble({"phi_t": [1.0, 2.0]}, {"R": [1.0, 2.0, 3.0]})
    with pytest.raises(JetnhError, match="'Q'.*not parameters"):
        disk.ensemble(params={"Q": [1.0]})
    with pytest.raises(JetnhError, match="not states"):
        disk.ensemble({"w": [1.0]})
    with pytest.raises(ConstraintError, match="inconsistent with the constraints in 2 run"):
        disk.ensemble({"x_t": [5.0, 6.0]})
    with pytest.raises(JetnhError, match="t_eval=... or save='final'"):
        disk.ensemble({"phi_t": [1.0]}, save="steps")
    with pytest.raises(JetnhError, match="parallel must be one of"):
        disk.ensemble({"phi_t": [1.0]}, parallel="gpu")
    with pytest.raises(JetnhError, match=r"shape \[n_runs, 6\]"):
        disk.ensemble(np.zeros((2, 3)))
    with pytest.raises(JetnhError, match="non-finite"):
        disk.ensemble({"phi_t": [np.nan]})


@pytest.mark.parametrize("method, kw", [("dop853", dict(t_eval=np.linspace(0.0, 5.0, 6))),
                                        ("rk4", dict(n_steps=200, save="final"))])
def test_ensemble_sensitivities_equal_single_runs_bitwise(disk, method, kw):
    """sensitivities=True: every run's state and S = dy/d(y0, p) are the single run's,
    to the last bit, in the order of the single run's columns; a run without them is
    refused its sensitivities."""
    ini, par = inputs()
    ini, par = {k: v[:4] for k, v in ini.items()}, {k: v[:4] for k, v in par.items()}
    ens = disk.ensemble(ini, par, method=method, sensitivities=True, rtol=1e-8,
                        parallel="threads", workers=2, **kw)
    assert ens.sensitivity_columns == disk.state_names + ("R",)
    assert ens.sensitivities.shape == ens.y.shape + (7,)
    for r in range(4):
        tr = disk.run(method=method, sensitivities=True, rtol=1e-8, y0=ens.initial[r],
                      params=ens.params[r], **kw)
        rows = slice(None) if "t_eval" in kw else slice(-1, None)
        assert np.array_equal(tr.y[rows], ens.y[r])
        assert np.array_equal(tr.sensitivities[rows], ens.sensitivities[r])
        assert np.array_equal(tr.sensitivity("x", "R")[rows], ens.sensitivity("x", "R")[r])
    # S = dy/dy0 starts as the identity, the parameter column at zero
    if "t_eval" in kw:
        np.testing.assert_array_equal(ens.sensitivities[:, 0, :, :6],
                                      np.broadcast_to(np.eye(6), (4, 6, 6)))
    with pytest.raises(JetnhError, match="not an initial value"):
        ens.sensitivity("x", "I1")
    with pytest.raises(JetnhError, match="no sensitivities"):
        disk.ensemble(ini, par, rtol=1e-8, save="final").sensitivity("x", "R")
