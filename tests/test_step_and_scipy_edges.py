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
