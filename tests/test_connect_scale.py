"""connect's end tolerance is relative to the problem's own displacement (free of the
units and the origin of the coordinates)."""

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st

import jetnh as jn
from jetnh.errors import ConnectError
from jetnh.models import knife_edge


def _oscillator():
    J = jn.JetSpace("x")
    x, = J.q
    xt, = J.qd
    return jn.System(J, xt**2 / 2 - x**2 / 2)


_OSC = _oscillator()


@settings(deadline=None, max_examples=8)
@given(st.sampled_from([1.0, 1e-6, 1e-10, 1e-14]), st.floats(0.3, 3.0))
def test_oscillator_end_in_any_units(unit, a):
    """x'' = -x from 0 to a u in T = 2: v0 = a u / sin 2 in every unit u (before:
    for a u <= 1e-10 the straight-line guess came back untouched, 55% short)."""
    c = jn.connect(_OSC, "vakonomic", {"x": 0.0}, {"x": a * unit}, (0.0, 2.0))
    exact = a * unit / math.sin(2.0)
    assert c.initial["x_t"] == pytest.approx(exact, rel=1e-8)
    assert c.trajectory["x"][-1] == pytest.approx(a * unit, rel=1e-8)
    assert c.relative_residual <= 1e-9 and c.iterations > 0


@pytest.mark.parametrize("turns", [0.0, 1e5, 1e7])
def test_pendulum_origin_free(turns):
    """The same pendulum problem, the angle counted after many turns: the same
    initial rate (before: a 7% miss after 1e7 turns, accepted)."""
    J = jn.JetSpace("th")
    th, = J.q
    tht, = J.qd
    S = jn.System(J, tht**2 / 2 + sp.cos(th))
    off = 2 * math.pi * turns
    c = jn.connect(S, "chetaev", {"th": off}, {"th": off + 0.5}, (0.0, 3.0))
    assert c.initial["th_t"] == pytest.approx(1.136720340033, rel=1e-7)
    assert abs(c.trajectory["th"][-1] - off - 0.5) <= 1e-7


@pytest.mark.parametrize("s", [1.0, 1e-9])
def test_unreachable_end_refused_in_any_units(s):
    """z_t = y x_t / s, every length scaled by s: (s, 0, 0.3 s) is off the Chetaev
    motions' reach in T = 1 in every unit (before: returned as connected at s = 1e-9)."""
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xt, yt, zt = J.qd
    k = sp.Symbol("s")
    S = jn.System(J, (xt**2 + yt**2 + zt**2) / 2, [zt - y * xt / k], dependent=[z])
    with pytest.raises(ConnectError, match="do not reach end") as e:
        jn.connect(S, "chetaev", {"x": 0, "y": 0, "z": 0},
                   {"x": s, "y": 0.0, "z": 0.3 * s}, (0, 1), params={k: s})
    assert e.value.best.residual == pytest.approx(0.239 * s, rel=0.01)


def test_heisenberg_normal_in_small_units():
    """The Heisenberg group has no abnormal motions but the constant ones: normal in
    metres and in units 1e-5 (z scales as a length squared; before, the search in the
    small units stopped 3% off the end, accepted)."""
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xt, yt, zt = J.qd
    H = jn.System(J, (xt**2 + yt**2) / 2, [zt - (x * yt - y * xt) / 2], dependent=[z])
    got = []
    for s in (1.0, 1e-5):
        c = jn.connect(H, "vakonomic", {"x": 0, "y": 0, "z": 0},
                       {"x": s, "y": 0.3 * s, "z": 0.2 * s * s}, (0, 1),
                       atol=1e-12 * s * s)        # the integration's, in z's units
        assert c.normal is True
        got.append(c.initial["lambda_z"])
    assert got[1] == pytest.approx(got[0], rel=1e-6)


def _free_oscillator():
    J = jn.JetSpace("x y")
    (x, y), (xt, yt) = J.q, J.qd
    k = sp.Symbol("k")
    return jn.System(J, k * (xt**2 + yt**2) / 2 - k * y**2 / 2)


_FREE = _free_oscillator()


@pytest.mark.parametrize("k", [1.0, 1e-12, 1e12])
def test_transversality_in_any_units_of_the_lagrangian(k):
    """y'' = -y from y = 0.5 with y(1) free: its momentum k y_t vanishes at t1, so
    y_t(0) = 0.5 tan 1 whatever the unit k of L (before, relative to 1: for k = 1e-12
    the straight-line guess y_t = 0 was accepted untouched, 100 % off; for k = 1e12 no
    answer).  The momentum's scale is the problem's own (``Momenta.scale``), and the
    search weighs a momentum far from the coordinates' scale by the ratio."""
    c = jn.connect(_FREE, "vakonomic", {"x": 0.0, "y": 0.5}, {"x": 1.0}, (0.0, 1.0),
                   params={"k": k})
    assert c.conditions == ("x", "p_y")
    assert c.initial["y_t"] == pytest.approx(0.5 * math.tan(1.0), rel=1e-9)
    assert c.relative_residual <= 1e-9


