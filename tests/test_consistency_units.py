"""Given dependent velocities are judged against the size of the terms that make the
constraints' value (``jetnh.numeric.regular``: ``terms``, ``sizes``, ``agree``,
``on_constraints``), never against the number 1: the same physical point gets the same
verdict in every unit of length and time.  A sleigh-like system with a unit ``u`` of
x, a length ``a`` and a velocity ``v``,

    sin(th) x_t / u - cos(th) y_t + a th_t + v = 0        (y dependent),

at points drawn on the constraints (among them y_t = 0 by cancellation and points past
the edge of the chart near th = pi/2) or a relative 1e-6 .. 1e-2 of the size of the
terms off them, in units scaled by 10^k (k in -12..12) for length, time and x alone."""

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st

import jetnh as jn
from jetnh import models
from jetnh.errors import ConstraintError
from jetnh.numeric import ensemble, regular

J = jn.JetSpace("x y th")
X, Y, TH = J.q
XT, YT, THT = J.qd
u_, a_, v_, m_, I_ = sp.symbols("u a v m I", positive=True)
L = m_ / 2 * (XT**2 / u_**2 + YT**2) + I_ / 2 * THT**2
F = [sp.sin(TH) * XT / u_ - sp.cos(TH) * YT + a_ * THT + v_]
S = jn.System(J, L, F, dependent=[Y])
RUNTIME = ("u", "a", "v")
REFUSED = "inconsistent with the constraints|off the constraints|but the constraints give"


def _point(p, scale, off=0.0):
    """The initial values and parameters of the physical point ``p`` in units scaled
    by ``scale`` = (length, time, x alone) factors, y_t off by ``off`` times the size
    of the terms that make it."""
    th, xt, tht, a, v = p
    cL, cT, cX = scale
    terms = (math.sin(th) * xt, a * tht, v)
    required = sum(terms) / math.cos(th)
    size = sum(map(abs, terms)) / abs(math.cos(th))
    initial = {"x": 0.3 * cL * cX, "y": -0.2 * cL, "th": th, "x_t": xt * cL * cT * cX,
               "th_t": tht * cT, "y_t": (required + off * size) * cL * cT}
    return initial, {"u": cX, "a": a * cL, "v": v * cL * cT, "m": 1.0, "I": 1.0}


_speed = st.one_of(st.just(0.0), st.floats(0.1, 2.0), st.floats(-2.0, -0.1))


@st.composite
def points(draw, moving=False):
    """A physical point (th, x_t, th_t, a, v): th regular or near pi/2 (past the edge
    of the chart), v zero, free or cancelling the other terms (y_t = 0); ``moving``:
    not at rest (a point at rest has no relative offset)."""
    th = draw(st.one_of(st.floats(-1.2, 1.2),
                        st.floats(0.3, 4.0).map(lambda e: math.pi / 2 - 10.0**-e)))
    xt, tht, a = draw(_speed), draw(_speed), draw(st.floats(0.1, 2.0))
    if moving and xt == tht == 0.0:
        xt = 1.0
    v = draw(st.sampled_from(["zero", "free", "cancel"]))
    v = (0.0 if v == "zero" else -(math.sin(th) * xt + a * tht) if v == "cancel"
         else draw(st.floats(-1.0, 1.0)))
    if moving and math.sin(th) * xt == a * tht == 0.0 and v == 0.0:
        v = 0.5
    return th, xt, tht, a, v


_exponent = st.integers(-12, 12)
scales = st.lists(st.tuples(_exponent, _exponent, _exponent).map(
    lambda k: tuple(10.0**e for e in k)), min_size=3, max_size=3).map(
    lambda s: [(1.0, 1.0, 1.0)] + s)
offs = st.tuples(st.floats(-6.0, -2.0), st.sampled_from([-1.0, 1.0])).map(
    lambda e: e[1] * 10.0**e[0])


def verdict(make) -> bool:
    """True if ``make()`` takes the point, False if it refuses it as off the
    constraints (any other error fails the test)."""
    try:
        make()
    except ConstraintError as exc:
        assert any(w in str(exc) for w in REFUSED.split("|")), str(exc)
        return False
    return True


# ---------------------------------------------------------------------- the reproducer
def test_knife_edge_one_percent_off_is_refused_at_every_speed():
    """The knife edge y_t 1 % off x_t tan(phi): refused at 1 and at 1e-8 (where the
    old absolute floor took it and replaced y_t silently) and at 1e8."""
    sys_ = models.get("knife_edge")
    for speed in (1.0, 1e-8, 1e8):
        ini = {"x": 0.0, "y": 0.0, "phi": 0.3, "x_t": speed, "phi_t": speed,
               "y_t": 1.01 * speed * math.tan(0.3)}
        with pytest.raises(ConstraintError, match="inconsistent with the constraints"):
            jn.Scene(sys_, initial=ini)
        jn.Scene(sys_, initial={**ini, "y_t": speed * math.tan(0.3)})
        assert jn.Scene(sys_, initial=ini, project=True).initial["y_t"] == pytest.approx(
            speed * math.tan(0.3), rel=1e-15)


