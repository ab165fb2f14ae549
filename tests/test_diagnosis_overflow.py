"""Overflow from extreme parameter values is reported as an overflow at a regular
configuration, naming the parameters, not as a singular configuration (the indicators
have not moved).  Before: "cos(th) = 0.980067 (initially 0.980067) is about to vanish
... the determinant of df/dqdot^alpha vanishes" and "a denominator vanishes"."""

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
    assert tr.status == SINGULAR and tr.singularity["kind"] == "overflow"
    assert np.isnan(tr.singularity["initial"])
    reason = tr.stop_reason
    assert "no denominator is shown to vanish" in reason and "m = 1e+300" in reason
    assert "A denominator (or a square-root argument)" not in reason
    assert "singular configuration" not in reason