@pytest.mark.parametrize("a", [1.0, 1e-6, 1e6])
def test_transversality_in_any_units_of_the_free_coordinate(a):
    """The same with y measured in units 1/a (Y = a y, L = k (x_t^2 + Y_t^2 / a^2) / 2
    - k Y^2 / (2 a^2)): the momentum of Y is 1/a that of y."""
    J = jn.JetSpace("x y")
    (x, y), (xt, yt) = J.q, J.qd
    S = jn.System(J, (xt**2 + yt**2 / a**2) / 2 - y**2 / (2 * a**2))
    c = jn.connect(S, "vakonomic", {"x": 0.0, "y": 0.5 * a}, {"x": 1.0}, (0.0, 1.0))
    assert c.initial["y_t"] == pytest.approx(0.5 * a * math.tan(1.0), rel=1e-9)


@pytest.mark.parametrize("f", [1.0, 1e6, 1e9])
def test_returning_angle_judged_in_radians(f):
    """The knife edge from (0, 0, 0) to (L, L/2, 0) in T = 1 is off the Chetaev
    motions' reach (two unknowns, three end conditions): refused with lengths in m,
    um and nm alike (before: accepted in um and nm with phi ending 0.93 rad from 0,
    its miss scaled by the displacement of x, y in their units)."""
    with pytest.raises(ConnectError, match="reach") as e:
        jn.connect(knife_edge(), "chetaev", {"x": 0.0, "y": 0.0, "phi": 0.0},
                   {"x": f, "y": 0.5 * f, "phi": 0.0}, (0.0, 1.0), tol=1e-5)
    assert e.value.best.relative_residual > 0.1
    assert abs(e.value.best.trajectory["phi"][-1]) > 0.1


def _length_and_angle():
    J = jn.JetSpace("x th")
    (x, th), (xt, tht) = J.q, J.qd
    f = sp.Symbol("f")
    return jn.System(J, (xt**2 - x**2) / (2 * f**2) + (tht**2 - th**2) / 2)


_LA = _length_and_angle()


@pytest.mark.parametrize("f", [1.0, 1e6, 1e9])
def test_returning_angle_connected_in_any_units(f):
    """Two oscillators, x a length in units 1 / f, th an angle that returns to its
    start 0.3 in T = 2: th_t(0) = 0.3 (1 - cos 2) / sin 2 and x_t(0) = f / sin 2, the
    same relative residual in every unit (th judged on its own excursion)."""
    c = jn.connect(_LA, "vakonomic", {"x": 0.0, "th": 0.3}, {"x": f, "th": 0.3},
                   (0.0, 2.0), params={"f": f}, atol=1e-12)
    assert c.initial["th_t"] == pytest.approx(0.3 * (1 - math.cos(2)) / math.sin(2),
                                              rel=1e-8)
    assert c.initial["x_t"] == pytest.approx(f / math.sin(2.0), rel=1e-8)
    assert c.trajectory["th"][-1] == pytest.approx(0.3, abs=1e-9)
    assert c.relative_residual <= 1e-9


def _heisenberg_in_units():
    """Heisenberg in X = a x, Y = b y, Z = c z, its constraint times k (the multiplier
    in units 1 / k): the same motions in every unit."""
    a, b, c, k = sp.symbols("a b c k")
    J = jn.JetSpace("x y z")
    (x, y, z), (xd, yd, zd) = J.q, J.qd
    return jn.System(J, (xd**2 / a**2 + yd**2 / b**2) / 2,
                     [k * (zd / c - (x / a * yd / b - y / b * xd / a) / 2)],
                     dependent=[z])


_HU = _heisenberg_in_units()
_UNITS = st.sampled_from([1e-6, 1e-3, 1.0, 1e3, 1e6])