# ---------------------------------------------------------------------- what S is
@given(st.floats(-3.0, 3.0), st.floats(-2.0, 2.0), st.floats(-2.0, 2.0),
       st.floats(-2.0, 2.0), st.floats(0.1, 2.0))
def test_terms_of_affine_constraints_are_phi_one_velocity_at_a_time(th, xt, tht, v, a):
    """Two routes to the terms of phi = Phi qdot + phi0: A_alpha^-1 (A_s qdot^s, b)
    from df/dqdot and f, and phi evaluated with one independent velocity at a time."""
    c, qd = {"x": 0.0, "y": 0.0, "th": th}, {"x_t": xt, "th_t": tht, "y_t": 0.0}
    p = {"u": 1.0, "a": a, "v": v, "m": 1.0, "I": 1.0}
    A, f = regular.at_point(S, 0.0, c, qd, p)
    M = regular.terms(S, A, f, [qd[s.name] for s in J.qd])
    phi0 = regular.phi(S, 0.0, c, {"x_t": 0.0, "th_t": 0.0}, p)["y_t"]
    one = [regular.phi(S, 0.0, c, {"x_t": 0.0, "th_t": 0.0, s: qd[s]}, p)["y_t"] - phi0
           for s in ("x_t", "th_t")]
    assert np.allclose(-M[0], [*one, phi0], rtol=1e-14, atol=1e-14 * np.abs(M).max())
    assert -M.sum() == pytest.approx(regular.phi(S, 0.0, c, qd, p)["y_t"], rel=1e-13,
                                     abs=1e-13 * np.abs(M).sum())


@given(st.floats(0.1, 3.0), st.floats(-0.99, 0.99), st.integers(-12, 12))
def test_size_of_a_constraint_not_affine_in_the_velocities(v, ratio, k):
    """x_t = sqrt(v^2 - y_t^2) (the isokinetic particle): the terms of f's
    linearization, y_t^2 / x_t and v^2 / x_t, so S = (y_t^2 + v^2) / x_t; a given x_t
    1e-6 off (relative to S) is refused and the exact one taken at every speed 10^k."""
    sys_ = models.get("isokinetic_particle")
    c = 10.0**k
    yt = ratio * v * c
    xt = math.sqrt((v * c) ** 2 - yt**2)
    p = {"g": 0.0, "m": 1.0, "v": v * c}
    qd = {"x_t": xt, "y_t": yt}
    A, f = regular.at_point(sys_, 0.0, {"x": 0.0, "y": 0.0}, qd, p)
    size = regular.sizes(sys_, A, f, [xt, yt])[0]
    assert size == pytest.approx((yt**2 + (v * c) ** 2) / xt, rel=1e-12)
    base = {"x": 0.0, "y": 0.0, "y_t": yt}
    assert verdict(lambda: jn.Scene(sys_, params=p, initial={**base, "x_t": xt}))
    assert not verdict(lambda: jn.Scene(sys_, params=p,
                                        initial={**base, "x_t": xt + 1e-6 * size}))


def test_at_rest_the_constraints_value_itself():
    """At rest (every term 0) a given dependent velocity must be the constraints' value
    itself: no absolute floor above the smallest normal float."""
    p = {"u": 1.0, "a": 0.5, "v": 0.0, "m": 1.0, "I": 1.0}
    rest = {"x": 0.0, "y": 0.0, "th": 0.4, "x_t": 0.0, "th_t": 0.0}
    jn.Scene(S, params=p, initial={**rest, "y_t": 0.0})
    for yt in (1e-300, -1e-30):
        with pytest.raises(ConstraintError, match="inconsistent with the constraints"):
            jn.Scene(S, params=p, initial={**rest, "y_t": yt})


# ---------------------------------------------------------------------- every route
@given(points(), scales)
def test_consistent_points_taken_in_every_unit(p, scaled):
    """Scene(initial=), replace(initial=) take a point on the constraints in every
    unit, with y_t given (also where it is 0 by cancellation, and past the edge)."""
    for scale in scaled:
        ini, prm = _point(p, scale)
        assert verdict(lambda: jn.Scene(S, params=prm, initial=ini)), (p, scale)
        scene = jn.Scene(S, params=prm, initial={k: ini[k] for k in ini if k != "y_t"})
        assert verdict(lambda: scene.replace(initial=ini)), (p, scale)


