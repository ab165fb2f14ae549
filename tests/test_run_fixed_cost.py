"""What the short-run path shares and skips keeps every result and guarantee: plans kept
per scene and handed to ``replace`` copies, a trajectory whose rows are read-only views
made on first read, the finiteness check of few entries, the lock-free watch of
``interrupt.call``."""

import threading
import time

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from _interrupt_helpers import recording_sigint, sigint_in, spin, stopped_by_sigint
from jetnh import models
from jetnh.errors import JetnhError
from jetnh.numeric import STOPPED, Scene, arguments, interrupt

DISK0 = dict(x=0.1, y=-0.2, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7)


@pytest.fixture(scope="module")
def disk():
    return Scene(models.get("rolling_disk"), "chetaev", initial=DISK0, t_span=(0.0, 0.5),
                 cache=False).compile()


def test_replace_copies_share_the_quick_plans_of_their_span_only(disk):
    """A copy with other initial values takes over the scene's plans of its span (the
    same plan object), runs bit for bit as ``run(y0=...)`` from the same state, and a
    copy with another span plans its own and ends at its own span."""
    first = disk.run(save="final")
    moved = disk.replace(initial={**DISK0, "phi_t": 1.3})
    assert moved._memo["quick"] is disk._memo["quick"]
    again = moved.run(save="final")
    by_y0 = disk.run(y0=moved.y0, save="final")
    assert np.array_equal(again.y, by_y0.y) and np.array_equal(again.t, by_y0.t)
    assert not np.array_equal(again.y, first.y)
    longer = moved.replace(t_span=(0.0, 1.0))
    assert "quick" not in longer._memo
    assert longer.run(save="final").t[-1] == 1.0 and again.t[-1] == 0.5


def test_a_run_of_the_quick_path_equals_the_general_path(disk):
    """The quick plan (every option as its default) and the general one (an option given
    as its default value, so the long key) give the same rows, counts and reason."""
    quick = disk.run(rtol=1e-8)
    general = disk.run(rtol=1e-8, singular_tol=1e-10)
    assert np.array_equal(quick.t, general.t) and np.array_equal(quick.y, general.y)
    assert quick.stop_reason == general.stop_reason
    for name in ("steps", "rejected", "rhs_evaluations"):
        assert getattr(quick.diagnostics, name) == getattr(general.diagnostics, name)


def test_trajectory_rows_are_read_only_views_of_the_output_rows(disk):
    """``t`` and ``y`` hold exactly the output rows (a final-only run: its two ends),
    read-only, the same object on every read."""
    traj = disk.run(save="final")
    assert traj.t.shape == (2,) and traj.y.shape == (2, len(disk.state_names))
    assert traj.t[0] == 0.0 and traj.t[-1] == 0.5
    assert traj.t is traj.t and traj.y is traj.y
    assert not traj.t.flags.writeable and not traj.y.flags.writeable
    with pytest.raises(ValueError):
        traj.y[0, 0] = 1.0
    assert traj.diagnostics.steps > 0 and traj.diagnostics.rhs_evaluations > 0
    every = disk.run()
    assert np.array_equal(every.y[-1], traj.y[-1]) and len(every) > 2


@given(st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64), max_size=300),
       st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64), max_size=300))
def test_all_finite_agrees_with_numpy(a, b):
    """Few entries (summed as Python floats) or many (a sum of squares): the answer is
    numpy's, overflowing sums included."""
    a, b = np.array(a, dtype=float), np.array(b, dtype=float)
    assert arguments.all_finite(a) == bool(np.isfinite(a).all())
    assert arguments.all_finite(a, b) == bool(np.isfinite(a).all() and np.isfinite(b).all())


def test_run_y0_refuses_a_state_that_is_not_finite(disk):
    for bad in (np.nan, np.inf, -np.inf):
        y = disk.y0.copy()
        y[2] = bad
        with pytest.raises(JetnhError):
            disk.run(y0=y)


