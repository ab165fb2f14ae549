"""Runs that an explicit method cannot finish stop early, with the cause and the way out.

* Hairer's stiffness test (``methods.loop``): a heavily damped oscillator x'' = -c x' - x
  (eigenvalues ~ -c and -1/c) is stiff for c = 1e6; dop853 and dopri5 would take ~10^6
  steps over t = 0..10 and now stop with status STIFF after a bounded number of them,
  with the rows of a run cut a step before bit for bit; radau finishes it.
* The estimate of h |lambda| is |h lambda| exactly on y' = lambda y (hypothesis).
* Crawling toward a singular set (``methods._events.sing_crawl``): Suslov's equations in
  the paper's convention for a sleigh in centre-of-mass coordinates with dependent=[Y]
  run into cos(th) = 0, where the split is singular and the run cannot change split; at
  rtol 1e-12 dop853 took 647 315 steps and stopped with a NaN state, blaming "the
  constraints themselves"; now it stops within a few thousand steps at a finite state,
  naming the singular set and the regular split, also with sensitivities; radau, whose
  step collapses there, says so.
"""

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import assume, given, settings, strategies as st

import jetnh as jn
from jetnh import models
from jetnh.numeric import Status
from jetnh.numeric.methods import loop

BOUND_STEPS = 3 * loop.STIFF_EVERY         # a few test windows


@pytest.fixture(scope="module")
def damped():
    J = jn.JetSpace("x")
    (x,), (xd,) = J.q, J.qd
    c = sp.Symbol("c", positive=True)
    system = jn.System(J, xd**2 / 2 - x**2 / 2, forces={"x": -c * xd})
    return jn.Scene(system, "chetaev", params={"c": 1e6}, runtime_params=["c"],
                    initial={"x": 1.0, "x_t": 0.0},
                    t_span=(0.0, 10.0))


@pytest.mark.parametrize("method", ["dop853", "dopri5"])
def test_a_stiff_problem_stops_early_with_the_cause(damped, method):
    tr = damped.run(method=method, rtol=1e-6, atol=1e-9)
    assert tr.status == Status.STIFF and not tr.success
    assert tr.diagnostics.steps <= BOUND_STEPS and tr.t[-1] < 0.1
    assert "became stiff" in tr.stop_reason and "method='radau'" in tr.stop_reason
    assert np.all(np.isfinite(tr.y))
    # the test changes no step: a run cut one step before has the same rows
    cut = damped.run(method=method, rtol=1e-6, atol=1e-9,
                     max_steps=tr.diagnostics.steps - 1)
    assert cut.status == Status.MAX_STEPS
    assert np.array_equal(cut.t, tr.t[:-1]) and np.array_equal(cut.y, tr.y[:-1])


def test_radau_finishes_the_stiff_problem(damped):
    tr = damped.run(method="radau", rtol=1e-6, atol=1e-9)
    assert tr.status == Status.FINISHED and tr.diagnostics.steps < 100
    # x'' + c x' + x = 0 from (1, 0): the slow mode exp(-t/c) dominates after t ~ 1/c
    lam = (-1e6 + math.sqrt(1e12 - 4)) / 2
    assert abs(tr["x"][-1] - math.exp(lam * 10.0)) < 1e-5


def test_a_mildly_damped_run_is_not_stiff(damped):
    tr = damped.run(params={"c": 0.1}, rtol=1e-10, atol=1e-12, max_step=1e-3)
    assert tr.status == Status.FINISHED and tr.diagnostics.steps > 2 * loop.STIFF_EVERY


@settings(max_examples=25, deadline=None)
@given(st.floats(-1e6, 1e6).filter(lambda v: abs(v) > 1e-6),
       st.floats(1e-6, 1.0), st.lists(st.floats(-1e3, 1e3), min_size=1, max_size=6),
       st.lists(st.floats(-1e3, 1e3), min_size=6, max_size=6))
def test_the_estimate_is_h_lambda_on_a_linear_problem(lam, h, ya, yb):
    y_new = np.array(ya)
    y_last = y_new + np.array(yb[:len(ya)])
    assume(np.abs(y_new - y_last).max() > 1e-100)    # (squares of less underflow)
    ratio = loop.stiff_ratio.py_func(h, y_new, y_last, lam * y_new, lam * y_last)
    assert ratio == pytest.approx(abs(h * lam), rel=1e-12)


@pytest.fixture(scope="module")
def suslov_sleigh():
    J = jn.JetSpace("X Y th")
    _, _, th = J.q
    Xt, Yt, tht = J.qd
    m, I, a = sp.symbols("m I a", positive=True)
    L = m / 2 * (Xt**2 + Yt**2) + I / 2 * tht**2
    f = [-sp.sin(th) * Xt + sp.cos(th) * Yt - a * tht]
    system = jn.System(J, L, f, dependent=[J.q[1]])
    initial = {"X": 0.1, "Y": -0.2, "th": 0.3, "X_t": 0.8, "th_t": 0.5, "lambda_Y": 0.4}
    return jn.Scene(system, "suslov", params={"m": 2.0, "I": 0.7, "a": 0.4},
                    initial=initial, t_span=(0.0, 3.0))


def _approach(tr, steps):
    assert tr.status == Status.SINGULAR and tr.diagnostics.steps < steps
    assert np.all(np.isfinite(tr.y)) and 1.3 < tr.t[-1] < 1.321
    assert tr.singularity["indicator"] == "cos(th)" and tr.singularity["kind"] == "split"
    assert 0 < math.cos(tr["th"][-1]) < 1e-2
    r = tr.stop_reason
    assert "approaches the singular set cos(th) = 0" in r and "cannot step closer" in r
    assert "dependent=['X'] is regular" in r and "cannot change split" in r
    assert "themselves are singular" not in r and "fell to nan" not in r and "kink" not in r


@pytest.mark.parametrize("rtol", [1e-8, 1e-12])
def test_suslov_sleigh_stops_where_it_cannot_approach_its_singular_split(suslov_sleigh,
                                                                          rtol):
    _approach(suslov_sleigh.run(rtol=rtol, atol=rtol / 10), 20_000)


def test_suslov_sleigh_with_sensitivities_stops_too(suslov_sleigh):
    tr = suslov_sleigh.run(rtol=1e-12, atol=1e-13, sensitivities=True)
    _approach(tr, 40_000)


def test_a_regular_approach_is_not_a_crawl():
    """The knife edge's dependent velocity tan(phi) xdot blows up like 1/(t* - t): the
    adaptive steps shrink with the distance to t*, and the run reaches the threshold."""
    ke = models.get("knife_edge")
    scene = jn.Scene(ke, "chetaev", initial=models.initial("knife_edge"),
                     t_span=(0.0, 2.0))
    for method in ("dop853", "dopri5"):
        tr = scene.run(method=method, rtol=1e-12, atol=1e-14, split="fixed")
        assert tr.status == Status.SINGULAR
        assert abs(math.cos(tr["phi"][-1])) <= 1.01e-10 and "fell to" in tr.stop_reason


def test_radau_near_the_singular_split_says_where_its_step_collapsed(suslov_sleigh):
    tr = suslov_sleigh.run(method="radau", rtol=1e-12, atol=1e-13)
    assert tr.status == Status.TOO_SMALL_STEP and 1.3 < tr.t[-1] < 1.321
    r = tr.stop_reason
    assert "fell below the spacing" in r and "near the singular set cos(th) = 0" in r
    assert "dependent=['X'] is regular" in r and "cannot change split" in r
