"""connect's verdicts do not depend on the chart or on the units of the coordinates.

- Legendre with holonomic constraints: a pendulum written in Cartesian x, y on
  x^2 + y^2 = l^2 (the constraints hold D g, so the admissible velocities are tangent to
  g = 0 already) with kinetic coefficient M, plus a free oscillator w; the same system
  in the angle th, L = M thdot^2 / 2 + wdot^2 / 2 + G cos th - w^2 / 2, is the reference
  (no constraint).  In the independent velocities (xdot, wdot) the reduced Hessian is
  diag(M (1 + x^2 / y^2), 1), in (thdot, wdot) diag(M l^2, 1): scaled to a unit
  diagonal both are diag(sign M, 1), so ``legendre`` is 1 for M > 0 and -1 for M < 0
  (Legendre's necessary condition fails: no minimizer), in both charts.
- Units: the Heisenberg system in the units X = a x, Y = b y, Z = c z,
  L = (Xdot^2 / a^2 + Ydot^2 / b^2 + e Zdot^2 / c^2) / 2 with
  Zdot / c = (X / a Ydot / b - Y / b Xdot / a) / 2, is the same motion whatever a, b,
  c: the same cost, and the verdicts (Gramian ratio, Legendre, normal, minimizer,
  conjugate times) must be the same numbers.  With e > 0 the reduced
  Hessian in (xdot, ydot) is I + e phi_u^T phi_u, phi_u = (-y, x) / 2, whose unit-diagonal
  form has the eigenvalues 1 +- |rho|, rho = -e x y / 4 / sqrt((1 + e y^2 / 4)
  (1 + e x^2 / 4)): ``legendre`` = min over the path of 1 - |rho| (closed form).
- Martinet's abnormal segment (zdot = y^2 xdot / 2, y = 0) stays abnormal in any units,
  and the end off it normal.  Its ends are also met, within the tolerance, by normal
  extremals y = A sin(pi t) whose end z = A^2 / 4 is the miss (the default guess
  returns one): within their miss of the abnormal segment, so not normal, in any units
  of x, y and z (``gramian_change`` the same number, whatever A the units' tolerance
  leaves); before, normal (the unit-free Gramian ratio is 0.1 at every A > 0).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import example, given, settings
from hypothesis import strategies as st

import jetnh as jn

O = {"x": 0.0, "y": 0.0, "z": 0.0}


def _pendulums():
    G, l, M = sp.symbols("G l M")
    J = jn.JetSpace("x y w")
    (x, y, w), (xt, yt, wt) = J.q, J.qd
    cart = jn.System(J, M * (xt**2 + yt**2) / 2 + wt**2 / 2 - G * y - w**2 / 2,
                     [x**2 + y**2 - l**2])
    Ja = jn.JetSpace("th w")
    (th, wa), (tht, wat) = Ja.q, Ja.qd
    angle = jn.System(Ja, M * tht**2 / 2 + wat**2 / 2 + G * sp.cos(th) - wa**2 / 2, [])
    return cart, angle


@pytest.fixture(scope="module")
def pendulums():
    return _pendulums()


@pytest.mark.parametrize("M", [3.0, -1.0])
def test_legendre_with_a_holonomic_constraint_is_the_angle_charts(pendulums, M):
    """Was 1.0 and minimizer True for M = -1 (one admissible direction dropped per
    holonomic constraint)."""
    cart, angle = pendulums
    th0, th1, w1, T = -0.2, 0.5, 0.3, 0.5
    c = jn.connect(cart, "vakonomic", {"x": math.sin(th0), "y": -math.cos(th0), "w": 0.0},
                   {"x": math.sin(th1), "w": w1}, (0.0, T),
                   params={"G": 9.81, "l": 1.0, "M": M})
    a = jn.connect(angle, "vakonomic", {"th": th0, "w": 0.0}, {"th": th1, "w": w1},
                   (0.0, T), params={"G": 9.81, "M": M})
    assert abs(c.cost - a.cost) < 1e-7                       # the same motion
    assert abs(c.legendre - math.copysign(1.0, M)) < 1e-12
    assert abs(a.legendre - math.copysign(1.0, M)) < 1e-12
    assert c.minimizer is a.minimizer is (M > 0)
    assert c.normal and a.normal


@pytest.mark.parametrize("T", [0.5, 0.8])
def test_plain_cartesian_pendulum_is_a_minimizer(T):
    """One admissible direction on a circle: was legendre 0.0, minimizer None (the only
    direction dropped)."""
    G, l = sp.symbols("G l", positive=True)
    J = jn.JetSpace("x y")
    (x, y), (xt, yt) = J.q, J.qd
    S = jn.System(J, (xt**2 + yt**2) / 2 - G * y, [x**2 + y**2 - l**2])
    for principle in ("vakonomic", "holder"):
        c = jn.connect(S, principle, {"x": math.sin(-0.2), "y": -math.cos(-0.2)},
                       {"x": math.sin(0.5)}, (0.0, T), params={"G": 9.81, "l": 1.0})
        assert abs(c.legendre - 1.0) < 1e-12
        assert c.minimizer is True and c.conjugate_times == () and c.normal
        assert c.gramian_ratio == 1.0                  # a 1 x 1 Gramian on g = 0


def _heisenberg():
    a, b, c, e = sp.symbols("a b c e")
    J = jn.JetSpace("x y z")
    (x, y, z), (xd, yd, zd) = J.q, J.qd
    L = (xd**2 / a**2 + yd**2 / b**2 + e * zd**2 / c**2) / 2
    return jn.System(J, L, [zd / c - (x / a * yd / b - y / b * xd / a) / 2], dependent=[z])


HEIS = _heisenberg()
END = {"x": 1.0, "y": 0.5, "z": 0.2}


def _heis(a=1.0, b=1.0, c=1.0, e=0.0, guess=None):
    end = {"x": a * END["x"], "y": b * END["y"], "z": c * END["z"]}
    return jn.connect(HEIS, "vakonomic", O, end, (0.0, 1.0), guess=guess,
                      params={"a": a, "b": b, "c": c, "e": e})


_REFERENCE: dict = {}


def _reference(e):
    if e not in _REFERENCE:
        _REFERENCE[e] = _heis(e=e)
    return _REFERENCE[e]


@pytest.mark.parametrize("e", [0.0, 0.5])
def test_legendre_closed_form_in_the_independent_velocities(e):
    r = _reference(e)
    names = r.trajectory.scene.state_names
    x = r._samples.grid_y[:, names.index("x")]
    y = r._samples.grid_y[:, names.index("y")]
    rho = e * x * y / 4 / np.sqrt((1 + e * y**2 / 4) * (1 + e * x**2 / 4))
    assert abs(r.legendre - (1.0 - np.abs(rho).max())) < 1e-12
    assert r.minimizer is True and r.normal


def _scale(low, high):
    return st.floats(low, high).map(lambda s: 10.0 ** s)


@settings(max_examples=8)
@given(_scale(-1.0, 2.0), _scale(-1.0, 2.0), _scale(-6.0, 3.0), st.sampled_from([0.0, 0.5]))
@example(1.0, 1.0, 1e-5, 0.0)          # normal was False (ratio 1e-11)
@example(1.0, 1.0, 1e5, 0.0)           # minimizer was None (legendre 3e-10)
@example(1e3, 1e-1, 1e-6, 0.5)
def test_heisenberg_verdicts_do_not_depend_on_units(a, b, c, e):
    """The same motion from the reference's initial velocities in the new units (the
    search itself is not what is tested; in units far off, e.g. x in 1e-3 and z in
    1e4, the scene's runs stop at a singularity indicator that depends on units)."""
    ref = _reference(e)
    u = ref.initial
    got = _heis(a, b, c, e, guess={"x_t": a * u["x_t"], "y_t": b * u["y_t"],
                                   "lambda_z": u["lambda_z"]})
    assert got.residual < 1e-8 * max(a, b, c)
    assert got.cost == pytest.approx(ref.cost, rel=1e-7)
    assert got.gramian_ratio == pytest.approx(ref.gramian_ratio, rel=1e-6)
    assert abs(got.legendre - ref.legendre) < 1e-7
    assert got.normal is ref.normal is True
    assert got.minimizer is ref.minimizer is True
    # none inside the span (t1 itself can be flagged where x and y are in units 1e4
    # apart: ``conjugate_times`` measures dq/du by columns, not by rows)
    assert ref.conjugate_times == () and all(t == 1.0 for t in got.conjugate_times)


