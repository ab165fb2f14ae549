"""The cheap paths of runs that watch a chart's edge (``jetnh.numeric.atlas``).

A run that never reaches its edge is its plan's one loop call and equals the same run
with split="fixed" (which watches nothing) bit for bit; a run that switches keeps the
pieces' own Trajectories unmade until read, and they equal what the loop results give;
the small-number arithmetic of a switch (one constraint's split measures, a chart's
velocities, a row mapped home) and its compiled route give the same numbers as the
numpy and determinant routes they replace; a warm switching run is one watched call.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import jetnh as jn
from jetnh.models import chaplygin_sleigh, knife_edge
from jetnh.numeric import Event, atlas, solve

RUN = dict(rtol=1e-8, atol=1e-11)


@pytest.fixture(scope="module")
def knife():
    """Heading rate 3 from phi = 0: the edge of dependent=['y'] (cos^2 phi = 1/8) comes
    at t = 0.41; T = 0.3 ends before it."""
    return jn.Scene(knife_edge(), "chetaev", initial=dict(x=0, y=0, phi=0, x_t=0.5, phi_t=3.0),
                    t_span=(0.0, 0.3))


@pytest.fixture(scope="module")
def sleigh():
    """The Chaplygin sleigh under vakonomic dynamics, one switch in T = 2."""
    scene = jn.Scene(chaplygin_sleigh(), "vakonomic",
                     initial=dict(x=0, y=0, theta=0, x_t=0.2, theta_t=1.0, lambda_y=0.1),
                     t_span=(0.0, 2.0))
    assert len(scene.run(**RUN).switches) == 1
    return scene


def _same(a, b):
    assert a.t.shape == b.t.shape and np.array_equal(a.t, b.t)
    assert np.array_equal(a.y, b.y)
    assert a.status == b.status and a.stop_reason == b.stop_reason
    assert a.diagnostics.steps == b.diagnostics.steps
    assert a.diagnostics.rhs_evaluations == b.diagnostics.rhs_evaluations


@pytest.mark.parametrize("method", ["dop853", "dopri5", "radau"])
@pytest.mark.parametrize("save", ["final", "steps"])
def test_run_before_the_edge_equals_fixed_split(knife, method, save):
    tr = knife.run(method=method, save=save, **RUN)
    assert solve.plan(knife, method, save=save).switch
    assert not tr.switches and tr._segments is None
    _same(tr, knife.run(method=method, save=save, split="fixed", **RUN))
    assert np.array_equal(tr.aux, knife.run(method=method, save=save, split="fixed",
                                            **RUN).aux)


def test_run_before_the_edge_with_events_and_t_eval(knife):
    """User events and t_eval: the edge watched after the user's events, which are
    reported as a run that keeps its split reports them."""
    phi = knife.system.J.q[2]
    events = [Event(phi - 0.5, name="half"), Event(phi - 0.8, terminal=True, name="stop")]
    t_eval = np.linspace(0.0, 0.3, 7)
    for kw in (dict(events=events), dict(t_eval=t_eval), dict(events=events[:1],
                                                              t_eval=t_eval)):
        a, b = knife.run(**RUN, **kw), knife.run(**RUN, split="fixed", **kw)
        _same(a, b)
        assert a.event_names == b.event_names
        for u, v in zip(a.t_events + a.y_events, b.t_events + b.y_events):
            assert np.array_equal(u, v)


def test_run_past_the_edge_at_the_start(knife):
    """Past the edge at t0 (phi = 1.4: cos^2 < 1/8): the run starts in dependent=['x']
    without a call in the scene's own chart."""
    tr = knife.run(y0=dict(x=0, y=0, phi=1.4, x_t=0.5, phi_t=3.0), t_span=(0.0, 0.3), **RUN)
    assert len(tr.switches) == 1 and tr.switches[0]["t"] == 0.0
    assert tr.switches[0]["to"] == ["x"]


