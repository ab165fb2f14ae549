"""Long runs stay on the holonomic constraints g = 0 with every method, or say that
they do not (``numeric.drift``).

scipy's one-step methods (RK23, RK45, DOP853, Radau) project every step as jetnh's loops
do (``scipy_backend``, ``methods.projection``); before, a Cartesian pendulum over 200 s
(about 90 turns) at rtol 1e-8 drifted to |g| = 8.7e-8 (RK45), 2.3e-7 (DOP853), 2.0e-6
(RK23), 3.6e-9 (Radau), silently, and a Kane four-bar over 34 turns to 4.1e-8 (DOP853).  BDF and LSODA (multistep) and the discrete
integrators dla and dvi (whose symmetry, symplecticity a projection would break) do not
project: their drift is reported by a JetnhWarning (before: silent).  Second routes: the
pendulum in its angle (no constraint) solved tightly, the closed form g = x^2 + y^2 -
1 on the rows, and the drift of dla and dvi shrinking as h^2 (g enters them as D g at
the midpoints: O(h^3) a step); exact (rounding) where g is quadratic.
"""

from __future__ import annotations

import functools
import warnings

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st

import jetnh as jn
import jetnh.strategies as jst
from jetnh.errors import JetnhWarning
from jetnh.numeric import Scene, drift

from holonomic_systems import (FOURBAR, KNIFE, kane_fourbar, knife_slider, pendulum_angle,
                               pendulum_xy)

PARAMS = {"l": 1.0, "G": 9.81}
T1 = 200.0
START = {"x": 0.6, "y": -0.8, "x_t": 2.0}


@pytest.fixture(scope="module")
def pendulum():
    return Scene(pendulum_xy(), params=PARAMS, initial=START, t_span=(0.0, T1))


@functools.cache
def angle_end(t1):
    """x, y at t1 of the pendulum in its angle, solved tightly (no constraint)."""
    th0 = np.arcsin(0.6)
    tr = Scene(pendulum_angle(), params=PARAMS, initial={"th": th0, "th_t": 2.0 / 0.8},
               t_span=(0.0, t1)).run(rtol=1e-13, atol=1e-14, save="final")
    return np.sin(tr["th"][-1]), -np.cos(tr["th"][-1])


def g(x, y):
    return np.abs(x**2 + y**2 - 1.0)


