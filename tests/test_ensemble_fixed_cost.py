"""What the short path of an ensemble shares and skips keeps every result and guarantee:
an ensemble of one is the single-run loop's rows as they are (stopped, singular, NaN);
the thread pool kept between calls gives the serial driver's bits for any number of runs
and workers, stops on a timeout, is dropped after a failing chunk and is not inherited
by a forked child."""

import os
import signal
import threading
import time

import numpy as np
import pytest
import sympy as sp

import jetnh as jn
from jetnh import models
from jetnh.errors import IntegrationError
from jetnh.mechanics.system import System
from jetnh.numeric import STOPPED, Scene, solve
from jetnh.numeric.methods._common import FINISHED, NONFINITE, SINGULAR

DISK0 = dict(x=0.1, y=-0.2, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7)


@pytest.fixture(scope="module")
def disk():
    return Scene(models.get("rolling_disk"), "chetaev", initial=DISK0, t_span=(0.0, 0.5),
                 runtime_params=["R"], cache=False).compile()


def _rows_equal(one, two):
    """``one`` (an ensemble of one) is row 0 of ``two``, bit for bit, every array."""
    for name in ("t", "y", "status", "steps", "rejected", "nfev", "rows", "t_final",
                 "y_final", "event_counts", "initial", "params", "aux", "aux_initial"):
        a, b = getattr(one, name), getattr(two, name)[:1]
        assert a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True), name
    assert one.stop_reasons == two.stop_reasons[:1]
    assert not any(getattr(one, n).flags.writeable for n in ("t", "y", "status", "t_final",
                                                             "y_final", "initial"))


def test_an_ensemble_of_one_stopped_singular_or_nonfinite_is_its_row():
    """The single-run loop's rows taken as they are, for runs that do not finish: a
    singular stop (the loop that watches its indicators), a NaN (recorded or raised as
    the driver's run is)."""
    J = jn.JetSpace("x y th")
    x, y, th = J.q
    xd, yd, thd = J.qd
    sleigh = Scene(System(J, (xd**2 + yd**2 + thd**2) / 2,
                          [yd * sp.cos(th) - xd * sp.sin(th)], dependent=[y]),
                   "chetaev", initial=dict(x=0.0, y=0.0, th=0.0, x_t=1.0, th_t=1.0),
                   t_span=(0.0, 3.0), cache=False)
    for te in (None, np.linspace(0.0, 3.0, 5)):
        kw = dict(split="fixed", **({"save": "final"} if te is None else {"t_eval": te}))
        one = sleigh.ensemble({"th_t": [1.0]}, **kw)
        two = sleigh.ensemble({"th_t": [1.0, 0.5]}, parallel="serial", **kw)
        assert one.status[0] == SINGULAR
        _rows_equal(one, two)
    Jq = jn.JetSpace("q")
    (q,), (qd,) = Jq.q, Jq.qd       # the force 1/(2 sqrt(q)): NaN past q = 0
    fall = Scene(System(Jq, qd**2 / 2 + sp.sqrt(q), []), "chetaev",
                 initial=dict(q=1.0, q_t=-3.0), t_span=(0.0, 2.0), cache=False)
    with pytest.raises(IntegrationError, match=r"ensemble run 0.*on_error='record'"):
        fall.ensemble({"q_t": [-3.0]}, save="final", singular="ignore")
    for singular, status in (("ignore", NONFINITE), ("stop", SINGULAR)):
        kw = dict(save="final", on_error="record", singular=singular)
        one = fall.ensemble({"q_t": [-3.0]}, **kw)
        two = fall.ensemble({"q_t": [-3.0, -2.0]}, parallel="serial", **kw)
        assert one.status[0] == status
        _rows_equal(one, two)


def _pool_threads():
    return {t.ident for t in threading.enumerate() if t.name.startswith("jetnh-ensemble")}


@pytest.mark.parametrize("workers", [2, 3])
def test_the_kept_pool_gives_the_serial_bits_for_any_number_of_runs(disk, workers):
    rng = np.random.default_rng(1)
    te = np.linspace(0.0, 0.5, 4)
    before = _pool_threads()
    seen = []
    for _ in range(2):
        for n in (2, 3, 5, 9, 13):
            ini = {"phi_t": rng.uniform(0.5, 1.5, n)}
            par = {"R": rng.uniform(0.5, 2.0, n)}
            a = disk.ensemble(ini, par, t_eval=te, workers=workers)
            b = disk.ensemble(ini, par, t_eval=te, parallel="serial")
            for name in ("t", "y", "status", "steps", "nfev", "t_final", "y_final"):
                assert np.array_equal(getattr(a, name), getattr(b, name)), (n, name)
        seen.append(_pool_threads())
    # at most workers - 1 threads beside the caller's, kept: none made in the second pass
    assert len(seen[0] - before) <= workers - 1 and seen[1] == seen[0]


