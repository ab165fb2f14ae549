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
