"""jetnh.numeric.linearize's steady test and mass-matrix conditioning give verdicts that
do not depend on how the equations are written or on the units: a spring
x'' = -k (x - c) written factored or expanded (-k x + k c) far from the origin; rows
with exp(g t) exp(-g t) that also depend on t, past g t ~ 710; given dependent
velocities in micro and mega units; indefinite kinetic energies, whose scaled mass
matrix has eigenvalues of both signs (closed forms)."""

import warnings
from functools import lru_cache

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st

import jetnh as jn
from jetnh.errors import JetnhWarning, LinearizationError
from jetnh.numeric.linearize import NOT_STEADY, TIME_DEPENDENT

k, c, g, b = sp.symbols("k c g b")


@lru_cache(maxsize=None)
def _spring(form: str):
    """x'' = -k (x - c), its potential written three ways (the rows differ in form)."""
    J = jn.JetSpace("x")
    (x,), (xt,) = J.q, J.qd
    V = {"factored": k * (x - c)**2 / 2,
         "expanded": k * x**2 / 2 - k * c * x,
         "polynomial": k * (x**2 - 2 * c * x + c**2) / 2}[form]
    return jn.System(J, xt**2 / 2 - V)


FORMS = ("factored", "expanded", "polynomial")


@settings(max_examples=30, deadline=None)
@given(c_exp=st.integers(-6, 9), c_sign=st.sampled_from([-1.0, 0.0, 1.0]),
       k_exp=st.integers(-6, 6), s_exp=st.integers(-6, 6),
       rel=st.floats(1e-9, 1e2), sign=st.sampled_from([-1.0, 1.0]),
       ulps=st.integers(0, 4))
def test_the_steady_test_does_not_depend_on_the_form(c_exp, c_sign, k_exp, s_exp, rel,
                                                     sign, ulps):
    """A point off the spring's equilibrium by at least 1e-9 of the larger of |c| and
    a scale s is no steady motion in every form (c = 1e6, 0.005 off was "marginal"
    expanded); the equilibrium, and points a few ulps of c from it (the rounding of x), are
    steady and marginal (+-i sqrt(k)) in every form."""
    cv, kv, s = c_sign * 10.0 ** c_exp, 10.0 ** k_exp, 10.0 ** s_exp
    off = sign * rel * max(abs(cv), s)
    near = cv
    for _ in range(ulps if cv else 0):      # at c = 0 an ulp of x is no rounding of c
        near = np.nextafter(near, np.inf)
    for form in FORMS:
        S, P = _spring(form), {"k": kv, "c": cv}
        far = jn.linearize(S, at={"x": cv + off, "x_t": 0.0}, params=P)
        assert far.verdict == NOT_STEADY, (form, far.rates)
        at = jn.linearize(S, at={"x": near, "x_t": 0.0}, params=P)
        assert at.verdict == "marginal", (form, at.rates)
        np.testing.assert_allclose(np.abs(at.eigenvalues.imag), np.sqrt(kv), rtol=1e-12)


def test_the_reviewed_point_far_from_the_origin():
    """The reviewer's case: c = 1e6, k = 1, 0.005 off is no steady motion however the
    row is written, and steady() finds x = c in each."""
    for form in FORMS:
        lin = jn.linearize(_spring(form), at={"x": 1e6 + 0.005, "x_t": 0.0},
                           params={"k": 1.0, "c": 1e6})
        assert lin.verdict == NOT_STEADY
        assert lin.steady(["x"]).at["x"] == pytest.approx(1e6, rel=1e-15)


