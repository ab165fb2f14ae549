"""The verdicts of connect against closed forms, and the default guess moved off a
rank-deficient start by the Gauss-Newton point of its own run.

- The controllability Gramian of the Heisenberg constraint system (zdot = x ydot - y
  xdot) along the straight line x = t, y = z = 0: A = d qdot/dq has the one entry
  dz'/dy = -x' = -1, B = d qdot/du the rows (1, 0), (0, 1), (-y, x) = (0, t), so
  Phi(T, s) B(s) = ((1, 0), (0, 1), (0, 2 s - T)) and W = diag(T, T, T^3 / 3): scaled
  to a unit diagonal (``gramian_ratio`` has no units), the identity, ratio 1.
- Conjugate times on a long unstable span: the Heisenberg constraint with the inverted
  potential a^2 x^2 / 2 in x alone, L = (xdot^2 + ydot^2 + a^2 x^2) / 2.  Its vakonomic
  equations are linear for the constant multiplier lambda (xddot = a^2 x - 2 lambda ydot,
  yddot = 2 lambda xdot), the sensitivities grow like e^{a T}.  The second variation
  of the composite action, int |delta v|^2 + a^2 delta x^2 - 2 lambda (delta x delta
  y' - delta y delta x') dt, is 4 lambda int delta x delta y' dt in its last term
  (integrating by parts with fixed ends), at most (2 |lambda| / a) int (a^2 delta x^2 +
  delta y'^2) dt, so it is positive for every admissible variation where 2 |lambda| <
  a: no conjugate time, however long the span.  The Heisenberg geodesics (a = 0) have
  their first at 2 pi / |omega| (omega = 2 lambda, the circles close).
- The rolling disk (x' = R phi' cos psi, y' = R phi' sin psi) from rest: the guess's
  shooting Jacobian dq(T)/d(phi', psi') = ((R T, 0), (0, 0)) has rank 1, and its
  minimum-norm Gauss-Newton point rolls straight to x = x1: phi' = x1 / (R T).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import assume, given
from hypothesis import strategies as st
from scipy.linalg import expm

import jetnh as jn
from jetnh.models import get
from jetnh.numeric.connect.problem import _scene
from jetnh.numeric.connect.solve import Search
from jetnh.numeric.connect.verdicts import jacobi_measure

O = {"x": 0.0, "y": 0.0, "z": 0.0}


@pytest.mark.parametrize("T", [1.0, 2.0, 3.0])
def test_gramian_of_the_heisenberg_straight_line(T):
    c = jn.connect(get("heisenberg"), "vakonomic", {"x": 0.0, "y": 0.0, "z": 0.0},
                   {"x": T, "y": 0.0, "z": 0.0}, (0.0, T))
    assert abs(c.initial["x_t"] - 1.0) < 1e-9 and abs(c.initial["y_t"]) < 1e-9
    assert abs(c.gramian_ratio - 1.0) < 1e-9     # diagonal: no correlation
    assert c.normal
    assert abs(c.cost - T / 2) < 1e-10          # L = (x'^2 + y'^2) / 2 along x = t


def test_samples_of_a_chetaev_answer_are_its_own_dense_output():
    """The verdicts' samples of a Chetaev answer (whose Jacobi fields are not square)
    are the trajectory's own states and sensitivities, not those of a new run."""
    zero = {"x": 0.0, "y": 0.0, "phi": 0.0, "psi": 0.0}
    c = jn.connect(get("rolling_disk"), "chetaev", zero, {"x": 0.5, "y": 0.3}, (0.0, 1.0))
    smp = c._samples
    tr = c.trajectory
    S = smp.grid_S
    assert S.shape == (smp.GRID + 1,) + tr.sensitivities.shape[1:]
    assert np.array_equal(S[-1], tr.sensitivities[-1])
    assert np.array_equal(smp.grid_y[-1], tr.y[-1])
    assert np.array_equal(smp.grid_y, tr.at(smp.grid)[list(tr.scene.state_names)]
                          .to_numpy())
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
    by scipy on the trajectory's dense output, scaled to a unit diagonal, has the same
    eigenvalue ratio."""
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
    W = W.reshape(3, 3)
    d = np.sqrt(np.diag(W))
    ev = np.linalg.eigvalsh(W / np.outer(d, d))
    assert abs(c.gramian_ratio - ev[0] / ev[-1]) < 1e-7 * ev[0] / ev[-1] + 1e-10
    assert 1e-3 < c.gramian_ratio < 0.99            # curved: not the straight line's


def _one_sided(a):
    """The Heisenberg constraint with the inverted potential a^2 x^2 / 2 in x alone."""
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    s = sp.Symbol("a")
    L = (xd**2 + yd**2) / 2 + s**2 * x**2 / 2
    return jn.System(J, L, [zd - (x * yd - y * xd)], [z], defaults={s: a})


@pytest.mark.parametrize("T", [14.0, 16.0])
def test_long_unstable_span_without_conjugate_time(T):
    """Sensitivities ~ 1e9 (T = 14, multiple shooting polished by single shooting) and
    ~ 3e10 (T = 16, stitched): dq/du keeps its rank (the bound above), so no conjugate
    time -- not even t1, where the smallest singular value of dq/du is ~ 1e-10 of the
    largest (and ~ 1e-8 with its columns scaled to unit length)."""
    a = 2.0
    end = {"x": 1.0, "y": 0.5, "z": 0.3}
    c = jn.connect(_one_sided(a), "vakonomic", O, end, (0.0, T))
    assert c.residual < 1e-8
    lam = c.initial["lambda_z"]
    assert 2 * abs(lam) < a                     # the bound's condition
    # the motion is the linear flow's (closed form, an independent route)
    M = np.array([[0, 0, 1, 0], [0, 0, 0, 1], [a * a, 0, 0, -2 * lam],
                  [0, 0, 2 * lam, 0]])
    xy = expm(M * T) @ np.array([0.0, 0.0, c.initial["x_t"], c.initial["y_t"]])
    assert np.max(np.abs(xy[:2] - [1.0, 0.5])) < 1e-3
    S = c.trajectory.sensitivities[-1][:3][:, list(c._columns)]
    s = np.linalg.svd(S, compute_uv=False)
    assert s[0] > 1e8 and s[-1] < 1e-9 * s[0]        # huge, and badly scaled
    assert c.conjugate_times == ()
    assert c.normal


@pytest.mark.parametrize("T, first", [(0.55, False), (0.7, True)])
def test_heisenberg_first_conjugate_time(T, first):
    """A geodesic of angular rate omega = 2 pi / 0.6 to its end at T: conjugate-free
    before 2 pi / omega = 0.6, its first conjugate time there (closed form) after."""
    from test_connect import heisenberg_end

    v, theta, omega = 1.0, 0.3, 2 * math.pi / 0.6
    end = dict(zip("xyz", heisenberg_end(v, theta, omega, T)))
    c = jn.connect(get("heisenberg"), "vakonomic", O, end, (0.0, T),
                   guess={"x_t": 0.9 * v * math.cos(theta), "y_t": v * math.sin(theta),
                          "lambda_z": 0.95 * omega / 2})
    assert abs(c.initial["lambda_z"] - omega / 2) < 1e-8
    if first:
        assert len(c.conjugate_times) == 1
        assert abs(c.conjugate_times[0] - 2 * math.pi / omega) < 1e-9
    else:
        assert c.conjugate_times == ()


_entries = st.floats(-1.0, 1.0, allow_nan=False, allow_infinity=False)


@given(st.integers(1, 4).flatmap(lambda n: st.tuples(
    st.just(n), st.lists(_entries, min_size=2 * n * n, max_size=2 * n * n),
    st.lists(st.integers(-12, 12), min_size=n, max_size=n),
    st.lists(st.booleans(), min_size=n, max_size=n))))
def test_jacobi_measure_is_free_of_the_unknowns_scale(data):
    """Rescaling the unknowns (columns by +-1e-12 ... 1e12) leaves the measures as they
    were (the determinant's sign follows det C); the scaled determinant has the sign of
    det dq/du; both lie in [0, 1] in magnitude; a field that vanishes in the
    configuration makes both zero."""
    n, x, k, flip = data
    X = np.array(x).reshape(2 * n, n) + np.vstack([np.eye(n), np.zeros((n, n))])
    assume(np.linalg.cond(X) < 1e6 and np.linalg.cond(X[:n]) < 1e6)
    c = 10.0 ** np.array(k) * np.where(flip, -1.0, 1.0)
    d, least = jacobi_measure(X, n)
    d2, least2 = jacobi_measure(X * c[None, :], n)
    assert abs(d2 - np.prod(np.sign(c)) * d) < 1e-9 and abs(least2 - least) < 1e-9
    assert 0.0 < least <= 1.0 + 1e-12 and 0.0 < abs(d) <= 1.0 + 1e-12
    assert np.sign(d) == np.sign(np.linalg.det(X[:n]))
    # the first field with no configuration part: singular
    Y = X.copy()
    Y[:n, 0], Y[n, 0] = 0.0, 1.0
    assume(np.linalg.cond(Y) < 1e8)
    d0, least0 = jacobi_measure(Y, n)
    assert abs(d0) < 1e-12 and least0 < 1e-12


def test_restarts_leave_a_geodesic_past_its_conjugate_point():
    """The geodesic of angular rate omega = 2 pi / 0.6 run for T = 1 passes its first
    conjugate time 0.6: no minimizer (``minimizer`` False).  With restarts the search
    keeps another geodesic to the same end -- the closed form from its initial state,
    with |omega'| T < 2 pi (no conjugate time), of action v'^2 T / 2 below the first's."""
    from test_connect import heisenberg_end

    v, theta, omega = 1.0, -0.7, 2 * math.pi / 0.6
    end = dict(zip("xyz", heisenberg_end(v, theta, omega, 1.0)))
    guess = {"x_t": 0.9 * v * math.cos(theta), "y_t": v * math.sin(theta),
             "lambda_z": 0.95 * omega / 2}
    heis = get("heisenberg")
    first = jn.connect(heis, "vakonomic", O, end, (0.0, 1.0), guess=guess)
    assert first.minimizer is False and first.search == ""
    assert abs(first.cost - v**2 / 2) < 1e-9
    c = jn.connect(heis, "vakonomic", O, end, (0.0, 1.0), guess=guess, restarts=4)
    assert c.minimizer is True and c.conjugate_times == () and c.residual < 1e-9
    # the verdict that failed is named: Jacobi's (conjugate times), not Legendre's
    assert c.search.startswith("4 restarts from the first answer, which is no "
                               "minimizer: conjugate times inside the span (t = 0.6, ")
    assert "Legendre's condition fails" not in c.search
    assert "the cheapest minimizer kept" in c.search and " (conjugate)" in c.search
    assert "restart" in c.route
    xt, yt, lam = c.initial["x_t"], c.initial["y_t"], c.initial["lambda_z"]
    v2, w2 = math.hypot(xt, yt), 2 * lam
    assert abs(w2) < 2 * math.pi
    assert np.max(np.abs(np.array(heisenberg_end(v2, math.atan2(yt, xt), w2, 1.0))
                         - [end["x"], end["y"], end["z"]])) < 1e-8
    assert abs(c.cost - v2**2 / 2) < 1e-9 and c.cost < first.cost - 0.1
    assert jn.connect(heis, "chetaev", O, {"x": 1.0}, (0.0, 1.0)).minimizer is None
    with pytest.raises(jn.JetnhError, match="restarts"):
        jn.connect(heis, "vakonomic", O, end, (0.0, 1.0), restarts=-1)


def test_direct_route_guess_is_near_the_minimizing_geodesic():
    """The direct route (the action minimised over admissible paths: x, y lines plus
    sine modes, z integrated from the constraint) to the end of the geodesic above:
    its velocities and multiplier at t0 (from SLSQP's multiplier of the z end, P_z =
    lambda_z: z is cyclic) are near the minimizing geodesic's, which shooting from them
    reaches (closed form: |omega| T < 2 pi)."""
    from test_connect import heisenberg_end

    from jetnh.numeric.connect import direct

    v, theta, omega = 1.0, -0.7, 2 * math.pi / 0.6
    end = dict(zip("xyz", heisenberg_end(v, theta, omega, 1.0)))
    heis = get("heisenberg")
    unknowns = ("x_t", "y_t", "lambda_z")
    scene = _scene(heis, "vakonomic", None, {**O, **{u: 0.0 for u in unknowns}},
                   (0.0, 1.0))
    search = Search(scene, O, end, unknowns, {}, 1e-11, 1e-12, "dop853", 1e-9)
    u = direct.guess(search)
    c = jn.connect(heis, "vakonomic", O, end, (0.0, 1.0), guess=u)
    assert c.residual < 1e-9 and c.minimizer and abs(2 * c.initial["lambda_z"]) < 2 * math.pi
    xt, yt, lam = (c.initial[k] for k in unknowns)
    assert np.max(np.abs(np.array(heisenberg_end(math.hypot(xt, yt), math.atan2(yt, xt),
                                                 2 * lam, 1.0))
                         - [end["x"], end["y"], end["z"]])) < 1e-8
    # the multiplier to 1e-3 of its size; the velocities at t0 to ~0.05 (the sine
    # series' derivative converges slowly at the ends)
    assert abs(u[2] - lam) < 1e-2 * abs(lam) and np.max(np.abs(u[:2] - [xt, yt])) < 0.1
    # a free end is not the direct route's problem
    free = Search(scene, O, {"x": 1.0, "y": 0.5}, unknowns, {}, 1e-11, 1e-12, "dop853",
                  1e-9)
    assert direct.guess(free) is None
