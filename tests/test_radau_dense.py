"""radau runs are evaluated between their rows (``Trajectory.at``) by each step's
collocation polynomial, the one the run's ``t_eval`` and events use
(``radau.collocation``): checked against the run's own rows, against the same run's
``t_eval`` output (to the run's ``newton_tol``: the run stops Newton there, ``at``
solves the stage equations to rounding level) and against a tight reference; on a
holonomic system the values inside a step lie on g = 0; with sensitivities, a change of
split and after pickling alike."""

import pickle

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import jetnh as jn
from jetnh import models
from jetnh.numeric.dense import evaluate

TIGHT = dict(rtol=1e-7, atol=1e-9, newton_tol=1e-10)


@pytest.fixture(scope="module")
def knife():
    return jn.Scene(models.get("knife_edge"), "chetaev", initial=models.initial("knife_edge"),
                    t_span=(0, 1.2))


@pytest.fixture(scope="module")
def pendulum():
    """The Cartesian pendulum of unit length (g = 9.81): x^2 + y^2 = 1 held."""
    J = jn.JetSpace("x y")
    (x, y), (xt, yt) = J.q, J.qd
    L = (xt**2 + yt**2) / 2 - sp.Rational(981, 100) * y
    return jn.Scene(jn.System(J, L, [x**2 + y**2 - 1]),
                    initial={"x": 0.6, "y": -0.8, "x_t": 1.0}, t_span=(0, 0.5))


def test_at_the_rows_gives_the_rows(knife):
    tr = knife.run(method="radau")
    assert len(tr) > 10
    assert np.array_equal(tr.at(tr.t).to_numpy(), tr.y)


@pytest.mark.parametrize("newton_tol, agree", [(1e-10, 1e-14), (None, 1e-9)])
def test_at_is_the_runs_t_eval_to_its_newton_tolerance(knife, newton_tol, agree):
    opts = dict(method="radau", rtol=1e-7, atol=1e-9, newton_tol=newton_tol)
    tr = knife.run(**opts)
    tau = np.linspace(0, 1.2, 41)[1:-1]
    own = knife.run(t_eval=tau, **opts).y
    at = tr.at(tau[::-1]).to_numpy()[::-1]           # (any order)
    ref = knife.run(method="dop853", rtol=1e-13, atol=1e-13, t_eval=tau).y
    assert np.max(np.abs(at - own)) <= agree
    err, err_own = np.max(np.abs(at - ref)), np.max(np.abs(own - ref))
    assert 0 < err < 1e-6 and err <= 1.01 * err_own + agree


@settings(max_examples=10)
@given(st.lists(st.floats(0.0, 1.2), min_size=1, max_size=6))
def test_any_times_in_the_span(knife, times):
    tr = knife.run(method="radau", **TIGHT)
    own = knife.run(method="radau", t_eval=sorted(times), **TIGHT).y
    at = tr.at(sorted(times)).to_numpy()
    assert np.max(np.abs(at - own)) <= 1e-13


def test_inside_a_step_the_values_lie_on_the_holonomic_constraint(pendulum):
    opts = dict(method="radau", split="fixed", **TIGHT)
    tr = pendulum.run(**opts)
    tau = np.linspace(0, 0.5, 23)[1:-1]
    at = tr.at(tau)
    own = pendulum.run(t_eval=tau, **opts).y
    ref = pendulum.run(method="dop853", rtol=1e-13, atol=1e-13, split="fixed", t_eval=tau).y
    assert np.max(np.abs(at.to_numpy() - own)) <= 1e-14
    assert np.max(np.abs(at.to_numpy() - ref)) < 1e-7
    assert np.max(np.abs(at["x"] ** 2 + at["y"] ** 2 - 1.0)) < 1e-14


def test_sensitivities_between_the_rows(knife):
    opts = dict(method="radau", sensitivities=True, **TIGHT)
    tr = knife.run(**opts)
    tau = np.linspace(0, 1.2, 11)[1:-1]
    full = evaluate(tr, tau, full=True)
    own = knife.run(t_eval=tau, **opts)
    n = own.y.shape[1]
    assert np.max(np.abs(full[:, :n] - own.y)) <= 1e-14
    assert np.max(np.abs(full[:, n:] - own.sensitivities.reshape(len(tau), -1))) <= 1e-12


def test_a_run_that_changed_split_and_a_pickled_run(knife):
    scene = knife.replace(t_span=(0, 6.0))
    tr = scene.run(method="radau", rtol=1e-8, atol=1e-10)
    assert len(tr.switches) >= 2 and tr.success
    tau = np.linspace(0, 6.0, 61)[1:-1]
    ref = scene.run(method="dop853", rtol=1e-13, atol=1e-13, t_eval=tau).y
    assert np.max(np.abs(tr.at(tau).to_numpy() - ref)) < 1e-6
    one = knife.run(method="radau")
    back = pickle.loads(pickle.dumps(one))
    assert np.array_equal(back.at(tau[:10] / 5).to_numpy(), one.at(tau[:10] / 5).to_numpy())


def test_t_eval_and_final_runs_still_say_what_to_do(knife):
    with pytest.raises(jn.JetnhError, match="must hold every step"):
        knife.run(method="radau", save="final").at([0.5])
    with pytest.raises(jn.JetnhError, match="must hold every step"):
        knife.run(method="radau", t_eval=[0.0, 1.0]).at([0.5])
