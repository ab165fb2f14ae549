"""The verdicts of connect against closed forms, and the default guess moved off a
rank-deficient start by the Gauss-Newton point of its own run.

- The controllability Gramian of the Heisenberg constraint system (zdot = x ydot - y
  xdot) along the straight line x = t, y = z = 0: A = d qdot/dq has the one entry
  dz'/dy = -x' = -1, B = d qdot/du the rows (1, 0), (0, 1), (-y, x) = (0, t), so
  Phi(T, s) B(s) = ((1, 0), (0, 1), (0, 2 s - T)) and W = diag(T, T, T^3 / 3).
- The rolling disk (x' = R phi' cos psi, y' = R phi' sin psi) from rest: the guess's
  shooting Jacobian dq(T)/d(phi', psi') = ((R T, 0), (0, 0)) has rank 1, and its
  minimum-norm Gauss-Newton point rolls straight to x = x1: phi' = x1 / (R T).
"""

from __future__ import annotations

import numpy as np
import pytest

import jetnh as jn
from jetnh.models import get
from jetnh.numeric.connect.problem import _scene
from jetnh.numeric.connect.solve import Search


@pytest.mark.parametrize("T", [1.0, 2.0, 3.0])
def test_gramian_of_the_heisenberg_straight_line(T):
    c = jn.connect(get("heisenberg"), "vakonomic", {"x": 0.0, "y": 0.0, "z": 0.0},
                   {"x": T, "y": 0.0, "z": 0.0}, (0.0, T))
    assert abs(c.initial["x_t"] - 1.0) < 1e-9 and abs(c.initial["y_t"]) < 1e-9
    ev = sorted([T, T, T**3 / 3])
    assert abs(c.gramian_ratio - ev[0] / ev[-1]) < 1e-9
    assert c.normal
    assert abs(c.cost - T / 2) < 1e-10          # L = (x'^2 + y'^2) / 2 along x = t


def test_samples_of_a_chetaev_answer_give_the_jacobi_fields_when_asked():
    """The sample run of a Chetaev answer carries no sensitivities (its Jacobi
    determinant is not square); asked for, they are those of the trajectory."""
    zero = {"x": 0.0, "y": 0.0, "phi": 0.0, "psi": 0.0}
    c = jn.connect(get("rolling_disk"), "chetaev", zero, {"x": 0.5, "y": 0.3}, (0.0, 1.0))
    smp = c._samples
    assert "grid_S" not in vars(smp)
    S = smp.grid_S
    assert S.shape == (smp.GRID + 1,) + c.trajectory.sensitivities.shape[1:]
    assert np.max(np.abs(S[-1] - c.trajectory.sensitivities[-1])) < 1e-9
    assert c.conjugate_times == ()


@pytest.mark.parametrize("x1, T", [(0.5, 1.0), (2.0, 0.5)])
def test_rank_deficient_guess_moves_to_its_gauss_newton_point(x1, T):
    system = get("rolling_disk")
    R = next(v for k, v in system.defaults.items() if k.name == "R")
    q0 = {"x": 0.0, "y": 0.0, "phi": 0.0, "psi": 0.0}
    q1 = {"x": x1, "y": 0.3}
    unknowns = ("phi_t", "psi_t")
    fixed = {}
    scene = _scene(system, "chetaev", None, {**q0, "phi_t": 0.0, "psi_t": 0.0}, (0.0, T))
    search = Search(scene, q0, q1, unknowns, fixed, 1e-11, 1e-12, "dop853", 1e-9)
    u = search.regular_start(np.zeros(2), q0, q1, T, 2)
    expected = min(x1 / (R * T), 1.0)         # a step of at most max(1, |u|)
    assert np.allclose(u, [expected, 0.0], atol=1e-9), u
    assert search.regular(search.endpoint(u))


def test_gramian_along_a_heisenberg_geodesic_against_the_lyapunov_equation():
    """Along a curved geodesic A(t) varies (dz'/dx = y', dz'/dy = -x'), so the order of
    the propagators matters: W(T) from W' = A W + W A^T + B B^T, W(0) = 0, integrated
    by scipy on the trajectory's dense output, has the same eigenvalue ratio."""
    from scipy.integrate import solve_ivp

    from jetnh.numeric.connect.verdicts import _dense_states

    c = jn.connect(get("heisenberg"), "vakonomic", {"x": 0.0, "y": 0.0, "z": 0.0},
                   {"x": 1.0, "y": 0.5, "z": 0.2}, (0.0, 1.0))
    tr = c.trajectory
    col = {n: i for i, n in enumerate(tr.scene.state_names)}

    def rhs(t, w):
        s = _dense_states(tr, [min(max(t, 0.0), 1.0)])[0]
        x, y, xt, yt = (s[col[k]] for k in ("x", "y", "x_t", "y_t"))
        A = np.array([[0.0, 0, 0], [0, 0, 0], [yt, -xt, 0]])
        B = np.array([[1.0, 0], [0, 1], [-y, x]])
        W = w.reshape(3, 3)
        return (A @ W + W @ A.T + B @ B.T).ravel()

    W = solve_ivp(rhs, (0.0, 1.0), np.zeros(9), rtol=1e-11, atol=1e-13).y[:, -1]
    ev = np.linalg.eigvalsh(W.reshape(3, 3))
    assert abs(c.gramian_ratio - ev[0] / ev[-1]) < 1e-7 * ev[0] / ev[-1] + 1e-10
    assert 1e-3 < c.gramian_ratio < 0.99            # curved: not the straight line's