def test_a_parameter_at_a_rounded_zero_of_its_row():
    """x'' = -x + G sin(a) with a = pi rounded: x = 0 is steady (the rate G sin(a) is
    the rounding of a through the row), and x = 1e-9 G is not, in every unit of G."""
    J = jn.JetSpace("x")
    (x,), (xt,) = J.q, J.qd
    G, a = sp.symbols("G a")
    S = jn.System(J, xt**2 / 2 - x**2 / 2 + G * sp.sin(a) * x)
    for Gv in (1e-6, 1.0, 1e6):
        P = {"G": Gv, "a": np.pi}
        assert jn.linearize(S, at={"x": 0.0, "x_t": 0.0}, params=P).verdict == "marginal"
        off = jn.linearize(S, at={"x": 1e-9 * Gv, "x_t": 0.0}, params=P)
        assert off.verdict == NOT_STEADY


def test_a_parameter_at_the_edge_of_its_domain_keeps_the_others_rounding():
    """x'' = -x + G sin(a) - sqrt(1 - e) x at x = 0, a = pi rounded: e = 1 (e (1 + NUDGE)
    makes sqrt(1 - e) undefined) leaves a's rounding in the allowance, so x = 0 is
    steady at e = 1 as at e = 0.5 (was "not a steady motion": one undefined difference
    zeroed the whole row)."""
    J = jn.JetSpace("x")
    (x,), (xt,) = J.q, J.qd
    G, a, e = sp.symbols("G a e")
    S = jn.System(J, xt**2 / 2 - x**2 / 2 + G * sp.sin(a) * x - sp.sqrt(1 - e) * x**2 / 2)
    for ev in (0.5, 1.0):
        P = {"G": 1.0, "a": np.pi, "e": ev}
        assert jn.linearize(S, at={"x": 0.0, "x_t": 0.0}, params=P).verdict == "marginal"
        assert jn.linearize(S, at={"x": 1e-9, "x_t": 0.0}, params=P).verdict == NOT_STEADY


# ---------------------------------------------------------------------- exp(g t) and t
@lru_cache(maxsize=None)
def _modulated():
    """e^(g t) (x_t^2/2 - (1 + b cos t) x^2/2): x'' = -g x' - (1 + b cos t) x, its rows
    carry exp(g t) exp(-g t) and depend on t."""
    J = jn.JetSpace("x")
    (x,), (xt,) = J.q, J.qd
    return jn.System(J, sp.exp(g * J.t) * (xt**2 / 2 - (1 + b * sp.cos(J.t)) * x**2 / 2))


@pytest.mark.parametrize("t", [0.0, 30.0, 60.0])
def test_rows_that_cancel_exp_factors_and_depend_on_t(t):
    """Where the point's rows are finite, x = 0 is a steady motion whose A changes with
    t (b = 0.1: TIME_DEPENDENT; b = 0: asymptotically stable, eigenvalues of
    [[0, 1], [-1, -g]]) even when the test's later times overflow exp(g t) (was "not a
    steady motion" at t = 60); x = 1 is none."""
    S = _modulated()
    lin = jn.linearize(S, at={"x": 0.0, "x_t": 0.0}, params={"g": 10.0, "b": 0.1}, t=t)
    assert lin.verdict == TIME_DEPENDENT
    want = np.linalg.eigvals(np.array([[0, 1], [-(1 + 0.1 * np.cos(t)), -10.0]]))
    np.testing.assert_allclose(np.sort(lin.eigenvalues.real), np.sort(want.real), rtol=1e-9)
    assert lin.replace(at={"x": 1.0}).verdict == NOT_STEADY
    frozen = lin.replace(params={"b": 0.0})
    assert frozen.verdict == "asymptotically stable"


@pytest.mark.parametrize("t", [71.5, 100.0, 1e4])
def test_rows_that_overflow_at_the_point_are_refused_by_name(t):
    """Past g t ~ 710 the compiled rows overflow: a LinearizationError naming the
    overflow of exp and the fix (an earlier t, or the factor cancelled), not a verdict
    nor a 0/0 blamed on the coordinates."""
    with pytest.raises(LinearizationError, match=r"overflow.*exp\(g\*t\)") as err:
        jn.linearize(_modulated(), at={"x": 0.0, "x_t": 0.0},
                     params={"g": 10.0, "b": 0.1}, t=t)
    assert "singular point of the coordinates" not in str(err.value)


