"""jetnh.numeric.linearize: each eigenvalue is judged zero, or on the imaginary axis,
against its own error bound, so that a stiff mode elsewhere in A does not hide an
unstable one.  Closed forms (a saddle next to a stiff spring: eigenvalues +-sqrt(c),
+-i sqrt(k)), a run of the same system as the second route, and a property test: the
verdict of a decoupled pair next to a damped stiff spring (stiffness 1 to 1e10) is the
verdict of the pair alone, and its closed form."""

from functools import lru_cache

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings, strategies as st

import jetnh as jn
from jetnh import models

REST = {"x": 0.0, "y": 0.0, "x_t": 0.0, "y_t": 0.0}


@lru_cache(maxsize=None)
def _pair(stiff: bool):
    """y'' = -a y - b y' (the pair), with a spring x'' = -k x - d x' beside it (stiff)."""
    k, d, a, b = sp.symbols("k d a b")
    if stiff:
        J = jn.JetSpace("x y")
        (x, y), (xt, yt) = J.q, J.qd
        S = jn.System(J, (xt**2 + yt**2) / 2 - k * x**2 / 2 - a * y**2 / 2,
                      forces={x: -d * xt, y: -b * yt})
        return jn.linearize(S, at=REST, params={"k": 1.0, "d": 1.0, "a": 1.0, "b": 1.0})
    J = jn.JetSpace("y")
    (y,), (yt,) = J.q, J.qd
    S = jn.System(J, yt**2 / 2 - a * y**2 / 2, forces={y: -b * yt})
    return jn.linearize(S, at={"y": 0.0, "y_t": 0.0}, params={"a": 1.0, "b": 1.0})


def _expected(a: float, b: float) -> str:
    """The verdict of y'' + b y' + a y = 0 (roots of l^2 + b l + a)."""
    if a < 0 or b < 0:
        return "unstable"
    return "asymptotically stable" if a > 0 and b > 0 else "marginal"


@pytest.fixture(scope="module")
def saddle():
    J = jn.JetSpace("x y")
    (x, y), (xt, yt) = J.q, J.qd
    k, c = sp.symbols("k c")
    S = jn.System(J, (xt**2 + yt**2) / 2 - k * x**2 / 2 + c * y**2 / 2)
    return S, jn.linearize(S, at=REST, params={"k": 1.0, "c": 0.25})


@pytest.mark.parametrize("k, c", [(1.0, 0.25), (1e6, 0.25), (1e8, 2500.0), (1e10, 0.01)])
def test_a_stiff_spring_hides_no_saddle(saddle, k, c):
    """Eigenvalues +-sqrt(c) and +-i sqrt(k): unstable with margin sqrt(c) at every
    stiffness (a flat 1e-6 |A| counted sqrt(c) as zero once k >= 1e6)."""
    _, lin = saddle
    lin = lin.replace(params={"k": k, "c": c})
    w = np.sqrt(c)
    expected = np.array([w, -1j * np.sqrt(k), 1j * np.sqrt(k), -w])
    assert np.allclose(lin.eigenvalues, expected, rtol=1e-12, atol=1e-9 * w)
    assert lin.verdict == "unstable" and lin.stable is False
    assert lin.margin == pytest.approx(w, rel=1e-5)     # less its error bound


def test_the_saddle_grows_in_a_run_and_along_c(saddle):
    """Second route: the run from y = 1e-6 (x = 0) follows 1e-6 cosh(sqrt(c) t) with
    k = 1e6; and ``along`` finds the crossing at c = 0 next to the stiff spring."""
    S, lin = saddle
    tr = jn.Scene(S, "chetaev", params={"k": 1e6, "c": 0.25},
                  initial={**REST, "y": 1e-6}, t_span=(0.0, 20.0)).run(method="dop853")
    assert tr["y"][-1] == pytest.approx(1e-6 * np.cosh(0.5 * 20.0), rel=1e-6)
    scan = lin.replace(params={"k": 1e6}).along("c", np.linspace(-1.0, 1.0, 8))
    assert len(scan.crossings) == 1 and abs(scan.crossings[0]) < 1e-12
    assert list(scan.stable) == [v <= 0 for v in scan.values]


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.floats(0.0, 10.0), st.floats(0.05, 1.0),
       st.sampled_from(["stable", "saddle", "antidamped", "oscillator", "free", "drift",
                        "critical", "anticritical"]),
       st.floats(-2.0, 2.0), st.floats(-2.0, 1.0))
def test_a_stiff_mode_changes_no_verdict(log_k, zeta, kind, log_a, log_b):
    """A damped spring of stiffness k = 1 ... 1e10 beside a decoupled pair: the verdict
    and the sign of the margin are those of the pair alone and of its closed form
    (stable, saddle, negative damping, undamped oscillator, free particle: a Jordan
    block of 0, damped drift, critically damped: a Jordan block of -b/2)."""
    k = 10.0**log_k
    a, b = 10.0**log_a, 10.0**log_b
    a, b = {"stable": (a, b), "saddle": (-a, b), "antidamped": (a, -b),
            "oscillator": (a, 0.0), "free": (0.0, 0.0), "drift": (0.0, b),
            "critical": (b * b / 4, b), "anticritical": (b * b / 4, -b)}[kind]
    both = _pair(True).replace(params={"k": k, "d": 2 * zeta * np.sqrt(k), "a": a, "b": b})
    alone = _pair(False).replace(params={"a": a, "b": b})
    assert both.verdict == alone.verdict == _expected(a, b)
    assert both.stable == alone.stable == (_expected(a, b) != "unstable")


def test_clusters_of_zero_eigenvalues_stay_zero():
    """Families of steady motions: the particle chain at rest (a defective zero
    eigenvalue that rounding splits into +-1e-8, beside semisimple ones and +-i, +-i
    sqrt(3)) and the sleigh running straight (0, 0 and a negative one) stay marginal."""
    chain = models.get("particle_chain", N=3)
    at = {q.name: 0.0 for q in chain.J.q}
    at.update({v.name: 0.0 for v in chain.independent_velocities})
    lin = jn.linearize(chain, at=at)
    ev = lin.eigenvalues
    small = np.abs(ev) < 1e-6
    assert np.sum(small) == 8 and np.any(small & (np.abs(ev) > 1e-12))  # split by rounding
    assert np.allclose(np.sort(np.abs(ev[np.abs(ev) > 1e-6].imag)), [1, 1, 3**0.5, 3**0.5])
    assert lin.verdict == "marginal" and lin.stable and lin.margin <= 0
    sleigh = jn.linearize(models.get("chaplygin_sleigh"),
                          at={"theta": 0.3, "x_t": np.cos(0.3), "theta_t": 0.0})
    assert sleigh.verdict == "marginal" and sleigh.stable


@pytest.mark.parametrize("k", [1.0, 1e6, 1e10])
def test_crossings_beside_a_stiff_mode(k):
    """The pair y'' + b y' + a y = 0 beside a damped spring of stiffness k: stable for
    a, b > 0; along b (a complex pair crossing) and along a (a real eigenvalue through
    0) the crossing is at 0 to 1e-12, as without the spring."""
    lin = _pair(True).replace(params={"k": k, "d": 0.1 * np.sqrt(k), "a": 1.0, "b": 0.3})
    for name in ("b", "a"):
        scan = lin.along(name, np.linspace(-0.35, 0.45, 9))
        assert len(scan.crossings) == 1 and abs(scan.crossings[0]) < 1e-12
        assert list(scan.stable) == [v > 0 for v in scan.values]
