"""connect on systems with holonomic constraints (a Kane four-bar): the verdicts on the
constraint manifold g = 0, its multipliers out of the unknowns, the ends checked on it;
and the small refusals of bad spans and tolerances."""

import math

import numpy as np
import pytest

import jetnh as jn
from jetnh.errors import ConnectError, ConstraintError, JetnhError

from damped_sleigh import ORIGIN, PARAMS, damped_sleigh
from holonomic_systems import FOURBAR, kane_fourbar


@pytest.fixture(scope="module")
def fourbar():
    """Three links l1, l2, l3 from the origin closing on (l4, 0): one degree of freedom,
    two loop-closure constraints (``configuration_constraints``)."""
    pytest.importorskip("sympy.physics.mechanics")
    s, P = kane_fourbar(), FOURBAR
    sc = jn.Scene(s, "chetaev", params=P, initial={"q1": 1.2, "q2": 0.3, "q3": -1.5,
                                                   "q1_t": 2.0},
                  complete=True, t_span=(0.0, 0.5))
    y0 = dict(zip(sc.state_names, map(float, sc.y0)))
    q0 = {k: y0[k] for k in ("q1", "q2", "q3")}
    return s, P, q0, sc


def _fd_end(sc, q0, u, h=1e-6):
    """dq(t1)/dq1_t by central differences of scene.run (the independent route)."""
    def end(v):
        tr = sc.run(y0={**q0, "q1_t": v}, rtol=1e-12, atol=1e-13)
        return np.array([tr[c][-1] for c in ("q1", "q2", "q3")])
    return (end(u + h) - end(u - h)) / (2 * h)


def test_chetaev_fourbar_is_normal_on_the_manifold(fourbar):
    s, P, q0, sc = fourbar
    c = jn.connect(s, "chetaev", q0, {"q1": 1.5}, (0.0, 0.5), params=P)
    assert c.trajectory["q1"][-1] == pytest.approx(1.5, abs=1e-8)
    d = _fd_end(sc, q0, c.initial["q1_t"])
    assert np.linalg.norm(d) > 0.5                     # full rank on the 1-d manifold
    assert d == pytest.approx([0.633, -0.0266, 0.3028], abs=2e-3)
    assert c.normal is True
    assert c.gramian_ratio == pytest.approx(1.0)       # a 1 x 1 Gramian on g = 0


def test_vakonomic_fourbar_no_conjugate_time_and_no_holonomic_unknowns(fourbar):
    s, P, q0, sc = fourbar
    c = jn.connect(s, "vakonomic", q0, {"q1": 1.5}, (0.0, 0.5), params=P)
    assert c.unknowns == ("q1_t",)            # the multipliers of g = 0 are inert
    assert c.trajectory["q1"][-1] == pytest.approx(1.5, abs=1e-8)
    assert c.conjugate_times == ()
    assert c.normal is True
    # the same motion as Chetaev's (holonomic constraints: the principles agree)
    ch = jn.connect(s, "chetaev", q0, {"q1": 1.5}, (0.0, 0.5), params=P)
    assert c.initial["q1_t"] == pytest.approx(ch.initial["q1_t"], rel=1e-7)


def test_start_and_end_off_the_manifold_are_refused(fourbar):
    s, P, q0, _ = fourbar
    off = {"q1": 1.2, "q2": 0.3, "q3": -1.5}
    with pytest.raises(ConstraintError, match=r"start.*complete=True"):
        jn.connect(s, "chetaev", off, {"q1": 1.5}, (0.0, 0.5), params=P)
    with pytest.raises(ConstraintError, match=r"end.*holonomic"):
        jn.connect(s, "chetaev", q0, {"q1": 1.5, "q2": 0.0, "q3": 0.0}, (0.0, 0.5),
                   params=P)
    # complete=True completes the start as Scene does
    c = jn.connect(s, "chetaev", off, {"q1": 1.5}, (0.0, 0.5), params=P, complete=True)
    assert c.initial["q2"] == pytest.approx(q0["q2"], abs=1e-10)
    assert c.initial["q3"] == pytest.approx(q0["q3"], abs=1e-10)


