"""Every row a run reports between its projected steps lies on the holonomic constraints
g = 0: the rows at ``t_eval`` of ensembles and sweeps (the compiled batch path), the
states of events and of a stop inside a step, the rows of runs with sensitivities (S on
the tangent of g = 0: G S_q + dg/dp = 0) and rk4's Hermite ``Trajectory.at``.  Each was
off g = 0 by the dense output's error before (a Cartesian pendulum over 100 s: 2.4e-9 in
an ensemble's rows, 3.6e-10 at events, 1.9e-10 at a terminal event, 4.3e-10 and
G S = 1.9e-8 in a sensitivity run's rows, 7.9e-10 in rk4's ``at``; a Kane four-bar's
ensemble rows 1.4e-9 off its loop closure).

Second routes: a single run's rows (an ensemble's runs are single runs, to the bit), an
event's state against the row ``t_eval`` gives at its time (the same interpolant at the
same time), central differences of projected runs for the sensitivities, dop853 at a
tight tolerance for rk4's values, and the closed form of the projection onto a circle
(radial).  Also: a switch of chart within the time resolution of the end of the span
ends the run in its chart (it was refused as an unresolvable span).
"""

import math

import numba
import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import jetnh as jn
from jetnh.models import knife_edge
from jetnh.modelfile import loads
from jetnh.numeric import Event
from jetnh.numeric.kernels.calls import Kernel
from jetnh.numeric.methods import projection
from jetnh.numeric.methods._common import RHS_SIGNATURE

from holonomic_systems import FOURBAR, kane_fourbar, knife_slider
from model_texts import PENDULUM_XY_STARTED

T1 = 100.0
TE = np.linspace(0.0, T1, 501)
RATES = np.linspace(0.5, 1.5, 6)


@pytest.fixture(scope="module")
def pendulum():
    """x^2 + y^2 = 1 with gravity G as a runtime parameter."""
    model = loads(PENDULUM_XY_STARTED)
    return jn.Scene(model.system, "chetaev", params={"G": 9.81, "l": 1.0},
                    initial=dict(model.initial), t_span=(0.0, T1), runtime_params=["G"])


def residual(x, y):
    return np.abs(x**2 + y**2 - 1.0)


# ------------------------------------------------------------------ ensembles, sweeps
@pytest.mark.parametrize("parallel", ["threads", "serial"])
def test_ensemble_rows_lie_on_g_and_are_the_single_runs(pendulum, parallel):
    gs = np.linspace(9.0, 10.5, RATES.size)
    ens = pendulum.ensemble(initial={"x_t": RATES}, params={"G": gs}, t_eval=TE,
                            parallel=parallel, workers=2)
    assert ens.success.all()
    assert residual(ens["x"], ens["y"]).max() < 1e-14           # was 2.6e-9
    assert ens.holonomic_residual_max.max() < 1e-14
    for r in (0, RATES.size - 1):
        one = pendulum.run(y0={"x_t": RATES[r]}, params={"G": gs[r]}, t_eval=TE)
        assert np.array_equal(ens.y[r], one.y)


def test_sweep_times_lie_on_g_and_are_the_single_runs(pendulum):
    times = [33.3, 77.7]
    df = jn.sweep(pendulum, {"x_t": [0.5, 1.0]}, times=times, outputs=["x", "y"])
    for i, w in enumerate([0.5, 1.0]):
        one = pendulum.run(y0={"x_t": w}, t_eval=times)
        got = [df[f"{n}(t={t:.12g})"][i] for n in ("x", "y") for t in times]
        assert got == one["x"].tolist() + one["y"].tolist()
        assert residual(one["x"], one["y"]).max() < 1e-14           # was 2.2e-10


def test_ensemble_stopped_inside_a_step_ends_on_g(pendulum):
    """A terminal event stops the runs inside a step: their last state (and with
    save="final" their one row) on g = 0, the single run's."""
    x = pendulum.system.J.q[0]
    stop = [Event(x, terminal=5)]
    for kw in ({"save": "final"}, {"t_eval": TE}):
        ens = pendulum.ensemble(initial={"x_t": RATES}, events=stop, **kw)
        assert (ens.status == 5).all()
        yf = ens.y_final
        assert residual(yf[:, 0], yf[:, 1]).max() < 1e-14           # was 1.9e-10
        one = pendulum.run(y0={"x_t": RATES[2]}, events=stop, **kw)
        assert np.array_equal(yf[2], one.y_events[0][-1])
        if "save" in kw:
            assert np.array_equal(ens.y[:, 0], yf) and np.array_equal(one.y[-1], yf[2])


