"""jetnh.numeric.linearize and jetnh.mechanics.holonomic give the same verdicts in every
system of units and wherever the origin of a coordinate is: "on g = 0" is judged against
the size of the constraint's terms, "steady" against the size of each rate's terms
(plus the rounding of the point), never against the number 1 or against |x| itself.
Closed forms: the pendulum th'' = -G sin th (steady only at th = k pi, eigenvalues
+-i sqrt(G), +-sqrt(G)), the Cartesian pendulum x^2 + y^2 = l^2 (+-i sqrt(G/l)), a spring
x'' = -k (x - c) (- G), V = G sin(x/a)/(x/a) at its removable 0/0 (+-sqrt(G/3)/a); and
the refusals at the poles of polar coordinates and Euler angles, where the limit of the
equations depends on the direction of approach."""

import warnings
from functools import lru_cache

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st

import jetnh as jn
from jetnh import models
from jetnh.mechanics import holonomic

exponents = st.integers(min_value=-8, max_value=8)


@lru_cache(maxsize=None)
def _pendulum():
    J = jn.JetSpace("th")
    (th,), (tht,) = J.q, J.qd
    return jn.System(J, tht**2 / 2 + sp.Symbol("G") * sp.cos(th))


@lru_cache(maxsize=None)
def _cartesian():
    J = jn.JetSpace("x y")
    (x, y), (xt, yt) = J.q, J.qd
    G, l = sp.symbols("G l")
    return jn.System(J, (xt**2 + yt**2) / 2 - G * y, [x**2 + y**2 - l**2], dependent=[y])


@lru_cache(maxsize=None)
def _spring():
    """x'' = -K (x - c) - G, and an independent pendulum th'' = -g sin th."""
    J = jn.JetSpace("x th")
    (x, th), (xt, tht) = J.q, J.qd
    K, c, G, g = sp.symbols("K c G g")
    return jn.System(J, (xt**2 + tht**2) / 2 - K * (x - c)**2 / 2 - G * x + g * sp.cos(th))


# ------------------------------------------------------------------ on g = 0 (holonomic)
@settings(max_examples=12)
@given(e=exponents, frac=st.floats(0.1, 0.99))
def test_off_the_circle_is_refused_in_every_unit_of_length(e, frac):
    """A point at a fraction of the pendulum's length is off g = 0 whatever the unit:
    refused by linearize, Scene and holonomic.check; the point on it gives +-i sqrt(G/l)."""
    S, lv = _cartesian(), 10.0 ** e
    params = {"G": 9.81, "l": lv}
    lin = jn.linearize(S, at={"x": 0.0, "y": -lv, "x_t": 0.0}, params=params)
    np.testing.assert_allclose(np.sort(lin.eigenvalues.imag), [-np.sqrt(9.81 / lv),
                                                               np.sqrt(9.81 / lv)], rtol=1e-9)
    assert lin.verdict == "marginal"
    y0 = -frac * lv
    with pytest.raises(jn.ConstraintError, match="off the holonomic constraints"):
        jn.linearize(S, at={"x": 0.0, "y": y0, "x_t": 0.0}, params=params)
    with pytest.raises(jn.ConstraintError, match="off the holonomic constraints"):
        jn.Scene(S, params=params, initial={"x": 0.0, "y": y0, "x_t": 0.0}, t_span=(0, 1))
    with pytest.raises(jn.ConstraintError, match="off the holonomic constraints"):
        holonomic.check(S, {"x": 0.0, "y": y0, **params})
    done, moved = holonomic.check(S, {"x": 0.0, "y": y0, **params}, complete=True)
    assert done[S.J.q[1]] == pytest.approx(-lv, rel=1e-14)


def test_connect_refuses_a_start_off_the_circle_in_micrometres():
    """connect's start (``on_manifold``) is checked the same way: a 10 um pendulum started
    at a tenth of its length is refused."""
    with pytest.raises(jn.ConstraintError, match="off the holonomic constraints"):
        jn.connect(_cartesian(), "chetaev", {"x": 0.0, "y": -1e-6}, {"x": 3e-6}, (0, 1e-3),
                   params={"G": 9.81, "l": 1e-5})