@pytest.mark.parametrize("gv, gt", [(10.0, 625.0), (1e-4, 630.0)])
def test_products_that_overflow_before_exp_are_left_out(gv, gt):
    """b = 0, x = 0 at g t = 625..630 is asymptotically stable (eigenvalues of
    [[0, 1], [-1, -g]]) where enough later times of the test stay finite."""
    lin = jn.linearize(_modulated(), at={"x": 0.0, "x_t": 0.0},
                       params={"g": gv, "b": 0.0}, t=gt / gv)
    assert lin.verdict == "asymptotically stable"
    want = np.linalg.eigvals(np.array([[0, 1], [-1.0, -gv]]))
    np.testing.assert_allclose(np.sort(lin.eigenvalues.real), np.sort(want.real), rtol=1e-9)


@pytest.mark.parametrize("gv, gt, bv", [(1e6, 620.0, 0.0), (10.0, 630.0, 0.1)])
def test_products_that_overflow_at_later_times_are_left_out_by_name(gv, gt, bv):
    """Later times where a product such as g exp(g t) in the Jacobian overflows though
    exp(g t) is a double (g = 1e6 at g t = 696.5; g = 10 at t = 70.78, exp(707.8)) are
    left out, not counted as "not a steady motion" (the verdict was that); with one
    time left the error names the overflow."""
    with pytest.raises(LinearizationError, match=r"overflow at the times.*exp\(g\*t\)"):
        jn.linearize(_modulated(), at={"x": 0.0, "x_t": 0.0},
                     params={"g": gv, "b": bv}, t=gt / gv)


@pytest.mark.parametrize("gv, gt", [(10.0, 707.8), (1e6, 700.0)])
def test_products_that_overflow_at_the_point_are_named(gv, gt):
    """Where a product such as g exp(g t) overflows at the point itself (exp(g t) a
    double), the error names the overflow, not a 0/0 of the coordinates."""
    with pytest.raises(LinearizationError, match=r"overflow.*exp\(g\*t\)") as err:
        jn.linearize(_modulated(), at={"x": 0.0, "x_t": 0.0},
                     params={"g": gv, "b": 0.1}, t=gt / gv)
    assert "singular point of the coordinates" not in str(err.value)


def test_the_overflow_advice_fits_its_argument():
    """exp of a state (exp(x) at x = 800) is told to change the state, not t; exp(g t)
    with g < 0 at t = -100 is told a t of smaller |argument|, not an earlier t."""
    J = jn.JetSpace("x")
    (x,), (xt,) = J.q, J.qd
    with pytest.raises(LinearizationError, match=r"exp\(x\) is exp\(800\)") as err:
        jn.linearize(jn.System(J, xt**2 / 2 - sp.exp(x)), at={"x": 800.0, "x_t": 0.0})
    assert "e^(g t)" not in str(err.value) and "earlier" not in str(err.value)
    with pytest.raises(LinearizationError, match=r"smaller \|argument\|") as err:
        jn.linearize(_modulated(), at={"x": 0.0, "x_t": 0.0},
                     params={"g": -10.0, "b": 0.1}, t=-100.0)
    assert "earlier" not in str(err.value)