# ------------------------------------------------------------------ events
@pytest.mark.parametrize("method", ["dop853", "rk4"])
def test_event_states_lie_on_g_and_are_the_rows_at_their_times(pendulum, method):
    """(rk4 locates events on its Hermite interpolant: 8.0e-10 off g = 0 before.)"""
    kw = {"n_steps": 20000} if method == "rk4" else {}
    x = pendulum.system.J.q[0]
    tr = pendulum.run(events=[x], method=method, **kw)
    t_ev, y_ev = tr.t_events[0], tr.y_events[0]
    assert len(t_ev) > 50
    assert residual(y_ev[:, 0], y_ev[:, 1]).max() < 1e-14           # was 3.6e-10
    # on g's gradient (0, 2y) at x = 0 the projection hardly moves x: still a root
    assert np.abs(y_ev[:, 0]).max() < 1e-13
    if method == "dop853":
        # the same interpolant at the same times, projected the same way
        rows = pendulum.run(t_eval=t_ev)
        assert np.array_equal(rows.y, y_ev)
    # a terminal one: the run's last row and last state
    stop = pendulum.run(events=[Event(x, terminal=5)], method=method, **kw)
    assert stop.status == 5 and np.array_equal(stop.t[-1], t_ev[4])
    assert np.array_equal(stop.y[-1], y_ev[4]) and np.array_equal(stop.y_events[0][-1],
                                                                  y_ev[4])


# ------------------------------------------------------------------ sensitivities
A = 0.4


@pytest.fixture(scope="module")
def slider():
    """The knife edge with a slider z = a sin th (``holonomic_systems``), a and k at
    run time: g depends on the parameter a."""
    ini = {"x": 0.1, "y": -0.2, "th": 0.3, "z": A * np.sin(0.3), "x_t": 1.0, "th_t": 0.7}
    return jn.Scene(knife_slider(), "chetaev", params={"a": A, "k": 3.0, "I": 0.7},
                    initial=ini, t_span=(0.0, 1.5), runtime_params=["a", "k"])


def tangent_defect(names, columns, th, S):
    """G S_q + dg/dp of every row and column (g = z - a sin th, G = (0, 0, -a cos th, 1),
    dg/da = -sin th) at the rows' angles ``th``."""
    col = columns.index("a")
    GS = -A * np.cos(th)[:, None] * S[:, names.index("th")] + S[:, names.index("z")]
    GS[:, col] -= np.sin(th)
    return GS


@pytest.mark.parametrize("method", ["dop853", "rk4"])
def test_sensitivity_rows_lie_on_the_tangent_of_g(slider, method):
    kw = dict(rtol=1e-12, atol=1e-14) if method == "dop853" else dict(n_steps=400)
    te = np.linspace(0.0, 1.5, 41)
    steps = slider.run(method=method, sensitivities=True, split="fixed", **kw)
    rows = (steps.at(te).to_numpy() if method == "rk4" else None)
    if method == "dop853":
        tr = slider.run(method=method, sensitivities=True, split="fixed", t_eval=te, **kw)
        assert np.abs(tr["z"] - A * np.sin(tr["th"])).max() < 1e-15
        S = tr.sensitivities
        # the start: along g = 0 in the split's chart (z follows th and a, its column 0)
        iz = slider.state_names.index("z")
        keep = np.arange(S.shape[1]) != iz
        assert np.array_equal(S[0][keep], np.eye(S.shape[1], S.shape[2])[keep])
        assert not S[:, :, iz].any()
        scale = max(1.0, np.abs(S).max())
        assert np.abs(tangent_defect(slider.state_names, tr.sensitivity_columns, tr["th"],
                                     S)).max() < 1e-13 * scale
        # through ensembles: the same rows
        ens = slider.ensemble(initial={"x_t": np.array([1.0, 0.8])}, t_eval=te,
                              sensitivities=True, split="fixed", **kw)
        assert np.array_equal(ens.sensitivities[0], S) and np.array_equal(ens.y[0], tr.y)
        # central differences of projected runs' rows in a (each from its start on g)
        base = dict(zip(slider.state_names, slider.y0.tolist()))
        h = 1e-6

        def at(a):
            return slider.run(method=method, y0={**base, "z": a * np.sin(base["th"])},
                              params={"a": a, "k": 3.0}, t_eval=te, split="fixed", **kw).y

        fd = (at(A + h) - at(A - h)) / (2 * h)
        col = tr.sensitivity_columns
        want = S[:, :, col.index("a")] + np.sin(base["th"]) * S[:, :, col.index("z")]
        assert np.abs(fd - want).max() < 2e-7 * max(1.0, np.abs(want).max())
    else:
        from jetnh.numeric.dense import evaluate

        full = evaluate(steps, te[1:-1], full=True)
        n = len(slider.state_names)
        th, z = full[:, slider.state_names.index("th")], full[:, slider.state_names.index("z")]
        assert np.abs(z - A * np.sin(th)).max() < 1e-15               # state rows
        S = full[:, n:].reshape(-1, n, len(steps.sensitivity_columns))
        inner = slider.run(method="dop853", t_eval=te[1:-1], split="fixed", rtol=1e-12,
                           atol=1e-14, sensitivities=True)
        assert np.abs(tangent_defect(slider.state_names, steps.sensitivity_columns, th,
                                     S)).max() < 1e-13 * max(1.0, np.abs(S).max())
        assert np.abs(full[:, :n] - inner.y).max() < 1e-8            # rk4's error, h^4
        assert np.array_equal(rows[0], steps.y[0])


