"""jetnh.numeric.linearize with holonomic constraints g(t, q) = 0: perturbations stay
within g = 0 (the state holds the independent coordinates of g; the eliminated ones
follow), a point off g = 0 is refused, and the holonomic multipliers no equation depends
on are left out.

Two routes to every result: the system with g kept against the same system with a
coordinate eliminated by hand (the pendulum in Cartesian coordinates against the pendulum
in its angle; a knife edge carrying a slider z = a sin(theta) against the knife edge with
z substituted) under every principle, and A against central differences of the compiled
rhs taken along curves inside g = 0 (random systems).
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, assume, given, settings, strategies as st

import jetnh as jn
import jetnh.strategies as jst
from jetnh.algebra import dag
from jetnh.errors import ConstraintError, JetnhError, LinearizationError
from jetnh.mechanics import holonomic, principles

from holonomic_systems import (I_, KNIFE, a_, knife_reduced, knife_slider, pendulum_angle,
                               pendulum_xy)

PENDULUM = {"l": 1.3, "G": 9.81}


def _lams(system, principle, value):
    return {m.name: value for m in principles.get(principle).multiplier_symbols(system)}


# ---------------------------------------------------------------------- closed forms
@pytest.mark.parametrize("principle", jn.PRINCIPLES)
def test_cartesian_pendulum_is_the_angle_pendulum(principle):
    """At the bottom x = l th to first order: A of the Cartesian pendulum (state x, x_t;
    y eliminated) is the angle pendulum's, eigenvalues +-i sqrt(G/l) and no zero; at the
    top +-sqrt(G/l).  The holonomic multiplier is no state (it enters through its rate
    only)."""
    s = pendulum_xy()
    w = np.sqrt(PENDULUM["G"] / PENDULUM["l"])
    low = jn.linearize(s, principle, at={"x": 0.0, "y": -1.3, "x_t": 0.0,
                                         **_lams(s, principle, 0.4)}, params=PENDULUM)
    assert low.state_names == ("x", "x_t") and low.eliminated == ("y",)
    assert low.inert == (("lambda_y",) if principle != "chetaev" else ())
    ref = jn.linearize(pendulum_angle(), "chetaev", at={"th": 0.0, "th_t": 0.0},
                       params=PENDULUM)
    assert np.allclose(low.A, ref.A, atol=1e-12) and low.residual == 0.0
    assert np.allclose(low.eigenvalues, [-1j * w, 1j * w], atol=1e-12)
    assert low.verdict == "marginal"
    top = low.replace(at={"y": 1.3})                    # re-checked and recomputed
    assert np.allclose(top.A, [[0.0, 1.0], [w**2, 0.0]], atol=1e-12)
    assert np.allclose(top.eigenvalues, [w, -w], atol=1e-12)
    assert top.verdict == "unstable"


@pytest.mark.parametrize("principle", jn.PRINCIPLES)
def test_knife_edge_with_slider_against_the_slider_eliminated(principle):
    """Mixed constraints, every principle, off any steady motion and with nonzero
    multipliers: A of the knife edge with z kept holonomic (z eliminated, its multiplier
    inert) equals A of the knife edge with z = a sin(th) substituted by hand, with every
    coordinate kept and with the cyclic ones dropped."""
    full, red = knife_slider(), knife_reduced()
    base = {"x": 0.1, "y": 0.2, "th": 0.3, "x_t": 1.1, "th_t": 0.7}
    a = jn.linearize(full, principle, at={**base, "z": 0.4 * np.sin(0.3),
                                          **_lams(full, principle, 0.2)},
                     params=KNIFE, drop=None)
    b = jn.linearize(red, principle, at={**base, **_lams(red, principle, 0.2)},
                     params=KNIFE, drop=None)
    assert a.state_names == b.state_names and a.eliminated == ("z",)
    assert a.inert == (("lambda_z",) if principle != "chetaev" else ())
    assert a.residual > 0.1 and np.abs(a.A).max() > 0.1
    assert np.allclose(a.A, b.A, atol=1e-12, rtol=1e-12)
    ac = jn.linearize(full, principle, at=dict(a.at), params=KNIFE)
    bc = jn.linearize(red, principle, at=dict(b.at), params=KNIFE)
    assert ac.dropped == bc.dropped == ("x", "y")
    assert ac.state_names == bc.state_names
    assert np.allclose(ac.A, bc.A, atol=1e-12, rtol=1e-12)
    assert np.allclose(ac.eigenvalues, bc.eigenvalues, atol=1e-9)


def test_steady_solves_along_g():
    """steady() for a coordinate moves the eliminated ones with it: the pendulum at rest
    from x = 0.3 (y on g = 0) settles at the bottom."""
    s = pendulum_xy()
    y0 = -np.sqrt(1.3**2 - 0.3**2)
    lin = jn.linearize(s, at={"x": 0.3, "y": y0, "x_t": 0.0}, params=PENDULUM)
    rest = lin.steady(["x"])
    assert abs(rest.at["x"]) < 1e-12 and abs(rest.at["y"] + 1.3) < 1e-12
    assert rest.residual < 1e-10


# ---------------------------------------------------------------------- bad input
def test_a_point_off_g_is_refused_with_the_residual_and_the_fix():
    s = pendulum_xy()
    with pytest.raises(ConstraintError,
                       match=r"off the holonomic.*is 0\.01.*y = -1\.296148"):
        jn.linearize(s, at={"x": 0.1, "y": -1.3, "x_t": 0.0}, params=PENDULUM)
    lin = jn.linearize(s, at={"x": 0.0, "y": -1.3, "x_t": 0.0}, params=PENDULUM)
    with pytest.raises(ConstraintError, match="off the holonomic"):
        lin.replace(at={"x": 0.5})
    with pytest.raises(ConstraintError, match="off the holonomic"):
        lin.replace(params={"l": 2.0})
    assert lin.replace(params={"l": 2.0}, at={"y": -2.0}).eigenvalues[1].imag == \
        pytest.approx(np.sqrt(9.81 / 2.0), rel=1e-12)
    with pytest.raises(JetnhError, match="missing operating-point values: y"):
        jn.linearize(s, at={"x": 0.0, "x_t": 0.0}, params=PENDULUM)
    # without its spring no equation uses z, but g ties it to th: it is no cyclic
    # coordinate (dropping it would let th move off g = 0)
    J = jn.JetSpace("x y th z")
    x, y, th, z = J.q
    xt, yt, tht, zt = J.qd
    free = jn.System(J, (xt**2 + yt**2 + I_ * tht**2 + zt**2) / 2,
                     [sp.sin(th) * xt - sp.cos(th) * yt, z - a_ * sp.sin(th)],
                     dependent=["y", "z"])
    with pytest.raises(JetnhError, match="holonomic constraint ties it to th"):
        jn.linearize(free, at={"x": 0, "y": 0, "th": 0, "z": 0, "x_t": 1, "th_t": 0},
                     params={"a": 0.4, "I": 0.7}, drop=["x", "y", "z"])
    from jetnh.numeric.linearize import _model
    assert _model(free, "chetaev").cyclic() == (0, 1)


# ---------------------------------------------------------------------- property
def _along_g(lin, h=1e-5):
    """Central differences of the compiled rhs along curves inside g = 0: one kept state
    moved by +-h, the eliminated coordinates solved from g = 0 again."""
    model, keep = lin._model, list(lin._keep)
    ck, p, t = lin._kernels, lin._p, lin.t
    f = np.empty(len(lin._y))
    cols = []
    for i in keep:
        out = []
        for s in (h, -h):
            y = lin._y.copy()
            y[i] += s
            if lin.eliminated:
                point = {"t": t, **dict(lin.params),
                         **{q.name: y[j] for j, q in enumerate(model.coordinates)}}
                done, _ = holonomic.check(lin.system, point, complete=list(lin.eliminated),
                                          tol=0.0)
                for j in lin._chart:
                    y[j] = float(done[model.coordinates[j]])
            ck.rhs(t, y, p, f)
            out.append(f[keep].copy())
        cols.append((out[0] - out[1]) / (2 * h))
    return np.array(cols).T


def _symbolic_at(lin):
    S = lin.symbolic()
    names = {sym.name: sym for sym in dag.free_symbols(list(S))}
    values = {**dict(lin.at), **dict(lin.params), "t": lin.t}
    vals = dag.evaluate(list(S), {sym: values[n] for n, sym in names.items()})
    return np.array([complex(v).real for v in vals]).reshape(lin.A.shape)


@settings(max_examples=5, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.data())
def test_A_along_curves_inside_g(data):
    """Random systems with one holonomic constraint (the last coordinate a polynomial
    graph over the others), every principle, random points on g = 0: A equals the central
    differences of the compiled rhs along curves inside g = 0 and the symbolic A, and has
    as many states as independent coordinates, velocities and live multipliers."""
    J = data.draw(jst.jet_spaces(min_n=2, max_n=3))
    others = jn.JetSpace([q.name for q in J.q[:-1]])
    V = data.draw(jst.polynomials(J, order=0, max_degree=2))
    P = data.draw(jst.polynomials(others, order=0, max_degree=2)).xreplace(
        {sp.Symbol(q.name): q for q in J.q[:-1]})
    # a spring on the last coordinate and a slope of g in the first: the rows depend on
    # the eliminated coordinate, which moves with the others
    P = P + J.q[0] / 2
    L = sum(v**2 for v in J.qd) / 2 + V - J.q[-1]**2 / 2
    principle = data.draw(st.sampled_from(jn.PRINCIPLES))
    try:
        s = jn.System(J, L, [J.q[-1] - P])
    except JetnhError:
        assume(False)
    rng = np.random.default_rng(data.draw(st.integers(0, 2**16)))
    point = {q.name: rng.uniform(-0.6, 0.6) for q in J.q[:-1]}
    on_g = {J.t: 0.0, **{q: point[q.name] for q in J.q[:-1]}}
    point[J.q[-1].name] = float(dag.evaluate([P], on_g)[0])
    point.update({v.name: rng.uniform(-0.6, 0.6) for v in s.independent_velocities})
    point.update(_lams(s, principle, rng.uniform(-0.6, 0.6)))
    try:
        lin = jn.linearize(s, principle, at=point, drop=None)
    except (LinearizationError, ConstraintError):
        assume(False)
    assume(np.all(np.isfinite(lin.A)) and not lin.limit)
    assert len(lin.eliminated) == 1 and lin.eliminated[0] not in lin.state_names
    lams = len(principles.get(principle).multiplier_symbols(s))
    assert len(lin.state_names) == (J.n - 1) + (J.n - 1) + lams - len(lin.inert)
    scale = max(1.0, np.abs(lin.A).max())
    assert np.allclose(lin.A, _along_g(lin), atol=1e-6 * scale, rtol=1e-6)
    assert np.allclose(lin.A, _symbolic_at(lin), atol=1e-10 * scale, rtol=1e-10)


def test_along_moves_the_eliminated_coordinates_with_g():
    """A scan along a coordinate or a parameter keeps the point on g = 0 (y solved from
    it): along l at the bottom the eigenvalues are +-i sqrt(G/l); along x they are those
    of ``replace`` at the points with y = -sqrt(l^2 - x^2) given by hand."""
    s = pendulum_xy()
    lin = jn.linearize(s, at={"x": 0.0, "y": -1.3, "x_t": 0.0}, params=PENDULUM)
    ls = np.array([0.5, 1.0, 2.0])
    scan = lin.along("l", ls)
    assert np.allclose(scan.eigenvalues[:, 1].imag, np.sqrt(9.81 / ls), rtol=1e-12)
    xs = np.array([-0.6, 0.2, 0.9])
    scan = lin.along("x", xs)
    for x, ev in zip(xs, scan.eigenvalues):
        ref = lin.replace(at={"x": x, "y": -np.sqrt(1.3**2 - x**2)})
        assert np.allclose(ev, ref.eigenvalues, atol=1e-12)
