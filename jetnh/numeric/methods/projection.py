"""Projection of an accepted step onto the holonomic constraints g(t, q) = 0.

The equations of a system with holonomic constraints use their derivatives D g = 0
(jetnh's dependent velocities solve them exactly), so g stays constant along the exact
flow, while a numerical step changes it by its local error: unchecked, |g| grows like
the global error.  After every accepted step the coordinates are moved orthogonally back
onto g = 0 by the simplified Gauss-Newton iteration of Hairer, Lubich & Wanner,
*Geometric Numerical Integration* (2006), section IV.4 (standard projection)::

    q <- q - G^T (G G^T)^{-1} g(t, q),   G = dg/dq at the current q,

until the correction is below the spacing of the floating-point numbers (at most
``MAX_ITERATIONS``).  The correction is of the size of the local error, so the method's
order is kept (HLW IV.4, Theorem 4.2).  Velocities need no projection: the dependent
velocities are no states but phi(t, q, qdot^mu), which solves D g = 0 exactly at every
state.  The step's dense output (``t_eval``, ``Trajectory.at``) is the method's
interpolant between two projected states, on g = 0 only to the interpolant's error, so
its rows are projected the same way (``rows``) before a trajectory holds them (a run
with sensitivities keeps its interpolated rows: their S would need the projection's
derivative too).  The iteration is deterministic: a run is reproducible bit for bit.

A run with sensitivities (the state followed by ``S = dy/d(y0, p)``, ``n_sens`` columns a
row, the runtime parameters' last) projects them with the state, by the derivative of
the projection map at the projected point: the rows of S of the coordinates become
``(I - G^+ G) S_q - G^+ dg/dp`` with ``G^+ = G^T (G G^T)^{-1}`` (the orthogonal metric
of the projection itself; the last term in the parameters' columns only, where g
depends on them), so that S is the derivative of the projected run, as central
differences of projected runs measure it.

``hol(t, y, p, out)`` is the generated kernel (``codegen``): ``out = (g_1..g_m, dg_i/dq^j
row by row)``, and for a run with sensitivities then ``dg_i/dp_k`` row by row (the
kernels of the "sensitivities" variant).
"""

from __future__ import annotations

import math

import numpy as np

from ._common import jit, solve_linear

#: Gauss-Newton iterations per step (one or two suffice: the start is within the local
#: error of g = 0)
MAX_ITERATIONS = 8


@jit
def workspace(m, nq, n_sens):
    """The arrays of ``project``: hol's output (with dg/dp where there are
    sensitivities: ``n_sens`` columns, the parameters among them), G G^T, a right-hand
    side and a solution of it."""
    m1 = max(m, 1)
    return (np.empty(m1 * (1 + nq + n_sens)), np.empty((m1, m1)), np.empty(m1),
            np.empty(m1))


@jit
def _normal(w, m, nq, A):
    """A = G G^T from hol's output ``w``."""
    for i in range(m):
        for k in range(m):
            acc = 0.0
            for j in range(nq):
                acc += w[m + i * nq + j] * w[m + k * nq + j]
            A[i, k] = acc


@jit
def project(hol, ctl, t, y, p, ws):
    """Move the coordinates y[:nq] onto g(t, q) = 0 (module docstring; ``ctl`` the run's
    ``loop.Control``: ``n_hol`` constraints, ``n_coord`` coordinates, ``n_sens``
    sensitivity columns); returns the number of ``hol`` evaluations.  Leaves y as it is
    where G G^T is singular or a value is not finite (the position-level residual in
    the diagnostics then shows it)."""
    m, nq, n_sens = ctl.n_hol, ctl.n_coord, ctl.n_sens
    w, A, b, x = ws
    calls = 0
    for _ in range(MAX_ITERATIONS):
        hol(t, y, p, w)
        calls += 1
        _normal(w, m, nq, A)
        for i in range(m):
            b[i] = w[i]
        if not solve_linear(A, b, x):       # (G G^T) x = g
            return calls
        big = 0.0
        for j in range(nq):
            d = 0.0
            for i in range(m):
                d += w[m + i * nq + j] * x[i]
            if not math.isfinite(d):
                return calls
            y[j] -= d
            big = max(big, abs(d) / max(1.0, abs(y[j])))
        if big <= 4.0 * 2.220446049250313e-16:
            break
    if n_sens > 0:
        hol(t, y, p, w)
        calls += 1
        _sensitivities(w, m, nq, n_sens, p.shape[0], y, A, b, x)
    return calls