# ------------------------------------------------------------------ rk4's at()
def test_rk4_values_between_steps_lie_on_g(pendulum):
    tr = pendulum.run(method="rk4", n_steps=20000)
    tau = np.linspace(0.013, 99.9, 777)
    y = tr.at(tau).to_numpy()
    assert residual(y[:, 0], y[:, 1]).max() < 1e-14                 # was 7.9e-10
    ref = pendulum.run(t_eval=tau, rtol=1e-12, atol=1e-14)
    assert np.abs(y - ref.y).max() < 1e-6                             # the same motion
    # at the steps: the steps' own rows, to the bit
    assert np.array_equal(tr.at(tr.t[:300]).to_numpy(), tr.y[:300])


# ------------------------------------------------------------------ the projection itself
@numba.cfunc(RHS_SIGNATURE)
def _circle(t, y, p, out):         # g = x^2 + y^2 - r^2, r^2 = p0 + t/10
    out[0] = y[0]**2 + y[1]**2 - p[0] - t / 10
    out[1] = 2 * y[0]
    out[2] = 2 * y[1]


def test_projection_onto_a_circle_is_radial_with_a_parameter_per_row():
    """On a circle g's gradient is radial, so every Gauss-Newton iterate stays on the
    ray: the projection is (x, y) r / |(x, y)|.  Rows with a parameter row each,
    together, are each row alone."""
    circle = Kernel(_circle, (3, 1, 3))
    rng = np.random.default_rng(7)
    ys = rng.uniform(-2, 2, (9, 3))
    ts = np.linspace(0.0, 1.0, 9)
    P = rng.uniform(0.5, 2.0, (9, 1))
    P[3] = P[5] = P[0]
    together = ys.copy()
    projection.rows(circle, 1, 2, ts, together, P)
    r = np.sqrt(P[:, 0] + ts / 10)
    radial = ys[:, :2] * (r / np.hypot(ys[:, 0], ys[:, 1]))[:, None]
    assert np.allclose(together[:, :2], radial, rtol=0, atol=1e-15)
    assert np.array_equal(together[:, 2], ys[:, 2])
    for i in range(9):
        alone = ys[i:i + 1].copy()
        projection.rows(circle, 1, 2, ts[i:i + 1], alone, P[i])
        assert np.array_equal(alone[0], together[i])


def test_rows_that_do_not_fit_the_kernel_are_refused():
    circle = Kernel(_circle, (3, 1, 3))
    ys, ts = np.zeros((2, 3)), np.zeros(2)
    with pytest.raises(ValueError, match="do not fit"):
        projection.rows(circle, 1, 2, ts, np.zeros((2, 2)), np.ones(1))     # short rows
    with pytest.raises(ValueError, match="do not fit"):
        projection.rows(circle, 1, 2, ts, ys, np.ones(0))                  # no parameter
    with pytest.raises(ValueError, match="do not fit"):
        projection.rows(circle, 1, 2, ts[:1], ys, np.ones(1))              # a time missing
    with pytest.raises(TypeError, match="writable"):
        projection.rows(circle, 1, 2, ts, np.zeros((3, 2)).T, np.ones(1))  # not C order


# ------------------------------------------------------------------ a switch at the end
@pytest.mark.parametrize("ulps", [0, 3, 1000, 60000])
def test_a_chart_edge_within_the_resolution_of_t1_ends_the_run_in_its_chart(ulps):
    """The knife edge's first switch at t_s; spans ending a few units in the last place
    after it ended with "t_span cannot be resolved" (the new chart's scene spans
    (t_s, t1)); now the run finishes at t1 in its chart, as a run and as an ensemble."""
    tol = dict(rtol=1e-11, atol=1e-12)

    def scene(t1):          # (its own atlas: the second chart not built yet)
        return jn.Scene(knife_edge(), "chetaev", initial=dict(x=0, y=0, phi=0, x_t=0.5,
                                                                phi_t=3.0), t_span=(0.0, t1))

    long = scene(1.0).run(**tol)
    t_s = long.switches[0]["t"]
    t1 = t_s + ulps * math.ulp(t_s)
    tr = scene(t1).run(**tol)
    assert tr.status == 0 and tr.t[-1] == t1 and not tr.switches
    assert np.abs(tr.y[-1] - long.at([t1]).to_numpy()[0]).max() < 1e-10
    ens = scene(t1).ensemble(initial={"phi_t": np.array([3.0, 1.0])}, **tol)
    assert (ens.status == 0).all() and np.array_equal(ens.y_final[0], tr.y[-1])


