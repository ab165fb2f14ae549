"""Edges of a run's inputs: the step a fixed-step method takes from ``h=``; scipy's
methods on the ``t_eval`` and ``first_step`` the compiled methods accept."""

import numpy as np
import pytest
import sympy as sp

import jetnh as jn
from jetnh.numeric import arguments

J = jn.JetSpace("x")
(X,), (XT,) = J.q, J.qd
OSC = jn.System(J, XT**2 / 2 - X**2 / 2)       # x = cos t from x = 1, x_t = 0


def oscillator(t_span=(0.0, 10.0)):
    t0 = t_span[0]
    return jn.Scene(OSC, initial={X: np.cos(t0), XT: -np.sin(t0)}, t_span=t_span)


@pytest.mark.parametrize("span, h, steps", [
    ((0.0, 1.0), 0.7, 2), ((0.0, 1.0), 0.4, 3), ((0.0, 1.0), 0.3, 4),
    ((0.0, 1.0), 0.1, 10), ((0.0, 0.3), 0.1, 3), ((0.0, 8.0), 0.02, 400),
    ((0.0, 1.0), 1 / 3, 3), ((5.0, 0.0), 0.7, 8), ((0.0, 1.0), 5.0, 1)])
def test_the_step_taken_from_h_is_at_most_h(span, h, steps):
    n = arguments.fixed_steps(None, h, *span, "rk4", 10**6)
    assert n == steps
    assert abs(span[1] - span[0]) / n <= h * (1 + 1e-9)


@pytest.mark.parametrize("method", ["rk4", "dla"])
def test_a_run_from_h_takes_steps_no_longer_than_h(method):
    tr = oscillator((0.0, 1.0)).run(method=method, h=0.7)
    np.testing.assert_allclose(tr.t, [0.0, 0.5, 1.0], rtol=0, atol=1e-15)
    same = oscillator((0.0, 1.0)).run(method=method, n_steps=2)
    np.testing.assert_array_equal(tr.y, same.y)


T_EVALS = [[0.0, 3.0, 3.0, 5.0], [], [0.0, 0.0, 10.0, 10.0]]


@pytest.mark.parametrize("method", ["scipy-RK45", "scipy-DOP853", "scipy-Radau"])
@pytest.mark.parametrize("te", T_EVALS)
def test_scipy_takes_the_t_eval_the_compiled_methods_take(method, te):
    sc = oscillator()
    own, tr = sc.run(t_eval=te, rtol=1e-10, atol=1e-12), sc.run(
        method=method, t_eval=te, rtol=1e-10, atol=1e-12)
    assert tr.status == own.status == 0
    np.testing.assert_array_equal(tr.t, te)
    assert tr.y.shape == own.y.shape == (len(te), 2)
    np.testing.assert_allclose(tr["x"], np.cos(te), rtol=0, atol=1e-7)
    np.testing.assert_allclose(tr["x"], own["x"], rtol=0, atol=1e-7)


def test_scipy_repeated_times_backwards_and_a_stop_before_the_first_time():
    sc = oscillator((10.0, 0.0))
    tr = sc.run(method="scipy-RK45", t_eval=[10.0, 3.0, 3.0, 0.0], rtol=1e-10, atol=1e-12)
    np.testing.assert_array_equal(tr.t, [10.0, 3.0, 3.0, 0.0])
    np.testing.assert_array_equal(tr.y[1], tr.y[2])
    np.testing.assert_allclose(tr["x"], np.cos(tr.t), rtol=0, atol=1e-8)
    stop = jn.Event(X - 0.5, terminal=True)       # cos t = 0.5 at t = 7 pi / 3 (backwards)
    for m in ("dop853", "scipy-RK45"):
        early = sc.run(method=m, t_eval=[3.0, 1.0], events=[stop], rtol=1e-10, atol=1e-12)
        assert early.t.shape == (0,) and early.y.shape == (0, 2)
        assert early.t_events[0] == pytest.approx([7 * np.pi / 3], abs=1e-8)


@pytest.mark.parametrize("method", ["dop853", "scipy-RK45", "scipy-LSODA"])
def test_a_first_step_beyond_the_span_is_taken_as_the_span(method):
    tr = oscillator().run(method=method, first_step=100.0, rtol=1e-10, atol=1e-12)
    assert tr.status == 0
    assert tr["x"][-1] == pytest.approx(np.cos(10.0), abs=1e-7)


def test_scipy_stops_at_a_charts_edge_and_says_why():
    """knife edge: the split's chart ends at cos(phi) = 0, t = pi/2 (phi = t)."""
    from jetnh import models

    sc = jn.Scene(models.get("knife_edge"), "chetaev", initial=models.initial("knife_edge"),
                  t_span=(0.0, 2.0))
    own = sc.run(rtol=1e-10, atol=1e-12)
    assert own.status == 0 and own.t_final == 2.0 and len(own.switches) == 1
    tr = sc.run(method="scipy-DOP853", rtol=1e-10, atol=1e-12)
    assert tr.status == jn.numeric.SINGULAR
    assert tr.t_final == pytest.approx(np.pi / 2, abs=1e-6)
    assert own.switches[0]["from"] == ["y"] and own.switches[0]["t"] < np.pi / 2
    assert "scipy's methods do not change split" in tr.stop_reason
    assert "dop853's, dopri5's, rk4's and radau's" in tr.stop_reason


def test_messages_say_what_works():
    sc = oscillator()
    radau = sc.run(method="radau", rtol=1e-10, atol=1e-12)
    assert radau.at([1.5])["x"].iloc[0] == pytest.approx(np.cos(1.5), abs=1e-8)
    with pytest.raises(jn.JetnhError, match="scipy-RK45 trajectories have no dense output"):
        sc.run(method="scipy-RK45").at([1.5])
    rk4 = sc.run(method="rk4", n_steps=400)
    assert rk4.at([1.5])["x"].iloc[0] == pytest.approx(np.cos(1.5), abs=1e-8)
    with pytest.raises(jn.JetnhError, match=r"takes no t_eval: .*traj.at\(times\)"):
        sc.run(method="rk4", n_steps=10, t_eval=[1.0])
    with pytest.raises(jn.JetnhError, match=r"initial= takes every state, in Scene.replace"):
        sc.replace(initial={"x": 2.0})
    c = sp.Symbol("c")
    stiff = jn.Scene(jn.System(J, XT**2 / 2 - X**2 / 2, forces={X: -c * XT}),
                     params={c: 1e6}, initial={X: 1.0, XT: 0.0}, t_span=(0.0, 10.0))
    with pytest.raises(jn.JetnhError, match=r"stability bound .*method='radau'"):
        stiff.run(method="rk4", n_steps=1000)


def test_a_sweeps_times_in_any_order():
    sc = oscillator((10.0, 0.0))
    df = jn.sweep(sc, {"x": [np.cos(10.0)]}, times=[2.5, 7.5], outputs=["x"],
                  rtol=1e-10, atol=1e-12)
    assert list(df.columns[1:3]) == ["x(t=7.5)", "x(t=2.5)"]
    assert df["x(t=7.5)"][0] == pytest.approx(np.cos(7.5), abs=1e-8)
    assert df["x(t=2.5)"][0] == pytest.approx(np.cos(2.5), abs=1e-8)
    with pytest.raises(jn.JetnhError, match="times must lie within"):
        jn.sweep(sc, {"x": [1.0]}, times=[11.0])