def test_every_call_is_watched_while_the_watchdog_comes_and_goes(monkeypatch):
    """With the watchdog ending after 5 ms idle, calls made just as it ends, from two
    threads at once, are each stopped by their timeout (no watch lost between the
    lock-free registration and the thread's end), and none stays registered."""
    wd = interrupt._Watchdog()
    monkeypatch.setattr(interrupt, "_WATCHDOG", wd)
    monkeypatch.setattr(interrupt, "IDLE", 0.005)
    stopped = []

    def calls(seed):
        rng = np.random.default_rng(seed)
        for _ in range(15):
            time.sleep(float(rng.uniform(0.0, 0.012)))      # around the idle end
            halt = interrupt.flag()
            stopped.append(interrupt.call(spin, halt, 0.02, (halt, 5.0)))

    try:
        threads = [threading.Thread(target=calls, args=(s,)) for s in range(2)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert stopped == [interrupt.TIMEOUT] * 30
        assert wd.calls == {}
    finally:
        wd.close()


def test_a_timeout_still_stops_a_compiled_run(disk):
    traj = disk.run(t_span=(0.0, 1e9), max_step=1e-6, max_steps=10**12, save="final",
                    timeout=0.2)
    assert traj.status == STOPPED and traj.t[-1] > 0.0


@pytest.mark.parametrize("options", [
    dict(save="final"), dict(method="dopri5", save="final", rtol=1e-6),
    dict(t_eval=np.linspace(0.0, 0.5, 6)), dict(t_eval=np.linspace(0.0, 0.5, 6), max_steps=4),
    dict(save="final", max_steps=3), dict(save="final", params={"R": [1.3]}),
])
def test_an_ensemble_of_one_is_its_row_of_a_larger_ensemble(disk, options):
    """An ensemble of one runs the single-run loop; the ensemble's driver runs two: the
    same rows, counts, status and last state, bit for bit (also stopped by its budget,
    and with a run-time parameter)."""
    options = dict(options)
    params = options.pop("params", None)
    one = disk.ensemble(initial={"phi_t": [0.9]}, params=params, **options)
    two = disk.ensemble(initial={"phi_t": [0.9, 0.9]},
                        params=None if params is None else {"R": params["R"] * 2},
                        parallel="serial", **options)
    assert np.array_equal(one.t, two.t[:1], equal_nan=True)
    assert np.array_equal(one.y, two.y[:1], equal_nan=True)
    for a, b in zip(one._arrays[:7], two._arrays[:7]):
        assert np.array_equal(a, b[:1], equal_nan=True)
    assert one.status.tolist() == two.status[:1].tolist()


def test_a_replace_copy_of_a_switching_scene_shares_its_charts():
    """A copy with other initial values (a shooting loop's run) takes over the atlas's
    charts of its original rather than building its own (each chart a scene compiled
    once), and switches as ``run(y0=...)`` of the original does, bit for bit, in a
    trajectory of the copy."""
    from jetnh.models import knife_edge
    from jetnh.numeric import atlas

    knife = Scene(knife_edge(), "chetaev", initial=dict(x=0, y=0, phi=0, x_t=0.5, phi_t=3.0),
                  t_span=(0.0, 2.0))
    first = knife.run(rtol=1e-8)
    moved = knife.replace(initial=dict(x=0, y=0, phi=0.1, x_t=0.5, phi_t=3.0))
    traj = moved.run(rtol=1e-8)
    by_y0 = knife.run(y0=moved.y0, rtol=1e-8)
    assert len(traj.switches) == len(first.switches) >= 2
    assert traj.switches == by_y0.switches
    assert np.array_equal(traj.y, by_y0.y) and np.array_equal(traj.t, by_y0.t)
    assert traj.scene is moved and by_y0.scene is knife
    mine, theirs = atlas.atlas(moved), atlas.atlas(knife)
    assert mine is not theirs and mine.charts is theirs.charts
    assert mine.own.scene is moved and theirs.own.scene is knife
    # a run that stays in its chart is the copy's too
    short = moved.replace(t_span=(0.0, 0.1)).run(rtol=1e-8)
    assert not short.switches and short.scene.t_span == (0.0, 0.1)


@pytest.fixture
def sigint_handler():
    """A SIGINT handler of the test's own (the handler ``interrupt._on_sigint`` stands
    in front of) recording the state of the calls when it runs; the previous handler
    and wakeup fd restored after the test."""
    with recording_sigint(lambda signum: (interrupt._DEPTH[0],
                                          list(interrupt._HALTS))) as seen:
        yield seen


def test_sigint_stops_nested_calls_and_reaches_the_handler_once_after(sigint_handler):
    """Ctrl-C during a call nested in another (a run inside an event callback): both
    halts set within a second, the handler run once, after the outer call returned,
    nothing left on the watch."""
    interrupt.call(lambda: None, interrupt.flag())       # (the watch installed)
    outer, inner = interrupt.flag(), interrupt.flag()

    def outer_call():
        got = interrupt.call(spin, inner, None, (inner, 10.0))
        return got, spin(outer, 10.0)

    timer = sigint_in(0.3)
    tic = time.monotonic()
    got = interrupt.call(outer_call, outer)
    timer.join()
    assert got == (interrupt.INTERRUPT, interrupt.INTERRUPT)
    assert time.monotonic() - tic < 3.0
    assert sigint_handler == [(0, [])]              # once, after every call returned
    assert interrupt._HALTS == [] and interrupt._DEPTH[0] == 0
    # a second Ctrl-C, between calls, reaches the handler at once; the next call runs
    import os
    import signal

    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(0.05)
    assert len(sigint_handler) == 2
    halt = interrupt.flag()
    assert interrupt.call(spin, halt, None, (halt, 0.2)) == 0


def test_sigint_is_heard_while_asyncio_holds_the_wakeup_fd(sigint_handler):
    """A wakeup fd of someone else's (an asyncio loop with a signal handler) receives
    the signal's byte during a call, the call is stopped within a second, and the fd
    is theirs again after it."""
    import asyncio
    import signal

    interrupt.call(lambda: None, interrupt.flag())
    loop = asyncio.new_event_loop()
    try:
        loop.add_signal_handler(signal.SIGUSR1, lambda: None)
        theirs = signal.set_wakeup_fd(-1)
        signal.set_wakeup_fd(theirs)
        assert theirs not in (-1, interrupt._WATCHDOG.own)

        async def run():
            return stopped_by_sigint(0.3)

        got, took = loop.run_until_complete(run())
        assert got == interrupt.INTERRUPT and took < 3.0
        assert len(sigint_handler) == 1
        now = signal.set_wakeup_fd(-1)
        signal.set_wakeup_fd(now)
        assert now == theirs                        # restored after the call
        loop.remove_signal_handler(signal.SIGUSR1)
    finally:
        loop.close()


def test_sigint_is_heard_after_the_watchdog_ended(monkeypatch, sigint_handler):
    """A call without a timeout made after the watchdog ended (idle) starts it again:
    Ctrl-C during the call still stops it."""
    wd = interrupt._Watchdog()
    monkeypatch.setattr(interrupt, "_WATCHDOG", wd)
    monkeypatch.setattr(interrupt, "IDLE", 0.005)
    try:
        for _ in range(3):
            interrupt.call(lambda: None, interrupt.flag())
            time.sleep(0.1)                         # the watchdog ends meanwhile
            got, _ = stopped_by_sigint()
            assert got == interrupt.INTERRUPT
        assert len(sigint_handler) == 3 and interrupt._HALTS == []
    finally:
        monkeypatch.undo()
        wd.close()


def test_a_call_in_another_thread_runs_unwatched_by_signals():
    """Outside the main thread (where ``set_wakeup_fd`` raises) a call without a timeout
    is the bare call: nothing on the main thread's watch."""
    got = []

    def work():
        halt = interrupt.flag()
        got.append((interrupt.call(lambda x: x + 1, halt, None, (1,)), list(interrupt._HALTS)))

    thread = threading.Thread(target=work)
    thread.start()
    thread.join()
    assert got == [(2, [])]


@given(st.floats(-3.0, 3.0), st.floats(-3.0, 3.0), st.floats(-3.0, 3.0))
def test_replace_initial_of_float_states_equals_the_general_route(disk, phi, phi_t, psi_t):
    """A copy's initial values from a dict of float states (the route at once) are those
    of the general check with the same kernels (``Scene._initial``), bit for bit, and so
    are its state array and its run."""
    ini = {**DISK0, "phi": phi, "phi_t": phi_t, "psi_t": psi_t}
    moved = disk.replace(initial=ini)
    general, _ = moved._initial(ini, False, False, disk.kernels, disk._p)
    assert dict(moved.initial) == general and list(moved.initial) == list(general)
    assert np.array_equal(moved.y0, [general[n] for n in disk.state_names])
    assert not moved.y0.flags.writeable
    assert np.array_equal(moved.run(save="final").y, disk.run(y0=moved.y0, save="final").y)


@pytest.mark.parametrize("bad, says", [
    ({**DISK0, "phi_t": float("nan")}, "initial value of 'phi_t' is nan"),
    ({**DISK0, "phi_t": float("inf")}, "initial value of 'phi_t' is inf"),
    ({k: v for k, v in DISK0.items() if k != "psi"}, "missing initial values: psi"),
    ({**DISK0, "theta": 1.0}, "'theta', which is not a state"),
    ({**DISK0, "x_t": 5.0}, "inconsistent with the constraints"),
    ({**DISK0, "phi_t": "1.0"}, "initial value of 'phi_t'"),
    ([1.0] * 6, "initial must be a dict"),
])
def test_replace_refuses_bad_initial_values_itself(disk, bad, says):
    """Bad initial values are refused by ``replace`` (not by the copy's run), with the
    error a new Scene gives them, also after copies took the route at once."""
    disk.replace(initial=dict(DISK0))
    with pytest.raises(JetnhError, match=says):
        disk.replace(initial=bad)
    with pytest.raises(JetnhError, match=says):
        Scene(disk.system, "chetaev", initial=bad, t_span=(0.0, 0.5))


def test_replace_initial_takes_whole_numbers_as_the_general_route(disk):
    """States given as ints or numpy floats take the general route: floats, the same
    values."""
    whole = disk.replace(initial={**DISK0, "phi_t": 1, "psi_t": np.float64(0.7)})
    same = disk.replace(initial={**DISK0, "phi_t": 1.0})
    assert type(whole.initial["phi_t"]) is float and dict(whole.initial) == dict(same.initial)


@pytest.mark.parametrize("save", ["final", "steps"])
def test_a_finished_runs_trajectory_equals_the_general_routes(disk, save):
    """The trajectory a finished run makes at once (the loop's result kept as it is) and
    the one of the general route (of a run watching an event that never fires, the same
    steps: ``general_route``) agree on every attribute read, stay immutable, and pickle
    alike."""
    from jetnh.errors import FrozenError

    quick = disk.run(save=save)
    x = disk.system.J.q[0]
    general = general_route(disk.run(save=save, events=[x - 1e6]), [x - 1e6])
    back = _agree(quick, general, save)
    assert quick.t_events == [] and quick.y_events == []
    assert [len(e) for e in general.t_events] == [0]
    with pytest.raises(FrozenError):
        quick.status = 3
    with pytest.raises(ValueError):
        quick.y[0, 0] = 1.0
    assert back.t_events == []


def general_route(traj, events):
    """The Trajectory the general route (``solve.trajectory`` past its quick path) makes
    of the loop's result that ``traj`` (a quick one, a watching run's) keeps, with its
    event records as the arrays of no record (what the loop returned for them before it
    returned None)."""
    from jetnh.numeric import solve

    out = traj.__dict__["_loop"]
    assert len(out) == 12 and out[7] is None and out[10] == 0
    n = out[2].shape[1]
    records = (np.empty(0), np.empty(0, dtype=np.int64), np.empty((0, n)))
    scene = traj.scene
    ce = scene.compile_events(events)
    return solve.trajectory(scene, traj.method, (*out[:7], *records, *out[10:]),
                            traj._wall, traj._kernels, ce, traj._p, scene.t_span[0],
                            scene.y0, 1e-10, True, None, traj._dense)


def _agree(quick, general, save):
    """Check that the trajectory ``quick`` made at once and ``general`` (its general
    route's) agree on their rows, attributes, diagnostics and values between rows (with
    ``save="steps"``), and that ``quick`` pickles without its loop's tuple; returns the
    unpickled copy."""
    import pickle

    assert "_loop" in quick.__dict__ and "_loop" not in general.__dict__
    assert np.array_equal(quick.t, general.t) and np.array_equal(quick.y, general.y)
    for name in ("status", "stop_reason", "success", "method", "names", "switches",
                 "singularity", "final", "t_final"):
        assert getattr(quick, name) == getattr(general, name), name
    assert quick.t_events is quick.t_events
    a, b = quick.diagnostics, general.diagnostics
    for name in ("steps", "rejected", "rhs_evaluations", "residual_max", "energy_drift",
                 "projected", "status", "success", "rows", "saved", "stop_row"):
        assert getattr(a, name) == getattr(b, name), name
    assert np.array_equal(quick["phi_t"], general["phi_t"])
    if save == "steps":         # (evaluation between rows re-takes the steps)
        assert np.array_equal(quick.at([0.25]).to_numpy(), general.at([0.25]).to_numpy())
    back = pickle.loads(pickle.dumps(quick))
    assert "_loop" not in back.__dict__ and back.diagnostics.steps == a.steps
    assert back.event_names == quick.event_names and np.array_equal(back.y, quick.y)
    return back


@pytest.mark.parametrize("save", ["final", "steps"])
@pytest.mark.parametrize("method", ["dop853", "radau"])
def test_a_finished_watching_loop_keeps_its_last_state_in_row_n_out(disk, method, save):
    """A watching loop (an event that never fires) that finished returns None for its last
    state (no array to box) and has it in row n_out, as a loop that watches nothing does:
    bit for bit its last output row and the end of the same run unwatched (the watch
    changes no step); ``loops.result`` reads it there; an ensemble of the run ends on it
    too."""
    from jetnh.numeric import loops, solve

    halt = np.zeros(1, dtype=np.int64)
    got = {}
    for events in ([disk.system.J.q[0] - 1e6], None):
        plan = solve.plan(disk, method, save=save, events=events)
        got[events is None] = plan.entry(*plan.head, disk.y0.copy(), disk.p, *plan.suffix,
                                         halt)
    out, bare = got[False], got[True]
    assert len(out) == 12 and out[0] == 0 and out[6] is None
    assert len(bare) == 6 or bare[6] is None        # (radau's loop always returns 12)
    n = out[3]
    assert n == bare[3] and out[1][n] == out[1][n - 1] == bare[1][n] == out[5]
    assert out[2][n].tobytes() == out[2][n - 1].tobytes() == bare[2][n].tobytes()
    res = loops.result(out)
    assert res.t == out[5] and res.y.tobytes() == out[2][n].tobytes()
    for rows in (1, 2):     # (one row: the loop's own call; two: the compiled driver)
        ens = disk.ensemble(np.stack([disk.y0] * rows), method=method)
        assert ens.y[:, -1].tobytes() == np.stack([out[2][n]] * rows).tobytes()


@pytest.mark.parametrize("save", ["final", "steps"])
@pytest.mark.parametrize("n_events", [1, 2])
def test_a_finished_watching_runs_trajectory_equals_the_general_routes(disk, save, n_events):
    """A run watching events that never fire (its loop returns None for the records) is
    made at once (the loop's 12 entries kept as they are) and agrees with the general
    route's trajectory of the same result on every attribute read, its empty event lists
    included (one read-only array per event); immutable; pickled alike."""
    from jetnh.errors import FrozenError

    x, y = disk.system.J.q[:2]
    events = [x - 1e6, y + 1e6][:n_events]
    quick = disk.run(save=save, events=events)
    general = general_route(quick, events)
    back = _agree(quick, general, save)
    assert quick.event_names == general.event_names and len(quick.event_names) == n_events
    for a, b in ((quick.t_events, general.t_events), (quick.y_events, general.y_events)):
        assert len(a) == len(b) == n_events
        for u, v in zip(a, b):
            assert u.shape == v.shape and u.dtype == v.dtype and not u.flags.writeable
    with pytest.raises(FrozenError):
        quick.event_names = ()
    with pytest.raises(ValueError):
        quick.y_events[0][:] = 1.0
    assert [e.shape for e in back.y_events] == [e.shape for e in quick.y_events]


def test_a_watching_run_whose_event_fires_keeps_its_records(disk):
    """An event that fires (non-terminal, then terminal) is recorded as before: the
    loop's records, the general route."""
    x = disk.system.J.q[0]
    x1 = float(disk.run(save="final").y[-1, 0])
    mid = 0.5 * (DISK0["x"] + x1)
    fired = disk.run(save="final", events=[x - mid])
    assert "_loop" not in fired.__dict__ and len(fired.t_events[0]) == 1
    assert abs(fired.y_events[0][0, 0] - mid) < 1e-9


def test_an_ensemble_of_one_is_immutable_and_pickles_as_made(disk):
    """An ensemble of one row (its arrays made when first read): the caller's row copied,
    the parameters the scene's (never written, read-only through the ensemble), every
    array read-only; pickled before any read, the same arrays, without the loop's."""
    import pickle

    row = disk.y0[None, :].copy()
    ens = disk.ensemble(initial=row, save="final")
    assert "_arrays" not in ens.__dict__            # (made when read)
    back = pickle.loads(pickle.dumps(ens))
    assert "_run" not in back.__dict__
    row[0, 0] = 99.0
    assert ens.initial[0, 0] == disk.y0[0]
    p = disk._p.copy()
    for name in ("t", "y", "status", "steps", "t_final", "y_final", "initial", "params",
                 "event_counts"):
        a, b = getattr(ens, name), getattr(back, name)
        assert np.array_equal(a, b, equal_nan=True) and not a.flags.writeable, name
    with pytest.raises(ValueError):
        ens.params[...] = 2.0
    assert np.array_equal(disk._p, p)
    assert np.array_equal(ens.y[0, -1], disk.run(save="final").y[-1])


def test_a_loop_over_new_spans_runs_them_and_keeps_the_stores_bounded(disk):
    """Runs on ever new spans (each on the plan of another span of the same options, no
    plan made for it) equal runs of scenes built with those spans, ``y0`` checked and
    run from the span's own start; past ``MAX_PLANS`` options the stores drop their
    oldest entries, so options planned after such a loop are kept all the same."""
    from jetnh.numeric import solve

    scene = disk.replace(t_span=(0.0, 0.4))
    y = disk.y0.copy()
    y[4] += 0.01
    for k in range(solve.MAX_PLANS + 6):
        T = 0.01 + 1e-3 * k
        if k % 13 == 0:
            a = scene.run(t_span=(0.0, T), save="final", rtol=1e-7)
            b = Scene(disk.system, "chetaev", initial=DISK0, t_span=(0.0, T),
                      cache=False).run(save="final", rtol=1e-7)
            assert a.t.tobytes() == b.t.tobytes() and a.y.tobytes() == b.y.tobytes()
            c = scene.run(t_span=(0.1, 0.1 + T), y0=y, save="final", rtol=1e-7)
            d = disk.replace(initial=dict(zip(disk.state_names, y.tolist())),
                             t_span=(0.1, 0.1 + T)).run(save="final", rtol=1e-7)
            assert c.t.tobytes() == d.t.tobytes() and c.y.tobytes() == d.y.tobytes()
            assert c.t[0] == 0.1 and c.t[-1] == 0.1 + T
        scene.run(t_eval=np.linspace(0.0, T, 3))      # (a new array of times each)
    memo = scene._memo
    assert all(len(memo[s]) <= solve.MAX_PLANS for s in ("quick", "quick_spans", "plans"))
    scene.run(save="final", rtol=1e-6)
    key = next(reversed(memo["quick"]))
    assert memo["quick"][key] is not None and 1e-6 in key
    for bad in ((0.0, 0.0), (0.0, np.inf), (np.nan, 1.0), (1e20, 1e20 + 1e5)):
        with pytest.raises(JetnhError):
            scene.run(t_span=bad, save="final", rtol=1e-7)


@given(st.floats(allow_nan=True, allow_infinity=True, width=64),
       st.floats(allow_nan=True, allow_infinity=True, width=64))
def test_time_span_accepts_exactly_the_resolvable_spans(t0, t1):
    """``arguments.time_span`` against its rule written out: both ends finite, a finite
    length of at least ``MIN_TIME_RESOLUTION`` units in the last place of the larger."""
    import math

    ok = (math.isfinite(t0) and math.isfinite(t1) and math.isfinite(t1 - t0)
          and abs(t1 - t0) >= arguments.MIN_TIME_RESOLUTION * math.ulp(max(abs(t0), abs(t1)))
          and t0 != t1)
    if ok:
        assert arguments.time_span((t0, t1)) == (t0, t1)
    else:
        with pytest.raises(JetnhError):
            arguments.time_span((t0, t1))