# ------------------------------------------------------------------ two constraints
@pytest.fixture(scope="module")
def fourbar():
    """A Kane four-bar (links 1, 3, 2 from the origin closing on (3, 0)): two
    loop-closure constraints, one degree of freedom."""
    pytest.importorskip("sympy.physics.mechanics")
    return jn.Scene(kane_fourbar(), "chetaev", params=FOURBAR,
                    initial={"q1": 1.2, "q2": 0.3, "q3": -1.5, "q1_t": 2.0},
                    complete=True, t_span=(0.0, 30.0))


def loop_closure(y, names):
    """|g| of the rows ``y``: the end of the third link's distance from (3, 0)."""
    q1, q2, q3 = (y[:, names.index(n)] for n in ("q1", "q2", "q3"))
    return np.hypot(np.cos(q1) + 3 * np.cos(q2) + 2 * np.cos(q3) - 3,
                    np.sin(q1) + 3 * np.sin(q2) + 2 * np.sin(q3))


def test_fourbar_ensemble_and_event_rows_close_the_loop(fourbar):
    names = fourbar.state_names
    te = np.linspace(0.0, 30.0, 301)
    ens = fourbar.ensemble(initial={"q1_t": np.array([1.0, 2.0, 3.0])}, t_eval=te)
    assert ens.success.all()
    assert max(loop_closure(ens.y[r], names).max() for r in range(3)) < 1e-13   # 1.4e-9
    one = fourbar.run(y0={"q1_t": 2.0}, t_eval=te)
    assert np.array_equal(ens.y[1], one.y)
    q1 = fourbar.system.J.q[0]
    tr = fourbar.run(events=[sp.sin(q1)])
    assert len(tr.t_events[0]) > 10
    assert loop_closure(tr.y_events[0], names).max() < 1e-13


@settings(deadline=None)
@given(m=st.integers(1, 2), extra=st.integers(1, 2), n_rows=st.integers(1, 6),
       seed=st.integers(0, 2**32 - 1))
def test_rows_and_their_sensitivities_against_the_linear_closed_form(m, extra, n_rows,
                                                                     seed):
    """g = A q - B p - c t (linear): the projection is the orthogonal one,
    q - A^+ g (A^+ = A^T (A A^T)^{-1}, numpy's pinv), reached in one step; the
    sensitivities' coordinate rows become S_q - A^+ (A S_q + dg/dp), dg/dp = -B in the
    parameters' columns, so that A S_q = B there and 0 elsewhere."""
    rng = np.random.default_rng(seed)
    nq, n_p = m + extra, 2
    n = nq + 1                                        # one velocity besides
    n_sens = n + n_p
    A, B, c = rng.normal(size=(m, nq)), rng.normal(size=(m, n_p)), rng.normal(size=m)

    Bt = -B.ravel()

    @numba.cfunc(RHS_SIGNATURE)
    def hol(t, y, p, out):
        for i in range(m):
            acc = -c[i] * t
            for j in range(nq):
                acc += A[i, j] * y[j]
                out[m + i * nq + j] = A[i, j]
            for k in range(n_p):
                acc -= B[i, k] * p[k]
                out[m + m * nq + i * n_p + k] = Bt[i * n_p + k]
            out[i] = acc

    ts = rng.uniform(0, 1, n_rows)
    p = rng.normal(size=n_p)
    ys = rng.normal(size=(n_rows, n * (1 + n_sens)))
    got = ys.copy()
    projection.rows(Kernel(hol, (n * (1 + n_sens), n_p, m * (1 + nq + n_p))), m, nq, ts, got,
                    p, n_sens)
    pinv = np.linalg.pinv(A)
    g = ys[:, :nq] @ A.T - B @ p - ts[:, None] * c
    assert np.allclose(got[:, :nq], ys[:, :nq] - g @ pinv.T, rtol=0, atol=1e-12)
    assert np.array_equal(got[:, nq:n], ys[:, nq:n])             # velocities as they were
    S, T = ys[:, n:].reshape(-1, n, n_sens), got[:, n:].reshape(-1, n, n_sens)
    dgdp = np.zeros((m, n_sens))
    dgdp[:, n_sens - n_p:] = -B
    want = S[:, :nq] - pinv @ (A @ S[:, :nq] + dgdp)
    assert np.allclose(T[:, :nq], want, rtol=0, atol=1e-12)
    assert np.allclose(A @ T[:, :nq] + dgdp, 0.0, atol=1e-12)
    assert np.array_equal(T[:, nq:], S[:, nq:])
