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
state.  The step's dense output (``t_eval``, an event's state, a stop inside a step,
``Trajectory.at``, an ensemble's rows) is the method's interpolant between two projected
states, on g = 0 only to the interpolant's error, so its rows are projected the same
way (``rows``, the same iteration on many rows at once) before anything holds them.
The iteration is deterministic: a run is reproducible bit for bit.

A run with sensitivities (the state followed by ``S = dy/d(y0, p)``, ``n_sens`` columns a
row, the runtime parameters' last) projects them with the state, by the derivative of
the projection map at the projected point: the rows of S of the coordinates become
``(I - G^+ G) S_q - G^+ dg/dp`` with ``G^+ = G^T (G G^T)^{-1}`` (the orthogonal metric
of the projection itself; the last term in the parameters' columns only, where g
depends on them), so that S is the derivative of the projected run, as central
differences of projected runs measure it.  Interpolated rows of S are projected the
same way at their projected state: the derivative of the projected run satisfies
``G S_q + dg/dp = 0`` at every time after the start (g(t, q(t; y0, p), p) = 0 along
every projected run, differentiated), which the interpolant meets only to its error;
the projection onto that tangent space moves S by that error only.  At the start the
run is its initial state itself, nothing projected, S the identity: rows there keep it.

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
#: the end of the iteration: a correction below four units in the last place
_CONVERGED = 4.0 * 2.220446049250313e-16


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
        if big <= _CONVERGED:
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
    """``rows`` of one state from Python (``hol`` the kernel's Python-callable form,
    ``kernels.hol``): a copy of ``y`` with its coordinates y[:nq] on g(t, q) = 0 (``y``
    itself where G G^T is singular or a value is not finite)."""
    p = np.ascontiguousarray(p, dtype=float)
    room = np.empty(m * (1 + nq + p.shape[0]))     # (a kernel with dg/dp writes them too)

    def hol_rows(ts, ys, p, out):
        hol(ts[0], ys[0], p, room)
        out[0] = room[:out.shape[1]]

    ys = np.array(y, dtype=float).reshape(1, -1)
    rows(hol_rows, m, nq, np.array([float(t)]), ys, p)
    return ys[0]


def rows(hol_rows, m, nq, ts, ys, p, n_sens=0):
    """The iteration of ``project`` on every row ``ys[i]`` (at ``ts[i]``) in place, the
    rows together (``hol_rows(ts, ys, p, out)``: the kernel at every row,
    ``kernels.calls.Rows``); each row's iterates depend on that row only, and a row
    where G G^T is singular or a correction is not finite is left as it is.  The dense
    output's rows (``t_eval``, events, a stop inside a step, ``Trajectory.at``) moved
    onto g = 0 as the steps are.

    ``p``: the parameters, or one row of them per row of ``ys`` (an ensemble's runs).
    ``n_sens`` > 0: each row is the state followed by its sensitivities (``n_sens``
    columns, the parameters' last; ``hol_rows`` the kernel with dg/dp), and they are
    projected with it as ``project`` does (``_sensitivities``: onto the tangent space of
    g = 0 at the projected point, ``G S_q + dg/dp = 0``)."""
    p = np.ascontiguousarray(p, dtype=float)
    n = ys.shape[1] // (1 + n_sens)
    n_p = p.shape[-1] if n_sens else 0
    at = _kernel_rows(hol_rows, p)
    left = np.arange(ys.shape[0])
    w = np.empty((ys.shape[0], m * (1 + nq + n_p)))
    for _ in range(MAX_ITERATIONS):
        if left.size == 0:
            break
        y = np.ascontiguousarray(ys[left, :n])
        out = w[:left.size]
        at(ts[left], y, left, out)
        G = out[:, m:m + m * nq].reshape(-1, m, nq)
        Gt = G.transpose(0, 2, 1)
        x, ok = _solve(G @ Gt, out[:, :m, None])
        d = (Gt @ x)[:, :, 0]
        go = ok & np.isfinite(d).all(axis=1)
        y[go, :nq] -= d[go]
        ys[left[go], :n] = y[go]
        big = np.max(np.abs(d) / np.maximum(1.0, np.abs(y[:, :nq])), axis=1)
        left = left[go & (big > _CONVERGED)]
    if n_sens and ys.shape[0]:
        _tangent(at, m, nq, n_sens, n_p, ts, ys, w)


def _tangent(at, m, nq, n_sens, n_p, ts, ys, w):
    """``_sensitivities`` of every row: S_q <- S_q - G^+ (G S_q + dg/dp) at the rows'
    (projected) states; rows where G G^T is singular keep theirs."""
    n = ys.shape[1] // (1 + n_sens)
    every = np.arange(ys.shape[0])
    at(ts, np.ascontiguousarray(ys[:, :n]), every, w)
    G = w[:, m:m + m * nq].reshape(-1, m, nq)
    Gt = G.transpose(0, 2, 1)
    S = ys[:, n:].reshape(-1, n, n_sens).copy()
    b = G @ S[:, :nq, :]
    if n_p:
        b[:, :, n_sens - n_p:] += w[:, m + m * nq:].reshape(-1, m, n_p)
    x, ok = _solve(G @ Gt, b)
    S[:, :nq] -= Gt @ x
    ys[ok, n:] = S[ok].reshape(int(ok.sum()), -1)


def _solve(A, b):
    """x with A[i] x[i] = b[i] for every row i, and whether row i was solvable (a row
    whose A is singular gets NaN)."""
    try:
        return np.linalg.solve(A, b), np.ones(A.shape[0], dtype=bool)
    except np.linalg.LinAlgError:
        x, ok = np.full(b.shape, np.nan), np.zeros(A.shape[0], dtype=bool)
        for i in range(A.shape[0]):
            try:
                x[i] = np.linalg.solve(A[i], b[i])
                ok[i] = True
            except np.linalg.LinAlgError:
                pass
        return x, ok


def _kernel_rows(hol_rows, p):
    """``at(ts, ys, which, out)``: ``hol_rows`` at the rows ``ys`` (rows ``which`` of the
    caller's, in increasing order), with the parameters ``p`` or, where ``p`` has a row
    per row, with each row's own: one call per run of equal rows (an ensemble's rows come
    run by run)."""
    if p.ndim == 2:
        run = np.concatenate([[0], np.cumsum(np.any(p[1:] != p[:-1], axis=1))])
        if run[-1] > 0:
            def at(ts, ys, which, out):
                cut = np.flatnonzero(np.diff(run[which])) + 1
                for a, b in zip([0, *cut], [*cut, which.size]):
                    hol_rows(np.ascontiguousarray(ts[a:b]), ys[a:b], p[which[a]],
                             out[a:b])
            return at
        p = p[0] if p.shape[0] else np.zeros(p.shape[1])
    return lambda ts, ys, which, out: hol_rows(np.ascontiguousarray(ts), ys, p, out)