def test_on_g_is_judged_against_the_terms_not_the_origin():
    """A pivot far from the origin: the terms of g are those of the circle, so a point a
    tenth of the length off is refused; a zero of sin q at the rounded pi is on g = 0
    (its terms are themselves rounding: the rounding of q through dg/dq decides)."""
    J = jn.JetSpace("x y")
    x, y = J.q
    c, l = sp.symbols("c l")
    S = jn.System(J, (J.qd[0]**2 + J.qd[1]**2) / 2, [(x - c)**2 + y**2 - l**2],
                  dependent=[y])
    holonomic.check(S, {"x": 1e6, "y": -1.0, "c": 1e6, "l": 1.0})
    with pytest.raises(jn.ConstraintError):
        holonomic.check(S, {"x": 1e6 + 0.1, "y": -1.0, "c": 1e6, "l": 1.0})
    J1 = jn.JetSpace("q r")
    q, r = J1.q
    S1 = jn.System(J1, (J1.qd[0]**2 + J1.qd[1]**2) / 2, [sp.sin(q) * r], dependent=[q])
    for scale in (1e-9, 1.0, 1e9):
        holonomic.check(S1, {"q": np.pi, "r": scale})
        with pytest.raises(jn.ConstraintError):
            holonomic.check(S1, {"q": np.pi + 1e-6, "r": scale})


# ------------------------------------------------------------------ steady motions
@settings(max_examples=15)
@given(e=exponents, th0=st.floats(0.01, 3.1))
def test_pendulum_verdicts_in_every_unit_of_time(e, th0):
    """G = 9.81 in units whose time unit is 10^e s: th0 off the equilibria is no steady
    motion; th = 0 is marginal (+-i sqrt(G)), th = pi unstable (+-sqrt(G)); steady()
    from th0 finds th = 0 or pi."""
    S, G = _pendulum(), 9.81 * 10.0 ** (2 * e)
    off = jn.linearize(S, at={"th": th0, "th_t": 0.0}, params={"G": G})
    assert not off.steady_motion and off.verdict == "not a steady motion"
    low = jn.linearize(S, at={"th": 0.0, "th_t": 0.0}, params={"G": G})
    assert low.verdict == "marginal"
    np.testing.assert_allclose(np.sort(low.eigenvalues.imag), [-np.sqrt(G), np.sqrt(G)],
                               rtol=1e-12)
    top = jn.linearize(S, at={"th": np.pi, "th_t": 0.0}, params={"G": G})
    assert top.verdict == "unstable"
    np.testing.assert_allclose(np.sort(top.eigenvalues.real), [-np.sqrt(G), np.sqrt(G)],
                               rtol=1e-9)
    found = off.steady(["th"])
    assert found.steady_motion
    assert min(abs(found.at["th"]), abs(abs(found.at["th"]) - np.pi)) < 1e-9
    assert found.verdict == ("marginal" if abs(found.at["th"]) < 1 else "unstable")


@settings(max_examples=12)
@given(e=exponents, c=st.sampled_from([0.0, 1e3, 1e6]), d=st.floats(1e-4, 1e2))
def test_spring_off_equilibrium_wherever_the_origin(e, c, d):
    """x'' = -K (x - c): a point d off the equilibrium is no steady motion, whatever K
    and wherever the origin (c); a pendulum displaced d/100 rad beside a spring at its
    equilibrium far from the origin is none either."""
    S, K = _spring(), 10.0 ** e
    params = {"K": K, "c": c, "G": 0.0, "g": 9.81}
    lin = jn.linearize(S, at={"x": c + d, "th": 0.0, "x_t": 0.0, "th_t": 0.0},
                       params=params)
    assert not lin.steady_motion, lin.rates
    lin = jn.linearize(S, at={"x": c, "th": d / 100, "x_t": 0.0, "th_t": 0.0},
                       params=params)
    assert not lin.steady_motion, lin.rates
    lin = jn.linearize(S, at={"x": c, "th": 0.0, "x_t": 0.0, "th_t": 0.0}, params=params)
    assert lin.verdict == "marginal"