def test_switching_run_reads_its_pieces_lazily(sleigh):
    tr = sleigh.run(save="final", **RUN)
    pieces = tr._segments.pieces
    assert len(pieces) == 2
    for _, _, _, seg, _, _ in pieces:
        assert isinstance(seg, atlas._Piece) and seg._traj is None
    # the rows kept come from the loop results: the first row of the first piece and the
    # last row of the last, mapped home
    first, last = pieces[0][3], pieces[1][3]
    assert tr.t[0] == first.out.ts[0] and tr.t[-1] == last.out.ts[int(last.out.n_out) - 1]
    assert np.array_equal(tr.y[0], first.out.ys[0])
    steps = sum(int(seg.out.stats[0]) for _, _, _, seg, _, _ in pieces)
    assert tr.diagnostics.steps == steps
    # a piece's Trajectory, made when read, is its chart's run as ``solve.trajectory``
    # makes it from the same loop result
    built = last.traj
    assert built is last.traj and np.array_equal(built.t, last.out.ts[:int(last.out.n_out)])
    chart = pieces[1][2]
    assert np.array_equal(tr.y[-1], atlas.to_home(tr._segments.own, chart, built.t[-1:],
                                                  built.y[-1:], tr._p)[0])
    # the stitched aux rows and a run with every step agree on the end
    full = sleigh.run(**RUN)
    assert np.array_equal(full.y[-1], tr.y[-1]) and np.array_equal(full.aux[-1], tr.aux[-1])


@pytest.mark.parametrize("save", ["final", "steps"])
def test_switching_run_maps_its_rows_when_read(sleigh, save):
    """A switching run's rows are mapped to the scene's chart on first read: until then
    none are made; then each piece's rows of its loop result, mapped home, read-only,
    and a pickled copy holds the same rows."""
    import pickle

    tr = sleigh.run(save=save, **RUN)
    assert tr.__dict__["_rows"] is None
    own, pieces = tr._segments.own, tr._segments.pieces
    want_t, want_y = [], []
    for lo, hi, chart, seg, a, _ in pieces:
        t = seg.out.ts[a:a + hi - lo]
        Y = np.ascontiguousarray(seg.out.ys[a:a + hi - lo])
        want_t.append(t)
        want_y.append(Y if chart is own else
                      np.concatenate([atlas.to_home(own, chart, t[i:i + 1], Y[i:i + 1], tr._p)
                                      for i in range(len(t))]))
    assert np.array_equal(tr.y, np.concatenate(want_y))
    assert np.array_equal(tr.t, np.concatenate(want_t)) and len(tr) == len(tr.t)
    assert not tr.t.flags.writeable and not tr.y.flags.writeable
    back = pickle.loads(pickle.dumps(tr))
    assert np.array_equal(back.t, tr.t) and np.array_equal(back.y, tr.y)


def test_switch_through_lists_equals_the_array_route(sleigh):
    """``atlas.switch`` of a chart whose multipliers keep their values (the numbers
    copied through lists) gives the state of ``Chart.point`` then ``_target``, bit for
    bit, at every row of the first piece."""
    tr = sleigh.run(**RUN)
    at, own = atlas.atlas(sleigh), tr._segments.own
    assert not own.explicit
    seg = tr._segments.pieces[0][3]
    for r in range(len(seg.t)):
        t, y = float(seg.t[r]), np.ascontiguousarray(seg.y[r])
        got = atlas.switch(at, own, t, y, tr._p)
        want = atlas._target(at, own, t, tr._p, *own.point(t, y, tr._p))
        assert (got is None) == (want is None)
        if got is not None:
            assert got[0] is want[0] and np.array_equal(got[1], want[1])


def test_switching_runs_repeat_bit_for_bit_and_keep_their_entries(sleigh):
    a = sleigh.run(**RUN)
    new = a._segments.pieces[1][2]
    entries = dict(new._entries)
    for _ in range(3):
        b = sleigh.run(**RUN)
        assert np.array_equal(a.t, b.t) and np.array_equal(a.y, b.y)
        assert a.switches == b.switches
    assert new._entries.keys() == entries.keys()       # looked up once
    c = sleigh.run(method="dopri5", **RUN)          # (follow: its loop looked up)
    assert len(new._entries) == len(entries) + 1 and c.switches
    d = sleigh.run(method="dopri5", **RUN)          # (follow or chart_driver: the same)
    assert len(new._entries) == len(entries) + 1 and d.switches == c.switches