def test_a_timeout_stops_every_thread_of_the_pool(disk):
    disk.replace(t_span=(0.0, 0.01)).ensemble(initial={"phi_t": [0.5, 1.0]})   # compiled
    tic = time.perf_counter()
    ens = disk.ensemble(initial={"phi_t": np.linspace(0.5, 1.0, 6)}, max_step=1e-8,
                        max_steps=10**9, timeout=0.3, workers=2, save="final")
    assert set(ens.status.tolist()) == {STOPPED}
    assert time.perf_counter() - tic < 30.0
    # the pool goes on serving
    again = disk.ensemble(initial={"phi_t": [0.5, 1.0]}, workers=2, save="final")
    assert set(again.status.tolist()) == {FINISHED}


def test_a_failing_chunk_ends_its_pool_and_the_next_call_gets_another(disk, monkeypatch):
    """An error in one thread's chunk reaches the caller once every thread has stopped
    (chunks not begun are not run); that pool is not kept."""
    ini = {"phi_t": np.linspace(0.5, 1.0, 8)}
    good = disk.ensemble(ini, save="final", workers=2)
    real = solve._driver
    begun = []

    def failing(method, prange, *specialised):
        drive = real(method, prange, *specialised)

        def wrapped(*args):
            begun.append(args[-1].shape[0])     # (rows in this chunk: the last array)
            if len(begun) == 2:
                raise RuntimeError("chunk failed")
            return drive(*args)
        return wrapped

    monkeypatch.setattr(solve, "_driver", failing)
    with pytest.raises(RuntimeError, match="chunk failed"):
        disk.ensemble(ini, save="final", workers=2)
    assert 2 <= len(begun) < 8
    assert not any(pool for pools in solve._IDLE.values() for pool in pools
                   if pool._shutdown)
    monkeypatch.setattr(solve, "_driver", real)
    again = disk.ensemble(ini, save="final", workers=2)
    assert np.array_equal(again.y, good.y)


@pytest.mark.skipif(not hasattr(os, "fork"), reason="os.fork")
def test_a_forked_child_runs_threaded_ensembles_of_its_own(disk):
    """A child forked after ensembles ran on the kept pool (whose threads stay in the
    parent) forgets it and runs them on a pool of its own: the same bits, no hang."""
    ini = {"phi_t": np.linspace(0.5, 1.0, 6)}
    want = disk.ensemble(ini, save="final", workers=2).y
    assert solve._IDLE
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:        # the child: report and leave at once, whatever happens
        code = 1
        try:
            forgotten = not solve._IDLE
            got = disk.ensemble(ini, save="final", workers=2).y
            code = (0 if forgotten and np.array_equal(got, want) and _pool_threads()
                    else 2)
        finally:
            os.write(w, bytes([code]))
            os._exit(code)
    os.close(w)
    try:
        deadline = time.monotonic() + 120.0
        while time.monotonic() < deadline:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                break
            time.sleep(0.05)
        else:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            pytest.fail("the forked child hung in a threaded ensemble")
        assert os.read(r, 1) == b"\x00"
        assert os.waitstatus_to_exitcode(status) == 0
    finally:
        os.close(r)


@pytest.mark.parametrize("options", [
    dict(), dict(method="dopri5", rtol=1e-6), dict(max_steps=4),
])
def test_a_row_of_states_again_takes_its_kept_plan_and_gives_the_same_bits(disk, options):
    """An ensemble of one row of float64 states with the same options again (its run's
    plan from the scene's memo at once) is row 0 of the two-row ensemble's driver, bit
    for bit, each time; other options on the same row give their own run."""
    row = disk.y0.copy()
    row[4] = 0.9
    two = disk.ensemble(np.array([row, row]), parallel="serial", **options)
    for _ in range(3):
        _rows_equal(disk.ensemble(row[None, :], **options), two)
    other = disk.ensemble(row[None, :], rtol=1e-4, **{k: v for k, v in options.items()
                                                      if k != "rtol"})
    assert other.nfev[0] != two.nfev[0] or not np.array_equal(other.y, two.y[:1])


def test_a_row_of_states_after_a_kept_plan_is_checked_as_the_first(disk):
    """The kept plan of an ensemble of one skips no check: a row that is not finite, of
    the wrong size or past the split's edge, and options that are not valid, are refused
    as on the first call (the same error and message)."""
    row = disk.y0[None, :].copy()
    disk.ensemble(row)
    disk.ensemble(row)
    for bad in (np.array([[np.nan, *row[0, 1:]]]), row[:, :3], row.astype(np.float32) * np.inf):
        with pytest.raises(jn.JetnhError) as again:
            disk.ensemble(bad)
        with pytest.raises(jn.JetnhError) as first:
            disk.replace(t_span=(0.0, 0.25)).ensemble(bad)
        assert str(again.value) == str(first.value)
    for bad in (dict(parallel="fork"), dict(on_error="ignore"), dict(rtol=-1.0),
                dict(save="some")):
        with pytest.raises(jn.JetnhError):
            disk.ensemble(row, **bad)


@pytest.mark.parametrize("workers", ["abc", 0, -1, True, 2.5])
def test_workers_must_be_a_positive_integer(disk, workers):
    """A bad ``workers`` is named (it was a bare ValueError from int(), and 0 or False
    silently meant numba's count), on the kept-plan route of one row too."""
    for rows in (disk.y0[None, :], np.repeat(disk.y0[None, :], 2, axis=0)):
        with pytest.raises(jn.JetnhError, match="workers must be a positive integer"):
            disk.ensemble(rows, workers=workers)