@given(points(moving=True), scales, offs)
def test_points_off_refused_in_every_unit(p, scaled, off):
    """A point whose y_t is off by a relative 1e-6 .. 1e-2 of the size of its terms
    is refused in every unit, by Scene(initial=) and replace(initial=); with
    project=True it is taken and y_t replaced by the constraints' value."""
    for scale in scaled:
        ini, prm = _point(p, scale, off)
        assert not verdict(lambda: jn.Scene(S, params=prm, initial=ini)), (p, scale, off)
        scene = jn.Scene(S, params=prm, initial={k: ini[k] for k in ini if k != "y_t"})
        assert not verdict(lambda: scene.replace(initial=ini)), (p, scale, off)


@pytest.fixture(scope="module")
def compiled():
    """One scene with u, a, v read at run time: its kernels compiled once."""
    ini, prm = _point((0.4, 0.7, -0.3, 0.5, -0.1), (1.0, 1.0, 1.0))
    return jn.Scene(S, params=prm, initial=ini, runtime_params=RUNTIME, t_span=(0.0, 1e-9))


@given(points(moving=True), scales, offs)
def test_run_y0_and_ensembles_in_every_unit(compiled, p, scaled, off):
    """run(y0=...) and an ensemble's columns (every scale a run) take the point on the
    constraints and refuse it off them, in every unit; its rows (no y_t) take it.  (A
    run lasts the same 1e-9 in every unit of time.)"""
    for scale in scaled:
        for bad in (0.0, off):
            ini, prm = _point(p, scale, bad)
            run = {k: prm[k] for k in RUNTIME}
            ok = verdict(lambda: compiled.run(y0=ini, params=run,
                                              t_span=(0.0, 1e-9 / scale[1])))
            assert ok == (bad == 0.0), (p, scale, bad)
    for bad in (0.0, off):
        cols = [_point(p, scale, bad) for scale in scaled]
        initial = {k: np.array([c[0][k] for c in cols]) for k in cols[0][0]}
        params = {k: np.array([c[1][k] for c in cols]) for k in RUNTIME}
        ok = verdict(lambda: ensemble.resolve(compiled, initial, params))
        assert ok == (bad == 0.0), (p, bad)
    rows = np.array([[c[0][k] for k in compiled.state_names] for c in cols])
    ensemble.resolve(compiled, rows, params)


@given(points(moving=True), st.tuples(_exponent, _exponent, _exponent), offs)
def test_linearize_in_every_unit(p, k, off):
    """linearize(at=) takes the point on the constraints and refuses it off them, in
    every unit (past the edge of the chart too: the chart's measure is not unit-free,
    so a scaled point may be judged on f = 0 itself, ``on_constraints``)."""
    for scale in [(1.0, 1.0, 1.0), tuple(10.0**e for e in k)]:
        for bad in (0.0, off):
            ini, prm = _point(p, scale, bad)
            ok = verdict(lambda: jn.linearize(S, at=ini, params=prm))
            assert ok == (bad == 0.0), (p, scale, bad)


def test_at_rest_a_large_factor_is_no_rounding():
    """x_t = 0 exactly at x = 1e-160 (y_t = (y / x) x_t): the split is determined there
    (y_t = 0), however large y / x; an input exactly 0 has no rounding unit to move it."""
    own = models.get("radial_line")
    sc = jn.Scene(own, "chetaev", initial=dict(x=0.3, y=0.3, x_t=0.5), t_span=(0, 1))
    run = sc.replace(initial=dict(x=1e-160, y=1.0, x_t=0.0)).run()
    assert run.status == 0 and np.all(np.isfinite(run.y))


@pytest.mark.parametrize("phi", [math.pi / 2, math.pi / 2 - 1e-7])
def test_knife_edge_at_rest_across_the_heading_edge(phi):
    """The knife edge with x_t = 0 at (or 1e-7 from) the heading pi/2, where
    y_t = tan(phi) x_t has a factor ~1e16 (~1e7): at rest, or spinning in place, y_t = 0
    is determined and consistent (an exact 0 has no rounding unit); x_t = 1e-300 there
    is not determined by the floats of the heading."""
    ke = models.get("knife_edge")
    rest = {"x": 0.0, "y": 0.0, "phi": phi, "x_t": 0.0, "phi_t": 0.0}
    for start in (rest, {**rest, "y_t": 0.0}, {**rest, "phi_t": 1.0}):
        sc = jn.Scene(ke, "chetaev", initial=start, t_span=(0.0, 0.1))
        assert sc.run().status == 0
    with pytest.raises(ConstraintError):
        jn.Scene(ke, "chetaev", initial={**rest, "x_t": 1e-300}, t_span=(0.0, 0.1))
