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
way before anything holds them (``rows``: ``onto`` at each row, the step's own
compiled iteration, so a row is moved exactly as a step ending there would be).  The
iteration is deterministic: a run is reproducible bit for bit.

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

from ._common import compiled, f8, function_at, i8, jit, solve_linear

#: Gauss-Newton iterations per step (one or two suffice: the start is within the local
#: error of g = 0)
MAX_ITERATIONS = 8
#: the end of the iteration: a correction below four units in the last place
_CONVERGED = 4.0 * 2.220446049250313e-16


@jit
def workspace(m, nq, n_sens):
    """The arrays of ``onto``: hol's output (with dg/dp where there are sensitivities:
    ``n_sens`` columns, the parameters among them), G G^T, a right-hand side, a
    solution of it and a correction of the coordinates."""
    m1 = max(m, 1)
    return (np.empty(m1 * (1 + nq + n_sens)), np.empty((m1, m1)), np.empty(m1),
            np.empty(m1), np.empty(max(nq, 1)))


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
    """``onto`` for a step of a compiled loop (``ctl`` the run's ``loop.Control``:
    ``n_hol`` constraints, ``n_coord`` coordinates, ``n_sens`` sensitivity columns)."""
    return onto(hol, ctl.n_hol, ctl.n_coord, ctl.n_sens, t, y, p, ws)


@jit
def onto(hol, m, nq, n_sens, t, y, p, ws):
    """Move the coordinates y[:nq] onto the ``m`` constraints g(t, q) = 0 (module
    docstring), and with ``n_sens`` > 0 the sensitivities stored after the state onto
    the tangent of g = 0 there; returns the number of ``hol`` evaluations.  Leaves y
    as the last complete iterate where G G^T is singular or a correction is not finite
    (the position-level residual in the diagnostics then shows it)."""
    w, A, b, x, d = ws
    calls = 0
    for _ in range(MAX_ITERATIONS):
        hol(t, y, p, w)
        calls += 1
        _normal(w, m, nq, A)
        for i in range(m):
            b[i] = w[i]
        if not solve_linear(A, b, x):       # (G G^T) x = g
            return calls
        for j in range(nq):
            acc = 0.0
            for i in range(m):
                acc += w[m + i * nq + j] * x[i]
            if not math.isfinite(acc):
                return calls
            d[j] = acc
        big = 0.0
        for j in range(nq):
            y[j] -= d[j]
            big = max(big, abs(d[j]) / max(1.0, abs(y[j])))
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


def _rows(hol_at, m, nq, n_sens, ts, ys, P, which):
    """``onto`` at every row ``ys[i]`` (time ``ts[i]``, parameters ``P[which[i]]``), in
    place; ``hol_at`` the address of the kernel (``_common.function_at``)."""
    hol = function_at(hol_at)
    ws = workspace(m, nq, n_sens)
    for i in range(ts.shape[0]):
        onto(hol, m, nq, n_sens, ts[i], ys[i], P[which[i]], ws)


_ROWS_ARGS = (i8, i8, i8, i8, f8[::1], f8[:, ::1], f8[:, ::1], i8[::1])


def rows(hol, m, nq, ts, ys, p, n_sens=0):
    """``onto`` of every row ``ys[i]`` (at ``ts[i]``) in place, by the compiled loop
    over the rows: each row moved exactly as a step of a compiled loop ending at it
    would be (the dense output's rows: ``t_eval``, events, a stop inside a step,
    ``Trajectory.at``, an ensemble's rows).

    ``hol``: the kernel as ``kernels.calls.Kernel`` (its address and the sizes it reads
    and writes; with ``n_sens`` > 0 the kernel of the augmented state, which writes
    dg/dp too); ``p``: the parameters, or one row of them per row of ``ys`` (an
    ensemble's runs).  ``n_sens`` > 0: each row is the state followed by its
    sensitivities (``n_sens`` columns, the parameters' last), moved onto the tangent
    space of g = 0 at the projected point, ``G S_q + dg/dp = 0``."""
    n_y, n_p, n_out = hol.sizes
    p = np.ascontiguousarray(p, dtype=float)
    if p.ndim == 1:
        P, which = p[None, :], np.zeros(ys.shape[0], dtype=np.int64)
    else:
        P, which = p, np.arange(ys.shape[0], dtype=np.int64)
    ts = np.ascontiguousarray(ts, dtype=float)
    if not (isinstance(ys, np.ndarray) and ys.dtype == np.float64 and ys.ndim == 2
            and ys.flags.c_contiguous and ys.flags.writeable):
        raise TypeError("ys must be a writable C-contiguous float64 array of rows")
    if (ts.shape != (ys.shape[0],) or P.shape[0] != (1 if p.ndim == 1 else ys.shape[0])
            or ys.shape[1] < max(n_y, nq) or P.shape[1] < n_p
            or max(m, 1) * (1 + nq + n_sens) < n_out
            or n_sens and ys.shape[1] % (1 + n_sens)):
        raise ValueError(f"the rows do not fit the kernel: ts {ts.shape}, ys {ys.shape}, "
                         f"p {p.shape}, {m} constraints on {nq} coordinates, {n_sens} "
                         f"sensitivity columns, kernel sizes {hol.sizes}")
    if ys.shape[0]:
        compiled(_rows, _ROWS_ARGS)(hol.address.address, m, nq, n_sens, ts, ys, P, which)