def _martinet():
    b, c = sp.symbols("b c")
    J = jn.JetSpace("x y z")
    (x, y, z), (xd, yd, zd) = J.q, J.qd
    return jn.System(J, (xd**2 + yd**2 / b**2) / 2, [zd / c - (y / b)**2 * xd / 2],
                     dependent=[z])


@pytest.mark.parametrize("b, c", [(1.0, 1.0), (1e-3, 1e6), (1e4, 1e-5)])
def test_martinet_abnormal_segment_in_any_units(b, c):
    S = _martinet()
    seg = jn.connect(S, "vakonomic", O, {"x": 1.0, "y": 0.0, "z": 0.0}, (0.0, 1.0),
                     params={"b": b, "c": c},
                     guess={"x_t": 1.0, "y_t": 0.0, "lambda_z": 0.0})   # y = 0 itself
    assert seg.trajectory["y"].max() == seg.trajectory["y"].min() == 0.0
    assert seg.residual < 1e-8 and not seg.normal and seg.gramian_ratio < 1e-9
    ref = _martinet_off()
    u = ref.initial                # the answer in units 1 (the search is not tested)
    off = jn.connect(S, "vakonomic", O, {"x": 1.0, "y": 0.0, "z": 0.05 * c}, (0.0, 1.0),
                     params={"b": b, "c": c},
                     guess={"x_t": u["x_t"], "y_t": b * u["y_t"], "lambda_z": u["lambda_z"]})
    assert off.normal and off.residual < 1e-9 * max(1.0, c)
    assert off.gramian_ratio == pytest.approx(ref.gramian_ratio, rel=1e-6)