def test_switching_run_with_a_timeout_equals_one_without(sleigh):
    a, b = sleigh.run(**RUN), sleigh.run(timeout=60.0, **RUN)
    assert np.array_equal(a.t, b.t) and np.array_equal(a.y, b.y) and a.switches == b.switches


@settings(deadline=None)
@given(st.lists(st.floats(-1e3, 1e3, allow_nan=False, allow_subnormal=False), min_size=2,
                max_size=6))
def test_one_constraint_measures(row):
    """One constraint: m_c = A_c^2 / |A|^2, summed in order as the determinant route sums
    the Gram matrix's one entry; against numpy's route to 1e-12, summing to 1
    (Cauchy-Binet)."""
    A = np.array([row])
    columns = [[c] for c in range(len(row))]
    got = atlas.measures_at(A, columns)
    gram = sum(a * b for a, b in zip(row, row))
    if not gram > 0.0:
        assert got == [0.0] * len(row)
        return
    assert got == [row[c] ** 2 / gram for c in range(len(row))]
    want = [float(atlas.split_measure_of(A, [c])) for c in range(len(row))]
    assert np.allclose(got, want, rtol=1e-12, atol=0)
    assert abs(sum(got) - 1.0) < 1e-12


def test_two_constraint_measures_unchanged():
    """The general route (k = 2) against numpy's, and summing to 1 over the splits."""
    rng = np.random.default_rng(3)
    A = rng.normal(size=(2, 4))
    columns = [[i, j] for i in range(4) for j in range(i + 1, 4)]
    got = atlas.measures_at(A, columns)
    want = [float(atlas.split_measure_of(A, c)) for c in columns]
    assert np.allclose(got, want, rtol=1e-12) and abs(sum(got) - 1.0) < 1e-12


def test_chart_numbers_equal_the_array_routes(sleigh):
    """A chart's velocities, a state from a point and one row mapped home: the numbers
    the numpy routes (index assignment, ``aux_rows`` over several rows) give, bit for
    bit, in both charts of the sleigh."""
    tr = sleigh.run(**RUN)
    own, other = tr._segments.own, tr._segments.pieces[1][2]
    p = tr._p
    rng = np.random.default_rng(0)
    for chart, seg in ((own, tr._segments.pieces[0][3]), (other, tr._segments.pieces[1][3])):
        n, k = chart.n, chart.k
        Y = np.ascontiguousarray(seg.y)
        for r in rng.choice(len(Y), size=min(4, len(Y)), replace=False):
            t, y = float(seg.t[r]), Y[r]
            aux = np.empty(chart.kernels.layout.n_aux)
            chart.kernels.aux(t, y, p, aux)
            qd = np.empty(n)
            qd[chart.ind] = y[n:2 * n - k]
            qd[chart.dep] = aux[:k]
            assert np.array_equal(chart.velocities(t, y, p), qd)
            q, v, lam, A = chart.point(t, y, p)
            for split, target in atlas.atlas(sleigh).maps.items():
                assert np.array_equal(target.state_at(q, v, lam, A),
                                      np.concatenate((q, v[target.ind], lam)))
        if chart is not own:
            rows = atlas.to_home(own, chart, seg.t, Y, p)
            for r in range(len(Y)):
                assert np.array_equal(atlas.to_home(own, chart, seg.t[r:r + 1], Y[r:r + 1],
                                                    p), rows[r:r + 1])


def test_solve_plans_the_edge_as_the_last_event(sleigh, knife):
    for scene in (sleigh, knife):
        plan = solve.plan(scene, "dop853", save="final")
        assert plan.switch and plan.ce.names[-1] == atlas.EDGE
        assert list(plan.watch.ev_max) == [1]