def quiet(run):
    """``run()`` with every JetnhWarning an error (a projected run reports nothing)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", JetnhWarning)
        return run()


@pytest.mark.parametrize("method, tol, t1, err", [("scipy-RK45", 1e-8, T1, 1e-4),
                                                  ("scipy-DOP853", 1e-8, T1, 1e-4),
                                                  ("scipy-RK23", 1e-6, T1 / 2, 1e-2),
                                                  ("scipy-Radau", 1e-6, T1 / 4, 1e-3)])
def test_scipy_one_step_methods_project_every_step(pendulum, method, tol, t1, err):
    tr = quiet(lambda: pendulum.run(method=method, rtol=tol, atol=tol * 1e-2,
                                    t_span=(0.0, t1)))
    assert tr.status == 0 and len(tr.t) > 1000
    assert g(tr["x"], tr["y"]).max() < 1e-14                 # was 3.6e-9 .. 2.0e-6
    assert tr.diagnostics.holonomic_residual_max < 1e-14
    # the motion itself: the angle form's, to the method's global error over the turns
    x1, y1 = angle_end(t1)
    assert abs(tr["x"][-1] - x1) < err and abs(tr["y"][-1] - y1) < err
    # rows of the dense output (t_eval, events, a terminal event's row) projected too
    x = pendulum.system.J.q[0]
    te = np.linspace(0.0, 50.0, 201)
    tr = quiet(lambda: pendulum.run(method=method, rtol=tol, atol=tol * 1e-2, t_eval=te,
                                    t_span=(0.0, 50.0), events=[x, jn.numeric.Event(
                                        x - 0.5, terminal=9)]))
    assert tr.status == 5 and len(tr.t_events[0]) > 5 and len(tr.t_events[1]) == 9
    assert g(tr["x"], tr["y"]).max() < 1e-14
    for ev in tr.y_events:
        assert g(ev[:, 0], ev[:, 1]).max() < 1e-14


@pytest.mark.parametrize("method", ["scipy-BDF", "scipy-LSODA"])
def test_scipy_multistep_methods_report_their_drift(pendulum, method):
    with pytest.warns(JetnhWarning, match=rf"{method}: the run left the holonomic "
                      r"constraints g = 0 by up to \|g\| = .*multistep"):
        tr = pendulum.run(method=method, rtol=1e-6, atol=1e-8, t_span=(0.0, 50.0))
    hmax = tr.diagnostics.holonomic_residual_max
    assert hmax == pytest.approx(g(tr["x"], tr["y"]).max(), rel=1e-9)   # the rows as run
    assert hmax > 1e3 * drift.DRIFT


def _vakonomic(scene):
    lam = {f"lambda_{d.name}": 0.0 for d in scene.system.dependent}
    return Scene(scene.system, "vakonomic", params=dict(scene.params),
                 initial={**scene.initial, **lam}, t_span=scene.t_span)


@pytest.mark.parametrize("method", ["dla", "dvi"])
def test_discrete_integrators_are_exact_on_a_quadratic_g(pendulum, method):
    """g = x^2 + y^2 - 1: D g at the midpoint is g(q_k+1) - g(q_k) exactly, so the
    nodes stay on g = 0 to rounding and nothing is reported."""
    sc = pendulum if method == "dla" else _vakonomic(pendulum)
    tr = quiet(lambda: sc.run(method=method, h=0.02))
    assert tr.status == 0
    assert g(tr["x"], tr["y"]).max() < 1e-13


@pytest.fixture(scope="module")
def knife():
    th0 = 0.3
    return Scene(knife_slider(), params=KNIFE, initial={
        "x": 0.0, "y": 0.0, "th": th0, "z": KNIFE["a"] * np.sin(th0), "x_t": 1.0,
        "th_t": 2.0}, t_span=(0.0, 20.0))


@pytest.mark.parametrize("method", ["dla", "dvi"])
def test_discrete_integrators_report_their_drift_which_shrinks_as_h2(knife, method):
    """g = z - a sin(th) (not quadratic): the nodes drift by O(h^2), reported, not
    projected; halving h quarters it."""
    sc = knife if method == "dla" else _vakonomic(knife)
    drifts = []
    for h in (0.02, 0.01):
        with pytest.warns(JetnhWarning, match=rf"{method}: the run left the holonomic "
                          r"constraints.*midpoint only"):
            tr = sc.run(method=method, h=h)
        assert tr.status == 0
        res = tr["z"] - KNIFE["a"] * np.sin(tr["th"])
        assert tr.diagnostics.holonomic_residual_max == pytest.approx(
            np.abs(res).max(), rel=1e-6)
        drifts.append(np.abs(res).max())
    assert 3.0 < drifts[0] / drifts[1] < 5.0, drifts


def test_dla_with_projection_moves_its_nodes_onto_g(knife):
    """dla's projection=True (no longer symmetric: its velocities are projected) moves
    every node onto g = 0 first: |g| at rounding, nothing reported, and the motion is
    dop853's to the method's O(h^2) error, as the unprojected run's is."""
    tr = quiet(lambda: knife.run(method="dla", h=0.01, projection=True))
    assert tr.status == 0
    assert np.abs(tr["z"] - KNIFE["a"] * np.sin(tr["th"])).max() < 1e-15     # 8.7e-6 without
    ref = knife.run(rtol=1e-12, atol=1e-14, t_eval=tr.t)
    for name in ("x", "y", "th", "z"):                    # (2.0e-4; unprojected 2.5e-4)
        assert np.abs(tr[name] - ref[name]).max() < 1e-3


def test_fourbar_with_scipy_closes_the_loop_over_many_turns():
    """Two loop-closure constraints (Kane's four-bar), about 20 turns of the crank."""
    pytest.importorskip("sympy.physics.mechanics")
    sc = Scene(kane_fourbar(), "chetaev", params=FOURBAR,
               initial={"q1": 1.2, "q2": 0.3, "q3": -1.5, "q1_t": 2.0}, complete=True,
               t_span=(0.0, 60.0))
    tr = quiet(lambda: sc.run(method="scipy-DOP853", rtol=1e-8, atol=1e-10))
    names = sc.state_names
    q1, q2, q3 = (tr.y[:, names.index(n)] for n in ("q1", "q2", "q3"))
    closure = np.hypot(np.cos(q1) + 3 * np.cos(q2) + 2 * np.cos(q3) - 3,
                       np.sin(q1) + 3 * np.sin(q2) + 2 * np.sin(q3))
    assert closure.max() < 1e-13
    assert np.ptp(q1) > 2 * np.pi * 10


