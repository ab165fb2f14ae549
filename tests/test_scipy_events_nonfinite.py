"""scipy's methods as the compiled ones on events and non-finite values: an event root
exactly on a step's end is one root (scipy's own rule, g_old <= 0 <= g_new, finds it in
both steps next to it; ``terminal=2`` then stopped at the one root); an event that is
not finite at the start gets the compiled methods' warning; a right-hand side that
becomes NaN next to a singular configuration is a singular stop (LSODA), and a NaN in
Radau's or BDF's Jacobian of finite differences a clear IntegrationError, not scipy's
bare ValueError."""

import warnings

import numpy as np
import pytest
import sympy as sp

import jetnh as jn
from jetnh.errors import IntegrationError, JetnhWarning

J = jn.JetSpace("x")
(X,), (XT,) = J.q, J.qd
OSC = jn.Scene(jn.System(J, XT**2 / 2 - X**2 / 2), initial={"x": 1.0, "x_t": 0.0},
               t_span=(0.0, 3.0))
#: x_t grows past x = 2, where sqrt(2 - x) in the force is NaN (indicator x - 2)
PAST = jn.Scene(jn.System(J, XT**2 / 2 - sp.Rational(1, 1000) * sp.sqrt(2 - X)),
                initial={"x": 0.0, "x_t": 1.0}, t_span=(0.0, 3.0))


@pytest.mark.parametrize("method", ["scipy-RK45", "scipy-DOP853", "scipy-Radau", "dop853"])
@pytest.mark.parametrize("step", [3, 5])
def test_a_root_on_a_step_end_is_one_root(method, step):
    tk = float(OSC.run(method=method).t[step])       # a step's end: the same steps below
    T = J.t
    tr = OSC.run(method=method, events=[T - tk, tk - T, jn.Event(T - tk, direction=1),
                                        jn.Event(T - tk, terminal=2)])
    assert [list(e) for e in tr.t_events] == [[tk]] * 4
    assert [len(e) for e in tr.y_events] == [1] * 4
    assert tr.status == 0 and tr.t[-1] == 3.0 and tr.diagnostics.events == {
        name: 1 for name in tr.event_names}
    once = OSC.run(method=method, events=[jn.Event(T - tk, terminal=1)])
    assert once.status == jn.numeric.EVENT and once.t[-1] == tk


@pytest.mark.parametrize("method", ["scipy-RK45", "dop853"])
def test_an_event_not_finite_at_the_start_is_said(method):
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        tr = OSC.run(method=method, events=[sp.sqrt(X - 2)])
    said = [str(w.message) for w in seen if issubclass(w.category, JetnhWarning)]
    assert len(said) == 1 and "'sqrt(x - 2)' are NaN or infinite at the initial state" in said[0]
    assert [len(e) for e in tr.t_events] == [0]


@pytest.mark.parametrize("method", ["scipy-LSODA", "scipy-RK45", "dop853"])
def test_a_nan_next_to_a_singular_configuration_is_a_singular_stop(method):
    tr = PAST.run(method=method)
    assert tr.status == jn.numeric.SINGULAR and tr.singularity["indicator"] == "x - 2"
    assert np.all(np.isfinite(tr.y)) and 1.99 < tr.t[-1] < 2.0
    assert tr.diagnostics.rows >= len(tr) - 1


@pytest.mark.parametrize("method", ["scipy-Radau", "scipy-BDF"])
def test_a_nan_in_a_jacobian_of_finite_differences_is_an_integration_error(method):
    with pytest.raises(IntegrationError, match=f"{method}: the right-hand side or the state "
                                               "became NaN or infinite"):
        PAST.run(method=method)


@pytest.mark.parametrize("method", ["scipy-RK45", "dop853"])
def test_a_root_at_the_start_counts_as_the_compiled_methods_count_it(method):
    T = J.t
    tr = OSC.run(method=method, events=[T, jn.Event(T, direction=1), jn.Event(-T, direction=-1)])
    assert [list(e) for e in tr.t_events] == [[0.0]] * 3


@pytest.fixture(scope="module")
def root_well():
    """x'' = 1/sqrt(x): the right-hand side is not finite past x = 0, which the run
    reaches from x = 1 at rest... (L = x_t^2/2 - 2 sqrt(x))."""
    J = jn.JetSpace("x")
    (x,), (xt,) = J.q, J.qd
    return jn.Scene(jn.System(J, xt**2 / 2 - 2 * sp.sqrt(x)), initial={"x": 1.0, "x_t": 0.0},
                    t_span=(0, 3))


def test_a_failed_scipy_bdf_run_reports_where_it_stopped(root_well):
    """BDF's finite-difference Jacobian taken across the NaN (an IntegrationError) or its
    step shrunk to nothing in front of it (a failed run; which of the two depends on the
    machine's rounding): either way the failure carries the stop, its time and the
    evaluations made, as every other failed run's does."""
    try:
        tr = root_well.run(method="scipy-BDF", singular="ignore")
    except jn.IntegrationError as error:
        stop = error.stop
        assert stop is not None and 0 < stop["t"] < 3 and stop["rhs_evaluations"] > 10
    else:
        assert not tr.success and "step size" in tr.stop_reason
        assert 0 < tr.t[-1] < 3 and tr.diagnostics.rhs_evaluations > 10


def test_a_scipy_run_singular_at_its_start_says_which_rows_it_saved(root_well):
    tr = root_well.run(method="scipy-RK45", t_eval=[1.0, 2.0], y0=[0.0, 0.0])
    assert tr.status != 0 and tr.diagnostics.saved == "t_eval"
    assert root_well.run(method="scipy-RK45", y0=[0.0, 0.0]).diagnostics.saved == "steps"