@pytest.mark.parametrize("model", ["rolling_disk", "n_trailer"])
def test_compiled_change_equals_the_python_route(model):
    """``Atlas.change`` (one compiled call: velocities, df/dqdot, the measures by
    cofactors, the splits in order of measure, the new state and its check) gives the
    chart and the state of the Python route (``Chart.point`` then ``_target``) bit for
    bit, at random states of every chart of systems of two and three constraints with
    three and four splits; ``MISSING`` before the charts have kernels."""
    from jetnh import models

    scene = jn.Scene(getattr(models, model)(), "chetaev", initial=models.initial(model),
                     t_span=(0.0, 1.0))
    at = atlas.Atlas(scene)
    p = np.ascontiguousarray(scene.p, dtype=float)
    n_y = len(scene.state_names)
    rng = np.random.default_rng(7)
    assert at.change(at.own, 0.0, rng.normal(size=n_y), p) is atlas.MISSING
    charts = [at.chart(s, 0.0, rng.normal(size=n_y)) for s in at.splits]
    for chart in charts:
        chart.kernels, chart.jacobian_kernel
    at.register(*charts)
    assert at.made(charts[0]) and len(charts) > 2
    found = 0
    for chart in charts:
        for _ in range(40):
            t, y = float(rng.uniform(0.0, 1.0)), 2.0 * rng.normal(size=n_y)
            got = at.change(chart, t, y, p)
            want = atlas._target(at, chart, t, p, *chart.point(t, y, p))
            assert (got is None) == (want is None)
            if got is not None:
                found += 1
                assert got[0] is want[0] and np.array_equal(got[1], want[1])
    assert found > 100


def test_a_warm_switching_run_is_one_interrupt_call(monkeypatch):
    """A switching run whose charts, events and loops are made runs all its pieces in
    one ``interrupt.call``; the first run of a scene (its other chart made on the way,
    outside that call) and a run with a timeout (one call a piece) give the same
    trajectory bit for bit."""
    from jetnh.numeric import interrupt

    scene = jn.Scene(chaplygin_sleigh(), "chetaev",
                     initial=dict(x=0, y=0, theta=0, x_t=0.2, theta_t=1.0),
                     t_span=(0.0, 2.0))
    calls = []
    real = interrupt.call

    def counted(*args, **kw):
        calls.append(1)
        return real(*args, **kw)

    monkeypatch.setattr(interrupt, "call", counted)
    first = scene.run(save="final", **RUN)
    cold = len(calls)
    calls.clear()
    warm = scene.run(save="final", **RUN)
    assert len(warm.switches) == 1 and len(calls) == 1 and cold > 1
    timed = scene.run(save="final", timeout=60.0, **RUN)
    for tr in (warm, timed):
        _same(first, tr)
        assert tr.switches == first.switches


def test_ctrl_c_stops_a_switching_run_within_a_second():
    """Ctrl-C during a long run that changes chart again and again (its pieces in one
    ``interrupt.call``): every piece after it stops at once (the run ends, long before
    its end), the SIGINT handler runs once, after it."""
    import os
    import signal
    import threading
    import time

    scene = jn.Scene(knife_edge(), "chetaev",
                     initial=dict(x=0, y=0, phi=0, x_t=0.5, phi_t=3.0), t_span=(0.0, 1e5))
    scene.run(t_span=(0.0, 2.0), save="final", **RUN)        # (its charts made)
    seen = []
    before = signal.signal(signal.SIGINT, lambda signum, frame: seen.append(signum))
    fd = signal.set_wakeup_fd(-1)
    signal.set_wakeup_fd(fd)
    try:
        timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))
        timer.start()
        tic = time.monotonic()
        tr = scene.run(save="final", **RUN)
        elapsed = time.monotonic() - tic
        timer.join()
    finally:
        signal.signal(signal.SIGINT, before)
        signal.set_wakeup_fd(fd)
    assert elapsed < 3.0 and seen == [signal.SIGINT]     # (not at its end: ~100 s)
    assert len(tr.switches) > 10 and tr.t[-1] < 1e5