@settings(deadline=None, max_examples=6)
@given(_UNITS, st.sampled_from([1e-8, 1.0, 1e8]))
def test_regular_start_judged_free_of_units(f, k):
    """The straight line to (1, 0.5, 0.2) with the coordinates in units 1 / f and the
    multiplier in units 1 / k: its shooting Jacobian has the same unit-free singular
    values (rows over their displacement, columns over their norm), so the guess is
    kept in every unit (before: judged on the raw Jacobian, where a multiplier in units
    1e8 makes its column 1e-8 of the others', and the guess was moved off)."""
    from jetnh.numeric.connect.problem import _scene
    from jetnh.numeric.connect.shooting import singular_values
    from jetnh.numeric.connect.solve import Search

    got = []
    for a, kk in ((1.0, 1.0), (f, k)):
        q0 = {"x": 0.0, "y": 0.0, "z": 0.0}
        q1 = {"x": a, "y": 0.5 * a, "z": 0.2 * a}
        line = {"x_t": q1["x"], "y_t": q1["y"], "lambda_z": 0.0}
        scene = _scene(_HU, "vakonomic", {"a": a, "b": a, "c": a, "k": kk},
                       lambda: {**q0, **line}, (0.0, 1.0))
        atol = [1e-12 * (1.0 / kk if n.startswith("lambda") else a)
                for n in scene.state_names]                 # in each state's units
        search = Search(scene, q0, q1, tuple(line), {}, 1e-11, atol, "dop853", 1e-9)
        u0 = np.array(list(line.values()))
        end = search.endpoint(u0)
        got.append(singular_values(search.unit_free(end[1])))
        assert search.regular(end)
        assert np.array_equal(search.regular_start(u0, q0, q1, 1.0, 2), u0)
    assert got[1] == pytest.approx(got[0], rel=1e-6)


@settings(deadline=None, max_examples=8)
@given(_UNITS, _UNITS, st.sampled_from([1e-8, 1.0, 1e8]), st.floats(-50.0, 50.0))
def test_matching_scales_follow_the_units(f, g, k, off):
    """Multiple shooting's matching conditions are met relative to each state's own
    size along the nodes, free of its unit and of the coordinates' origin: x, y in
    units 1 / f, z in 1 / g, the multiplier in 1 / k and the whole start moved by
    ``off`` (in units 1) scale each state's scale by its unit (before: 1 + |Y|, an
    absolute 1e-9 on states of size 1e-6, and the origin's |Y| on a coordinate)."""
    from jetnh.numeric.connect.problem import _scene
    from jetnh.numeric.connect.solve import Search, _Segments

    got = []
    for a, c, kk, o in ((1.0, 1.0, 1.0, 0.0), (f, g, k, off)):
        q0 = {"x": o * a, "y": o * a, "z": o * c}
        q1 = {"x": (o + 1.0) * a, "y": (o + 0.5) * a, "z": (o + 0.2) * c}
        u = {"x_t": 0.8 * a, "y_t": -0.3 * a, "lambda_z": 0.7 / kk}
        scene = _scene(_HU, "vakonomic", {"a": a, "b": a, "c": c, "k": kk},
                       lambda: {**q0, **u}, (0.0, 1.0))
        search = Search(scene, q0, q1, tuple(u), {}, 1e-11, 1e-12, "dop853", 1e-9)
        seg = _Segments(search, 4, 1e-9)
        unit = np.array([{"x": a, "y": a, "z": c}.get(n, a if n.endswith("_t") else 1 / kk)
                         for n in scene.state_names])
        inner = seg.scale(seg.guess(np.array(list(u.values()))))[:3 * len(unit)]
        got.append(inner.reshape(3, -1) / unit)
    # (the rounding of the moved origin's values aside: 16 ulps of |Y| / tol)
    assert got[1] == pytest.approx(got[0], rel=1e-9, abs=1e-4 * (1.0 + abs(off)))


def test_a_state_zero_at_every_node_has_a_scale():
    """A state that is 0 at every node of multiple shooting (here the multiplier of a
    start with lambda = 0, which the guess keeps at the inner nodes) has no size of its own:
    its matching conditions get the rounding of the largest state as their scale, never
    0 (a scale of 0 asked for a miss of exactly 0: a ConnectError on a solvable
    problem)."""
    from jetnh.numeric.connect.problem import _scene
    from jetnh.numeric.connect.solve import Search, _Segments

    q0, q1 = {"x": 0.0, "y": 0.0, "z": 0.0}, {"x": 1.0, "y": 0.5, "z": 0.2}
    u = {"x_t": 0.8, "y_t": -0.3, "lambda_z": 0.0}
    scene = _scene(_HU, "vakonomic", {"a": 1.0, "b": 1.0, "c": 1.0, "k": 1.0},
                   lambda: {**q0, **u}, (0.0, 1.0))
    search = Search(scene, q0, q1, tuple(u), {}, 1e-11, 1e-12, "dop853", 1e-9)
    seg = _Segments(search, 4, 1e-9)
    U = seg.guess(np.array(list(u.values())))
    column = scene.state_names.index("lambda_z")
    assert all(Y[column] == 0.0 for Y in seg.split(U))
    scales = seg.scale(U)
    assert np.all(scales > 0.0) and np.all(np.isfinite(scales))
