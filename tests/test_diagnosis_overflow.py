"""Overflow from extreme parameter values is reported as an overflow at a regular
configuration, naming the parameters, not as a singular configuration (the indicators
have not moved).  Before: "cos(th) = 0.980067 (initially 0.980067) is about to vanish
... the determinant of df/dqdot^alpha vanishes" and "a denominator vanishes"."""

import sys

import numpy as np
import pytest
import sympy as sp

import jetnh as jn
from jetnh.errors import IntegrationError
from jetnh.numeric.methods._common import SINGULAR

PARAMS = {"m": 1.0, "I": 0.5, "a": 0.3, "k": 1.0}


@pytest.fixture(scope="module")
def sleigh():
    """A sleigh-like model with a spring; m and k given at run time."""
    J = jn.JetSpace("x y th")
    (x, y, th), (xt, yt, tht) = J.q, J.qd
    m, I, a, k = sp.symbols("m I a k")
    S = jn.System(J, m * (xt**2 + yt**2) / 2 + I * tht**2 / 2 - k * x**2 / 2,
                  [sp.sin(th) * xt - sp.cos(th) * yt + a * tht], dependent=[y])
    return jn.Scene(S, "chetaev", params=PARAMS, runtime_params=["m", "k"],
                    initial={"x": 0.1, "y": 0, "th": 0.2, "x_t": 1.0, "th_t": 0.5},
                    t_span=(0, 5), cache=False)


def test_regular_parameters_run(sleigh):
    tr = sleigh.run(params=np.array([1.0, 1.0]))
    assert tr.status == 0 and tr.t[-1] == 5.0


@pytest.mark.parametrize("m, k, name", [(1e-300, 1.0, "m = 1e-300"),
                                        (1.0, 1e300, "k = 1e+300")])
def test_overflowing_rhs_is_no_singular_configuration(sleigh, m, k, name):
    """x_tt = -k x / m = -1e299 at cos(th) = 0.98: the first step overflows."""
    with pytest.raises(IntegrationError) as info:
        sleigh.run(params=np.array([m, k]))
    text = str(info.value)
    assert "No singularity indicator explains it" in text
    assert "overflowed" in text and name in text and "nondimensionalise" in text
    assert "about to vanish" not in text and "determinant" not in text
    size = float(text.split("The right-hand side there is ")[1].split(" in size")[0])
    assert 9e298 < size < 1e299          # |x_tt| = k x / (m (1 + ...)) ~ 0.1 / 1e-300


def test_nan_indicator_from_overflow_at_the_start(sleigh):
    """m = 1e300: the reduced mass determinant has m^2 = inf, inf - inf = NaN, while
    cos(th) = 0.98: an overflow, not a vanishing denominator."""
    tr = sleigh.run(params=np.array([1e300, 1.0]))
    assert tr.status == SINGULAR and tr.singularity["kind"] == "nonfinite"
    assert np.isnan(tr.singularity["initial"])
    reason = tr.stop_reason
    assert "no denominator is shown to vanish" in reason and "m = 1e+300" in reason
    assert "A denominator (or a square-root argument)" not in reason
    assert "singular configuration" not in reason


# ---------------------------------------------------------------------- energy overflow
@pytest.fixture(scope="module")
def exp_velocity():
    """L = x_t^2/2 + exp(x_t): x_tt = 0 (x_t constant), E = x_t^2/2 + (x_t - 1) exp(x_t),
    which is inf - inf = NaN at x_t = 1000 while the motion is exact."""
    J = jn.JetSpace("x")
    (x,), (xt,) = J.q, J.qd
    return jn.Scene(jn.System(J, xt**2 / 2 + sp.exp(xt), []), "chetaev",
                    initial={"x": 0.0, "x_t": 1.0}, t_span=(0, 1), cache=False)


def test_an_energy_that_overflows_is_not_printed_as_a_drift(exp_velocity):
    tr = exp_velocity.run(y0=np.array([0.0, 1000.0]))
    d = tr.diagnostics
    assert d.success and tr["x"][-1] == pytest.approx(1000.0, rel=1e-12)
    assert np.isnan(d.energy_initial) and np.isnan(d.energy_drift)
    text = str(d)
    assert "energy not evaluated: it is nan at the start" in text
    assert "drift nan" not in text and "relative nan" not in text
    regular = str(exp_velocity.run().diagnostics)         # E = 1/2 at x_t = 1
    assert "energy 0.5, drift" in regular and "not evaluated" not in regular


def test_energy_text():
    from jetnh.numeric.trajectory import _energy_text as energy_text

    assert energy_text(2.0, 1e-12, 5e-13) == "energy 2, drift 1.000e-12 (relative 5.000e-13)"
    assert energy_text(2.0, np.nan, np.nan).startswith(
        "energy 2, drift not evaluated: the energy became NaN or infinite on the way")
    assert energy_text(np.inf, np.nan, np.nan).startswith(
        "energy not evaluated: it is inf at the start")


def test_a_sweep_keeps_nan_energy_drift_for_an_overflowing_energy(exp_velocity):
    """The sweep's documented meaning: NaN energy_drift of a successful row is an energy
    that could not be evaluated, the row's values stay valid."""
    df = jn.sweep(exp_velocity, {"x_t": [1.0, 1000.0]})
    assert df["success"].tolist() == [True, True]
    assert df["x"].tolist() == pytest.approx([1.0, 1000.0], rel=1e-12)
    assert df["energy_drift"][0] < 1e-12 and np.isnan(df["energy_drift"][1])
    assert "is no drift: the energy could\n  not be evaluated" in sys.modules["jetnh.sweep"].__doc__


def test_linearize_at_a_degenerate_parameter_names_the_parameters(sleigh):
    """m = 0 makes L degenerate (the Scene says so for the same values); linearize
    named only the point and the split."""
    with pytest.raises(jn.JetnhError, match="parameter values that make them degenerate"):
        jn.linearize(sleigh.system, at={"x": 0.0, "th": 0.0, "x_t": 1.0, "th_t": 0.0},
                     params={**PARAMS, "m": 0.0})