@jit
def _sensitivities(w, m, nq, n_sens, n_p, y, A, b, x):
    """S_q <- S_q - G^T (G G^T)^{-1} (G S_q + dg/dp), column by column, for the
    sensitivities stored after the state in ``y`` (row-major, ``n_sens`` columns, the
    ``n_p`` parameters' last; G and dg/dp from ``w``)."""
    n = y.shape[0] // (1 + n_sens)
    first_p = n_sens - n_p
    for k in range(n_sens):
        for i in range(m):
            acc = 0.0
            for j in range(nq):
                acc += w[m + i * nq + j] * y[n + j * n_sens + k]
            if k >= first_p:
                acc += w[m + m * nq + i * n_p + k - first_p]
            b[i] = acc
        _normal(w, m, nq, A)
        if not solve_linear(A, b, x):
            return
        for j in range(nq):
            d = 0.0
            for i in range(m):
                d += w[m + i * nq + j] * x[i]
            y[n + j * n_sens + k] -= d


def onto(hol, m, nq, t, y, p) -> np.ndarray:
    """``project`` of one state from Python (``hol`` the kernel's Python-callable form,
    ``kernels.hol``): a copy of ``y`` with its coordinates y[:nq] on g(t, q) = 0 (``y``
    itself where G G^T is singular or a value is not finite)."""
    y = np.array(y, dtype=float)
    p = np.ascontiguousarray(p, dtype=float)
    w = np.empty(m * (1 + nq + p.shape[0]))       # (room for dg/dp)
    for _ in range(MAX_ITERATIONS):
        hol(float(t), y, p, w)
        G = w[m:m + m * nq].reshape(m, nq)
        try:
            d = G.T @ np.linalg.solve(G @ G.T, w[:m])
        except np.linalg.LinAlgError:
            return y
        if not np.all(np.isfinite(d)):
            return y
        y[:nq] -= d
        if np.max(np.abs(d) / np.maximum(1.0, np.abs(y[:nq]))) <= 4.0 * 2.220446049250313e-16:
            break
    return y


def rows(hol_rows, m, nq, ts, ys, p):
    """The iteration of ``onto`` on every row ``ys[i]`` (at ``ts[i]``) in place, the rows
    together (``hol_rows(ts, ys, p, out)``: the kernel at every row, ``kernels.calls.Rows``);
    each row's iterates depend on that row only.  The dense output's rows moved onto
    g = 0 as the steps are."""
    p = np.ascontiguousarray(p, dtype=float)
    left = np.arange(ys.shape[0])
    w = np.empty((ys.shape[0], m * (1 + nq)))
    for _ in range(MAX_ITERATIONS):
        if left.size == 0:
            return
        y = np.ascontiguousarray(ys[left])
        out = w[:left.size]
        hol_rows(np.ascontiguousarray(ts[left]), y, p, out)
        G = out[:, m:].reshape(-1, m, nq)
        Gt = G.transpose(0, 2, 1)
        try:
            d = (Gt @ np.linalg.solve(G @ Gt, out[:, :m, None]))[:, :, 0]
        except np.linalg.LinAlgError:   # G G^T singular at some row: each row alone (a
            if left.size > 1:            # singular one is left as it is, as in ``onto``)
                for i in left:
                    rows(hol_rows, m, nq, ts[i:i + 1], ys[i:i + 1], p)
            return
        go = np.isfinite(d).all(axis=1)   # (rows with a non-finite correction are left)
        y[go, :nq] -= d[go]
        ys[left[go]] = y[go]
        big = np.max(np.abs(d) / np.maximum(1.0, np.abs(y[:, :nq])), axis=1)
        left = left[go & (big > 4.0 * 2.220446049250313e-16)]