# ---------------------------------------------------------------------- units of _split
@pytest.mark.parametrize("unit", [1e-12, 1e-6, 1.0, 1e6])
def test_given_dependent_velocities_are_judged_in_every_unit(unit):
    """The Suslov knife edge (motions that depend on the split) past the edge of its own
    chart (heading pi/2 - 1e-4, y_t = tan(phi) x_t): the given y_t on the constraints
    is linearized in the own split in every unit of length; one 1 % off is refused as
    off the constraints in every unit (in units of 1e-12 it was told it was "on the
    constraints" but past the edge of its chart)."""
    from jetnh import models

    S = models.knife_edge()
    P = {"I": 0.5, "alpha": 0.0, "m": 1.0, "g": 9.81}
    phi = np.pi / 2 - 1e-4
    lams = [m.name for m in jn.mechanics.principles.get("suslov").multiplier_symbols(S)]
    at = {"x": 0.0, "y": 0.0, "phi": phi, "x_t": unit, "phi_t": 0.3,
          **{m: 0.0 for m in lams}}
    lin = jn.linearize(S, "suslov", at={**at, "y_t": np.tan(phi) * unit}, params=P)
    assert lin.at["y_t"] == pytest.approx(np.tan(phi) * unit, rel=1e-12)
    with pytest.raises(jn.ConstraintError, match="off the constraints") as err:
        jn.linearize(S, "suslov", at={**at, "y_t": 1.01 * np.tan(phi) * unit}, params=P)
    assert "on the constraints" not in str(err.value)


# ---------------------------------------------------------------------- conditioning
@lru_cache(maxsize=None)
def _indefinite():
    """Kinetic energy (x_t^2 + 2 a x_t y_t + s y_t^2)/2 with s = +-1 (s = -1: a negative
    block), potential (x^2 + y^2)/2: M = [[1, a], [a, s]]."""
    J = jn.JetSpace("x y")
    (x, y), (xt, yt) = J.q, J.qd
    a, s = sp.symbols("a s")
    return jn.System(J, (xt**2 + 2 * a * xt * yt + s * yt**2) / 2 - (x**2 + y**2) / 2)


@pytest.mark.parametrize("a, s", [(0.0, -1.0), (0.5, -1.0), (3.0, -1.0), (2.0, 1.0),
                                  (1 - 1e-9, 1.0), (0.999999999, -1.0)])
def test_conditioning_of_an_indefinite_kinetic_energy(a, s):
    """``conditioning`` is |lambda|max/|lambda|min of [[1, a], [a, s]] (already of unit
    diagonal) whatever the signs: a negative block or |a| > 1 is no singularity, and
    warns only where that exceeds CONDITION; the squared eigenvalues are those of
    -M^-1 K (K = I), within 100 cond eps."""
    from jetnh.numeric.linearize import CONDITION

    M = np.array([[1.0, a], [a, s]])
    ev = np.abs(np.linalg.eigvalsh(M))
    cond = ev.max() / ev.min()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        lin = jn.linearize(_indefinite(), at={"x": 0, "y": 0, "x_t": 0, "y_t": 0},
                           params={"a": a, "s": s})
    assert lin.conditioning == pytest.approx(cond, rel=1e-6)
    assert len([w for w in caught if issubclass(w.category, JetnhWarning)]) == (
        cond > CONDITION)
    want = np.sort_complex(np.repeat(np.linalg.eigvals(-np.linalg.inv(M)), 2))  # lambda^2
    got = np.sort_complex(lin.eigenvalues**2)
    tol = max(1e-9, 100 * cond * np.finfo(float).eps)
    np.testing.assert_allclose(got, want, rtol=tol, atol=tol * np.abs(want).max())


def test_conditioning_with_a_zero_diagonal():
    """M = [[0, 1], [1, 0]] (T = x_t y_t): perfectly conditioned though its diagonal is
    zero; conditioning 1, no warning (was infinite: "nearly singular")."""
    J = jn.JetSpace("x y")
    (x, y), (xt, yt) = J.q, J.qd
    S = jn.System(J, xt * yt - (x**2 + y**2) / 2)
    with warnings.catch_warnings():
        warnings.simplefilter("error", JetnhWarning)
        lin = jn.linearize(S, at={"x": 0, "y": 0, "x_t": 0, "y_t": 0})
    assert lin.conditioning == pytest.approx(1.0, rel=1e-12)