@pytest.mark.parametrize("K", [1e6, 1e12, 1e15])
def test_stiff_spring_at_its_static_equilibrium_is_steady(K):
    """x'' = -K (x - c) - G at x = c - G/K rounded: a steady motion (the rate is the
    rounding of K x), marginal with +-i sqrt(K); steady() keeps it."""
    S = _spring()
    params = {"K": K, "c": 0.1, "G": 9.81, "g": 9.81}
    lin = jn.linearize(S, at={"x": 0.1 - 9.81 / K, "th": 0.0, "x_t": 0.0, "th_t": 0.0},
                       params=params)
    assert lin.steady_motion and lin.verdict == "marginal"
    assert np.max(np.abs(lin.eigenvalues.imag)) == pytest.approx(np.sqrt(K), rel=1e-9)
    found = lin.steady(["x"])
    assert found.verdict == "marginal"
    assert found.at["x"] == pytest.approx(0.1 - 9.81 / K, rel=1e-12)


# ------------------------------------------------------------------ limits at 0/0
@settings(max_examples=10)
@given(e=st.integers(min_value=-6, max_value=3))
def test_removable_limit_in_every_unit_of_length(e):
    """V = G sin(x/a)/(x/a) at x = 0 (0/0 in the rows): the limit +-sqrt(G/3)/a,
    unstable, whatever a."""
    J = jn.JetSpace("x")
    (x,), (xt,) = J.q, J.qd
    G, a = sp.symbols("G a")
    S = _sinc(J, x, xt, G, a)
    av = 10.0 ** e
    lin = jn.linearize(S, at={"x": 0.0, "x_t": 0.0}, params={"G": 1.0, "a": av})
    assert lin.limit and lin.verdict == "unstable"
    np.testing.assert_allclose(np.sort(lin.eigenvalues.real),
                               [-np.sqrt(1 / 3) / av, np.sqrt(1 / 3) / av], rtol=1e-6)


_SINC: dict = {}


def _sinc(J, x, xt, G, a):
    if "S" not in _SINC:
        _SINC["S"] = jn.System(J, xt**2 / 2 - G * sp.sin(x / a) / (x / a))
    return _SINC["S"]


def test_pole_of_polar_coordinates_is_refused():
    """The isotropic oscillator in polar coordinates at r = 0: th_tt = -2 r_t th_t / r has
    a limit that depends on the direction of approach: refused, naming the coordinates."""
    J = jn.JetSpace("r th")
    (r, th), (rt, tht) = J.q, J.qd
    k = sp.Symbol("k")
    S = jn.System(J, (rt**2 + r**2 * tht**2) / 2 - k * r**2 / 2)
    for tv in (0.0, 1.0):
        with pytest.raises(jn.LinearizationError, match="other coordinates"):
            jn.linearize(S, at={"r": 0.0, "th": 0.0, "r_t": 0.0, "th_t": tv},
                         params={"k": 4.0}, drop=None)


def test_heavy_top_at_and_near_its_pole():
    """The heavy top in Euler angles: at theta = 0 (the pole) refused, naming the
    coordinates; at theta = 1e-6 with phi_t = 0 no steady motion (theta'' = Mgl theta /
    I1 there), below and above Maievskii's speed, with a warning: the mass matrix is
    nearly singular beside the pole (scaled condition ~ 1/theta^2)."""
    J = jn.JetSpace("theta phi psi")
    (th, ph, ps), (tht, pht, pst) = J.q, J.qd
    I1, I3, Mgl = sp.symbols("I1 I3 Mgl")
    S = jn.System(J, I1 / 2 * (tht**2 + pht**2 * sp.sin(th)**2)
                  + I3 / 2 * (pst + pht * sp.cos(th))**2 - Mgl * sp.cos(th))
    P = {"I1": 1.0, "I3": 0.5, "Mgl": 1.0}
    for W in (2.0, 8.0):
        at = {"theta": 0.0, "phi": 0, "psi": 0, "theta_t": 0, "phi_t": 0, "psi_t": W}
        with pytest.raises(jn.LinearizationError, match="other coordinates"):
            jn.linearize(S, at=at, params=P)
        with pytest.warns(jn.errors.JetnhWarning, match="mass matrix is nearly singular"):
            lin = jn.linearize(S, at={**at, "theta": 1e-6}, params=P)
        assert lin.verdict == "not a steady motion" and lin.conditioning > 1e11