@settings(max_examples=3, deadline=None)
@given(st.data())
def test_random_graph_constraint_stays_on_g_or_reports(data):
    """Property: q_n = P(q_1..q_n-1) + sin(q_1)/4 (P a random quadratic) on a random
    system with a confining potential, 20 time units: scipy's RK45 and DOP853 stay on
    g = 0 to rounding; LSODA and dla warn exactly when their rows leave g = 0 by more
    than ``drift.DRIFT``, and the diagnostics hold the figure."""
    J = data.draw(jst.jet_spaces(min_n=2, max_n=3))
    rest = jn.JetSpace([q.name for q in J.q[:-1]])
    back = {sp.Symbol(q.name): q for q in J.q[:-1]}
    P = data.draw(jst.polynomials(rest, order=0, max_degree=2, with_time=False)
                  ).xreplace(back) + sp.sin(J.q[0]) / 4
    V = 4 * sum(q**2 for q in J.q) + data.draw(jst.polynomials(
        J, order=0, max_degree=2, with_time=False))
    L = sum(v**2 for v in J.qd) / 2 - V
    system = jn.System(J, L, [J.q[-1] - P])
    values = data.draw(st.lists(st.floats(-0.5, 0.5), min_size=2 * J.n - 2,
                                max_size=2 * J.n - 2))
    initial = {q.name: v for q, v in zip(J.q[:-1], values)}
    initial[J.q[-1].name] = float(P.xreplace({q: initial[q.name] for q in J.q[:-1]}))
    initial.update({v.name: w for v, w in zip(J.qd[:-1], values[J.n - 1:])})
    sc = Scene(system, initial=initial, t_span=(0.0, 20.0))
    on_g = sp.lambdify(list(J.q), J.q[-1] - P, "numpy")

    def residual(tr):
        return np.abs(on_g(*(tr[q.name] for q in J.q)))

    for method in ("scipy-RK45", "scipy-DOP853"):
        tr = quiet(lambda: sc.run(method=method, rtol=1e-8, atol=1e-10))
        scale = max(1.0, np.abs(tr.y[:, :J.n]).max())
        assert tr.status == 0 and residual(tr).max() <= 8 * np.finfo(float).eps * scale
    for method, kw in (("scipy-LSODA", dict(rtol=1e-6, atol=1e-8)), ("dla", dict(h=0.01))):
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always", JetnhWarning)
            tr = sc.run(method=method, **kw)
        scale = max(1.0, np.abs(tr.y[:, :J.n]).max())
        hmax = tr.diagnostics.holonomic_residual_max
        assert hmax == pytest.approx(residual(tr).max(), rel=1e-6, abs=1e-15)
        reported = any("left the holonomic" in str(w.message) for w in seen)
        assert reported == (hmax > drift.DRIFT * scale)


def test_scipy_sensitivities_are_projected_with_the_state():
    """A scipy run with sensitivities: S of the coordinates on the tangent of g = 0
    (G S_q = 0 after the start, G = (0, 0, -a cos th, 1)) and, second route, the
    sensitivities of jetnh's projected dop853 at the end."""
    ini = {"x": 0.1, "y": -0.2, "th": 0.3, "z": KNIFE["a"] * np.sin(0.3), "x_t": 1.0,
           "th_t": 0.7}
    sc = Scene(knife_slider(), "chetaev", params=KNIFE, initial=ini, t_span=(0.0, 1.5),
               runtime_params=["k"])
    tr = quiet(lambda: sc.run(method="scipy-DOP853", sensitivities=True, rtol=1e-11,
                              atol=1e-13))
    names = sc.state_names
    S = tr.sensitivities
    GS = -KNIFE["a"] * np.cos(tr["th"])[:, None] * S[:, names.index("th")] \
        + S[:, names.index("z")]
    assert np.max(np.abs(GS[1:])) < 1e-13 * max(1.0, np.max(np.abs(S)))
    assert np.max(np.abs(tr["z"] - KNIFE["a"] * np.sin(tr["th"]))) < 1e-15
    # (the columns of th and z alone leave g = 0 at t0, and how much of that the first
    # projection keeps depends on the first step: compared along g = 0 only)
    R = sc.run(method="dop853", sensitivities=True, split="fixed", rtol=1e-12,
               atol=1e-14).sensitivities[-1]
    col = {c: i for i, c in enumerate(tr.sensitivity_columns)}
    off = [col["th"], col["z"]]
    keep = [i for i in range(S.shape[2]) if i not in off]
    assert np.allclose(S[-1][:, keep], R[:, keep], rtol=0, atol=1e-8)
    along = KNIFE["a"] * np.cos(ini["th"])
    assert np.allclose(S[-1][:, off[0]] + along * S[-1][:, off[1]],
                       R[:, off[0]] + along * R[:, off[1]], rtol=0, atol=1e-8)
