"""Connect's verdicts are those of the motion it returns, for every principle.

The nonholonomic particle L = (xdot^2 + ydot^2 + zdot^2) / 2 - k (x^2 + y^2) / 2 with
zdot = y xdot (z dependent).  Its Chetaev equations by hand (Lagrange-d'Alembert with
df/dqdot = (-y, 0, 1)): xddot + k x = -lambda y, yddot + k y = 0, zddot = lambda, and
the constraint's rate zddot = ydot xdot + y xddot, so (1 + y^2) xddot = -k x - y xdot
ydot, yddot = -k y.

- k = -1 (an inverted well): the runs grow like e^t, the span is long, connect shoots
  on segments.  The cost must be the quadrature of L along the returned trajectory, and
  that trajectory must reach the end (stitched segments where a single run's growth is
  past ``POLISH_GROWTH``), not a re-integration that leaves it.
- k = 1, from the origin: y = y_t sin t, so d y(t) / d(x_t, y_t) = (0, sin t) and the
  endpoint map (x_t, y_t) -> (x, y)(t) is singular at t = pi whatever the motion
  (closed form); its other singular times from central differences of the hand-written
  equations above, integrated by scipy (an independent route).
- Heisenberg, L = m (xdot^2 + ydot^2) / 2, zdot = x ydot - y xdot: in the independent
  velocities (xdot, ydot) the Hessian of L on the admissible ones is m I (L has no
  zdot), so ``legendre`` (its smallest eigenvalue scaled to a unit diagonal) is 1 for
  m > 0 and -1 for m < 0, where the extremal is a maximizer, no minimizer.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import simpson, solve_ivp
from scipy.optimize import brentq

import jetnh as jn
from jetnh.models import get
from jetnh.numeric.connect.solve import POLISH_GROWTH

O = {"x": 0.0, "y": 0.0, "z": 0.0}
END = {"x": 1.0, "y": 0.5}


def _particle():
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xt, yt, zt = J.qd
    k = sp.Symbol("k")
    return jn.System(J, (xt**2 + yt**2 + zt**2) / 2 - k * (x**2 + y**2) / 2,
                     [zt - y * xt], dependent=[z])


PARTICLE = _particle()


@pytest.mark.parametrize("T", [12.0, 20.0, 40.0])
def test_chetaev_cost_is_the_action_along_the_motion_returned(T):
    c = jn.connect(PARTICLE, "chetaev", O, END, (0.0, T), params={"k": -1.0})
    tr = c.trajectory
    n = tr.layout.n_state
    at_end = dict(zip(tr.scene.state_names, tr.y[-1]))
    assert max(abs(at_end[q] - v) for q, v in END.items()) < 1e-9
    if abs(tr.sensitivities[-1][:, :n]).max() > POLISH_GROWTH:
        assert "stitched" in c.route
    ts = np.linspace(0.0, T, 40001)
    d = tr.at(ts)
    X, Y, Xt, Yt = (d[k].to_numpy() for k in ("x", "y", "x_t", "y_t"))
    quad = simpson((Xt**2 + Yt**2 + (Y * Xt)**2) / 2 + (X**2 + Y**2) / 2, x=ts)
    assert abs(c.cost - quad) < 1e-8
    assert abs(c.cost - 0.65394454) < 1e-6   # the same motion, however long the span


def _hand_chetaev(k):
    def rhs(t, s):
        x, y, xt, yt = s
        return [xt, yt, (-k * x - y * xt * yt) / (1 + y * y), -k * y]
    return rhs


def test_chetaev_conjugate_times_are_where_the_endpoint_map_is_singular():
    T = 4.0
    c = jn.connect(PARTICLE, "chetaev", O, END, (0.0, T), params={"k": 1.0})
    times = c.conjugate_times
    assert len(times) == 2
    assert abs(times[0] - math.pi) < 1e-9                  # y(t) = y_t sin t
    u = np.array([c.initial["x_t"], c.initial["y_t"]])
    rhs, h = _hand_chetaev(1.0), 1e-5

    def det(t):
        cols = []
        for j in range(2):
            e = np.zeros(2)
            e[j] = h
            ends = [solve_ivp(rhs, (0.0, t), [0.0, 0.0, *(u + s * e)], rtol=1e-12,
                              atol=1e-13, method="DOP853").y[:2, -1] for s in (1, -1)]
            cols.append((ends[0] - ends[1]) / (2 * h))
        return cols[0][0] * cols[1][1] - cols[0][1] * cols[1][0]

    grid = np.linspace(0.5, T, 36)
    d = np.array([det(t) for t in grid])
    signs = np.nonzero(np.sign(d[1:]) != np.sign(d[:-1]))[0]
    roots = [brentq(det, grid[i], grid[i + 1], xtol=1e-10) for i in signs]
    assert len(roots) == 2
    assert np.allclose(times, roots, atol=1e-6), (times, roots)
    assert c.minimizer is None and c.legendre is None      # no extremal of an action


def test_chetaev_short_span_has_no_singular_time_and_says_what_it_checked():
    c = jn.connect(PARTICLE, "chetaev", O, END, (0.0, 2.0), params={"k": 1.0})
    assert c.conjugate_times == ()                      # checked: t = pi lies beyond
    assert "conjugate_times=()" in repr(c)


@pytest.mark.parametrize("m", [1.0, 2.0, -1.0])
def test_legendre_condition_of_heisenberg_geodesics(m):
    c = jn.connect(get("heisenberg"), "vakonomic", O, {"x": 1.0, "y": 0.5, "z": 0.2},
                   (0.0, 1.0), params={"m": m})
    if m > 0:
        assert c.minimizer is True
        assert abs(c.legendre - 1.0) < 1e-12
    else:
        assert c.cost < 0 and c.conjugate_times == ()
        assert c.minimizer is False                     # a maximizer of the action
        assert "not a minimizer" in repr(c)
        assert abs(c.legendre + 1.0) < 1e-12


def test_restarts_name_legendre_where_it_fails():
    """m = -1: every extremal is a maximizer (legendre = -1, no conjugate time); the
    least-action search says Legendre's condition failed, not conjugate times."""
    c = jn.connect(get("heisenberg"), "vakonomic", O, {"x": 1.0, "y": 0.5, "z": 0.2},
                   (0.0, 1.0), params={"m": -1.0}, restarts=2)
    assert c.minimizer is False and c.conjugate_times == ()
    assert c.search.startswith("2 restarts from the first answer, which is no "
                               "minimizer: Legendre's condition fails (legendre = -1)")
    assert "conjugate" not in c.search and "(Legendre fails)" in c.search
    assert "Legendre's condition fails on every one" in c.search
    assert "more restarts" not in c.search          # more would not help