# ------------------------------------------------------------------ inputs
def test_inert_holonomic_multiplier_needs_no_value():
    """The vakonomic Cartesian pendulum: lambda_y is inert (left out of A) and need not
    be given; the result is the one with it given."""
    S = _cartesian()
    at = {"x": 0.0, "y": -1.0, "x_t": 0.0}
    params = {"G": 9.81, "l": 1.0}
    lin = jn.linearize(S, "vakonomic", at=at, params=params)
    assert lin.inert == ("lambda_y",)
    ref = jn.linearize(S, "vakonomic", at={**at, "lambda_y": 0.7}, params=params)
    np.testing.assert_array_equal(lin.A, ref.A)
    np.testing.assert_allclose(np.sort(lin.eigenvalues.imag), [-np.sqrt(9.81),
                                                               np.sqrt(9.81)], rtol=1e-12)


@pytest.mark.parametrize("R", [1.0, 1e-9, 1e-12])
def test_inconsistent_dependent_velocity_is_refused_in_small_units(R):
    """The rolling disk with radius R: x_t = 5 R where the constraint gives R is refused
    whatever R; x_t = R is accepted."""
    S = models.rolling_disk()
    at = {"x": 0, "y": 0, "phi": 0, "psi": 0, "phi_t": 1.0, "psi_t": 0.0}
    with pytest.raises(jn.ConstraintError, match="off the constraints"):
        jn.linearize(S, at={**at, "x_t": 5 * R}, params={"R": R}, drop=None)
    lin = jn.linearize(S, at={**at, "x_t": R}, params={"R": R}, drop=None)
    assert lin.at["x_t"] == pytest.approx(R, rel=1e-12)


# ------------------------------------------------------------------ mass-matrix conditioning
@lru_cache(maxsize=None)
def _coupled():
    """Two unit oscillators with kinetic energy (x_t^2 + 2 (1 - e) s x_t y_t + s^2 y_t^2)/2
    (y in units of s): M = [[1, (1 - e) s], [(1 - e) s, s^2]], frequencies^2 k/e and
    k/(2 - e); the mass matrix scaled to a unit diagonal has condition (2 - e)/e."""
    J = jn.JetSpace("x y")
    (x, y), (xt, yt) = J.q, J.qd
    e, k, s = sp.symbols("epsilon k s")
    return jn.System(J, (xt**2 + 2 * (1 - e) * s * xt * yt + s**2 * yt**2) / 2
                     - k * (x**2 + s**2 * y**2) / 2)


@pytest.mark.parametrize("e", [0.5, 1e-6, 1e-9, 1e-12])
@pytest.mark.parametrize("s", [1e-3, 1.0, 1e6])
def test_nearly_singular_mass_matrix_warns_in_every_unit(e, s):
    """A nearly singular mass matrix: ``conditioning`` is (2 - e)/e in every unit of y,
    linearize warns (a JetnhWarning naming the fix) exactly when it exceeds
    ``CONDITION`` = 1e-8/eps, and the eigenvalues, +-i sqrt(k/e) and +-i
    sqrt(k/(2 - e)), are within their rounding cond * eps of the closed form."""
    from jetnh.errors import JetnhWarning
    from jetnh.numeric.linearize import CONDITION

    cond = (2 - e) / e
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        lin = jn.linearize(_coupled(), at={"x": 0, "y": 0, "x_t": 0, "y_t": 0},
                           params={"epsilon": e, "k": 1.0, "s": s})
    assert lin.conditioning == pytest.approx(cond, rel=1e-4)
    ours = [w for w in caught if issubclass(w.category, JetnhWarning)]
    assert len(ours) == (cond > CONDITION)
    if ours:
        assert "mass matrix is nearly singular" in str(ours[0].message)
        assert "coordinates in which the mass matrix is regular" in str(ours[0].message)
    want = np.sort(np.sqrt([1 / e, 1 / (2 - e)]))
    got = np.sort(np.abs(lin.eigenvalues.imag))[::2]
    np.testing.assert_allclose(got, want, rtol=max(1e-12, 100 * cond * np.finfo(float).eps))