_MARTINET: dict = {}


def _martinet_off():
    if "off" not in _MARTINET:
        _MARTINET["off"] = jn.connect(_martinet(), "vakonomic", O,
                                      {"x": 1.0, "y": 0.0, "z": 0.05}, (0.0, 1.0),
                                      params={"b": 1.0, "c": 1.0})
    return _MARTINET["off"]


def _martinet3():
    a, b, c = sp.symbols("a b c")
    J = jn.JetSpace("x y z")
    (x, y, z), (xd, yd, zd) = J.q, J.qd
    return jn.System(J, (xd**2 / a**2 + yd**2 / b**2) / 2,
                     [zd / c - (y / b)**2 * xd / a / 2], dependent=[z])


MARTINET3 = _martinet3()
UNITS = [(1.0, 1.0, 1.0), (1e-6, 1.0, 1.0), (1e6, 1.0, 1.0), (1.0, 1e-6, 1.0),
         (1.0, 1e6, 1.0), (1.0, 1.0, 1e-6), (1.0, 1.0, 1e6)]


def _martinet3_in(a, b, c, z1, guess=None):
    return jn.connect(MARTINET3, "vakonomic", O, {"x": a, "y": 0.0, "z": z1 * c},
                      (0.0, 1.0), params={"a": a, "b": b, "c": c}, guess=guess)


def _refused_best(*args):
    """The end z = 0 beside the abnormal segment: refused (z returns, judged on its own
    excursion); the closest motion found."""
    with pytest.raises(jn.ConnectError) as e:
        _martinet3_in(*args)
    return e.value.best


def _martinet3_references():
    if "near" not in _MARTINET:
        _MARTINET["near"] = _refused_best(1.0, 1.0, 1.0, 0.0)       # the default guess
        _MARTINET["off3"] = _martinet3_in(1.0, 1.0, 1.0, 0.05)
    return _MARTINET["near"], _MARTINET["off3"]


@pytest.mark.parametrize("a, b, c", UNITS)
def test_martinet_near_abnormal_in_any_units(a, b, c):
    """x, y and z each in units 1e-6 and 1e6: the closest motion beside the abnormal
    segment (refused in every unit; from the default guess's in units 1) is not
    normal, its ``gramian_change``
    the same; the end off the segment is normal, with a change at the relative miss."""
    near, off = _martinet3_references()
    assert near.normal is False and 0.3 < near.gramian_change < 1.0
    assert near.gramian_ratio > 1e-2                   # the path's own: no units either
    u = near.initial
    got = _refused_best(a, b, c, 0.0, {"x_t": a * u["x_t"], "y_t": b * u["y_t"],
                                       "lambda_z": u["lambda_z"]})
    assert 0.0 < abs(got.trajectory["y"]).max() / b < 1e-3
    assert got.normal is False
    assert got.gramian_change == pytest.approx(near.gramian_change, rel=0.05)
    v = off.initial
    far = _martinet3_in(a, b, c, 0.05, {"x_t": a * v["x_t"], "y_t": b * v["y_t"],
                                        "lambda_z": v["lambda_z"]})
    assert far.normal is True and far.gramian_change < 1e-6
    assert far.gramian_ratio == pytest.approx(off.gramian_ratio, rel=1e-6)