def test_samples_are_the_motion_returned_whichever_way_they_are_taken():
    """A run with t_eval is used only where it ends on the trajectory bit for bit (the
    same steps): a run with another tolerance is refused, and the dense output (the
    steps re-taken) gives the same bits."""
    from jetnh.numeric.connect.verdicts import _rerun, _Samples

    c = jn.connect(PARTICLE, "chetaev", O, END, (0.0, 12.0), params={"k": -1.0})
    tr, run = c.trajectory, dict(c._run)
    assert _rerun(tr, np.array([0.0, 12.0]), run) is not None
    assert _rerun(tr, np.array([0.0, 12.0]), {**run, "rtol": 1e-6}) is None
    fast, dense = _Samples(tr, run), _Samples(tr)
    for name in ("gauss_y", "grid_y", "grid_S"):
        assert np.array_equal(getattr(fast, name), getattr(dense, name))


def test_suslov_singular_times_against_central_differences_of_plain_runs():
    """Suslov's motions (other equations than Chetaev's): the singular times of the
    endpoint map against central differences of plain runs (no sensitivities)."""
    c = jn.connect(PARTICLE, "suslov", O, END, (0.0, 4.0), params={"k": 1.0})
    sc, y0 = c.trajectory.scene, c.trajectory.y[0]
    ts, h = np.linspace(0.5, 4.0, 351), 1e-6
    cols = []
    for name in ("x_t", "y_t"):
        e = np.zeros_like(y0)
        e[sc.state_names.index(name)] = h
        r = [sc.run(y0=y0 + s * e, t_eval=ts, rtol=1e-12, atol=1e-13) for s in (1, -1)]
        cols.append([(np.asarray(r[0][q]) - np.asarray(r[1][q])) / (2 * h) for q in "xy"])
    det = cols[0][0] * cols[1][1] - cols[0][1] * cols[1][0]
    i = np.nonzero(np.sign(det[1:]) != np.sign(det[:-1]))[0]
    assert len(c.conjugate_times) == len(i) == 1
    assert ts[i[0]] <= c.conjugate_times[0] <= ts[i[0] + 1]