# ------------------------------------------------------------------ the sleigh's small ones
@pytest.fixture(scope="module")
def sleigh():
    return damped_sleigh(), dict(PARAMS), dict(ORIGIN)


def test_backward_span_refused_clearly(sleigh):
    s, P, O = sleigh
    with pytest.raises(JetnhError, match=r"t1 > t0"):
        jn.connect(s, "chetaev", O, {"x": 0.2, "th": 0.3}, (1.0, 0.0), params=P)


@pytest.mark.parametrize("tol", [1e-2, 1e3])
def test_loose_tolerance_refused(sleigh, tol):
    s, P, O = sleigh
    with pytest.raises(JetnhError, match=r"tol"):
        jn.connect(s, "vakonomic", O, {"x": 1.0, "y": 0.3, "th": 0.4}, (0.0, 1.0),
                   params=P, tol=tol)


def test_no_best_motion_message_is_truthful(sleigh):
    s, P, O = sleigh
    with pytest.raises(ConnectError) as info:
        jn.connect(s, "vakonomic", O, {"x": -20.0, "y": 15.0, "th": 3.0}, (0.0, 50.0),
                   params=P, max_iter=3, max_continuation=2, segments=1, timeout=10.0)
    e = info.value
    text = e.args[0]
    if e.best is None:
        assert "?" not in text and "ConnectError.best is that" not in text
        assert "ConnectError.best is None" in text
    else:
        assert f"{e.best.residual:.3g}" in text


def test_timeout_stops_the_search_with_the_closest_motion(sleigh):
    """An end the search does not reach (th = 20 from th = 0 in 1 s, through many
    edges of the split): a search of 20 s without a budget; with one, a ConnectError
    saying so, its closest motion a real run to t1."""
    s, P, O = sleigh
    with pytest.raises(ConnectError, match=r"timeout of 0\.5 s") as info:
        jn.connect(s, "chetaev", O, {"x": 3.0, "th": 20.0}, (0.0, 1.0), params=P,
                   timeout=0.5)
    best = info.value.best
    if best is not None:
        assert best.residual > 1e-3
        assert best.trajectory.t[-1] == pytest.approx(1.0)
    with pytest.raises(JetnhError, match="timeout"):
        jn.connect(s, "chetaev", O, {"x": 0.2, "th": 2.0}, (0.0, 1.0), params=P,
                   timeout=-1.0)


def test_end_at_the_edge_of_the_split_is_normal(sleigh):
    """At th = pi/2 the split with y dependent is singular (cos th = 0); the Gramian is
    measured without it there: the endpoint map has full rank (central differences of
    scene.run: singular values 1.00 and 0.71), so the motion is normal (the Gramian's
    unit-free ratio 4e-4, far above ``GRAMIAN_RCOND``)."""
    s, P, O = sleigh
    end = {"x": 0.2, "th": math.pi / 2}
    c = jn.connect(s, "chetaev", O, end, (0.0, 1.0), params=P,
                   guess=[0.01139617261555533, 1.9306420355965677])   # its answer
    assert c.residual < 1e-8
    sc = jn.Scene(s, "chetaev", params=P, initial={**O, "x_t": 0.1, "th_t": 1.0},
                  t_span=(0.0, 1.0))
    u, h = np.array([c.initial["x_t"], c.initial["th_t"]]), 1e-6

    def F(v):
        tr = sc.run(y0={**O, "x_t": v[0], "th_t": v[1]}, rtol=1e-12, atol=1e-13)
        return np.array([tr[k][-1] for k in ("x", "y", "th")])

    D = np.array([(F(u + h * e) - F(u - h * e)) / (2 * h) for e in np.eye(2)]).T
    sv = np.linalg.svd(D, compute_uv=False)
    assert sv == pytest.approx([0.999, 0.708], abs=5e-3)
    assert c.normal is True and c.gramian_ratio > 1e-4