def test_small_inertia_is_no_ill_conditioning():
    """The knife edge with an inertia 1e-12 of its mass: the reduced mass matrix
    diag(m, I) is badly scaled, not ill-conditioned: conditioning 1 and no warning (a
    2-norm condition number would be 1e12, a unit of length away from 1)."""
    S = models.knife_edge()
    at = {"x": 0, "y": 0, "phi": 0.3, "x_t": 1.0, "phi_t": 0.0}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for inertia in (0.5, 1e-12):
            lin = jn.linearize(S, at=at, params={"I": inertia})
            assert lin.conditioning == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("av", [1e-3, 1.0, 1e3])
def test_removable_limit_beside_an_offset_cyclic_coordinate(av):
    """The sinc beside a free coordinate y kept at 0, 1e-3, 1, 1e5, 1e8 (in no equation):
    the limit +-sqrt(G/3)/a and "unstable" at every y.  The steps were one scalar, the
    largest |y|: at y = 1e-3, a = 1e3 every digit was lost and zeros agreed ("marginal"),
    at large y no step settled (refused)."""
    J = jn.JetSpace("x y")
    (x, y), (xt, yt) = J.q, J.qd
    G, a = sp.symbols("G a")
    if "Sy" not in _SINC:
        _SINC["Sy"] = jn.System(J, xt**2 / 2 + yt**2 / 2 - G * sp.sin(x / a) / (x / a))
    want = np.sqrt(1 / 3) / av
    for yv in (0.0, 1e-3, 1.0, 1e5, 1e8):
        lin = jn.linearize(_SINC["Sy"], at={"x": 0.0, "y": yv, "x_t": 0.0, "y_t": 0.0},
                           params={"G": 1.0, "a": av}, drop=None)
        assert lin.limit and lin.verdict == "unstable", yv
        re = np.sort(lin.eigenvalues.real)
        np.testing.assert_allclose(re[[0, -1]], [-want, want], rtol=1e-6)
        np.testing.assert_allclose(re[1:-1], 0.0, atol=1e-9 * want)


def test_removable_limit_beside_a_well_conditioned_entry():
    """The sinc coupled to z by z x (x'' gets + z, z'' = x): the 0/0 entry dx''/dx is
    judged on its own, not beside the entry 1 of dx''/dz in its row (that row settled
    on the lost value 2.6e-10 / (3 a^2) at a = 1e-3, z = 0, when rows were judged whole)."""
    J = jn.JetSpace("x z")
    (x, z), (xt, zt) = J.q, J.qd
    G, a = sp.symbols("G a")
    S = jn.System(J, xt**2 / 2 + zt**2 / 2 - G * sp.sin(x / a) / (x / a) + z * x)
    for av in (1e-3, 1.0, 1e3):
        for zv in (0.0, 1e-3, 1e6):
            lin = jn.linearize(S, at={"x": 0.0, "z": zv, "x_t": 0.0, "z_t": 0.0},
                               params={"G": 1.0, "a": av}, drop=None)
            i, j = lin.state_names.index("x_t"), lin.state_names.index("x")
            assert lin.limit
            assert lin.A[i, j] == pytest.approx(1 / (3 * av**2), rel=1e-6), (av, zv)
            assert lin.A[i, lin.state_names.index("z")] == pytest.approx(1.0, rel=1e-9)


def test_removable_limit_away_from_the_origin():
    """The sinc of (x - c)/a at x = c: the 0/0 is at c, whose size is no scale of the
    steps.  At a = 1e3, c = 1e-3 or 1 the steps h |x| lost every digit and zeros agreed
    ("marginal", eigenvalue 0); now +-sqrt(G/3)/a, "unstable"."""
    J = jn.JetSpace("x")
    (x,), (xt,) = J.q, J.qd
    G, a, c = sp.symbols("G a c")
    S = jn.System(J, xt**2 / 2 - G * sp.sin((x - c) / a) / ((x - c) / a))
    for av, cv in ((1e3, 1e-3), (1e3, 1.0), (1e3, 1e4), (1.0, 1e-3), (1e-3, 1e3)):
        lin = jn.linearize(S, at={"x": cv, "x_t": 0.0}, params={"G": 1.0, "a": av, "c": cv})
        assert lin.limit and lin.verdict == "unstable", (av, cv)
        want = np.sqrt(1 / 3) / av
        np.testing.assert_allclose(np.sort(lin.eigenvalues.real), [-want, want], rtol=1e-6)
