"""Radau IIA of order 5: an implicit collocation method for stiff problems.

- Three stages at the Radau points c = ((4 - sqrt 6)/10, (4 + sqrt 6)/10, 1); order 5,
  stiffly accurate (y_new is the last stage), L-stable.  The matrix A and everything
  below are derived here from the nodes (collocation: ``A[i, j] = int_0^c_i l_j``).
- Stage equations ``Z = h (A x I) F(Z)`` solved by simplified Newton in the eigenbasis
  of A^-1 (Hairer & Wanner II, IV.8): with ``T^-1 A^-1 T = diag(gamma, [[alpha, beta],
  [-beta, alpha]])`` one real n x n system ``(gamma/h - J) dW1 = r1`` and one complex
  ``((alpha - i beta)/h - J) (dW2 + i dW3) = r2 + i r3`` per iteration, their LU
  factors kept while h and the Jacobian J stay; J = df/dy is the generated Jacobian of
  the right-hand side (``jac(t, y, p, J)``, from the symbolic derivation), recomputed
  after an accepted step unless Newton contracted fast (rate <= 1e-3).  Starting values
  from the previous step's collocation polynomial; convergence test
  ``rate / (1 - rate) |dW| <= newton_tol`` (default ``max(10 eps / rtol, min(0.03,
  rtol^0.5))``, scipy's), at most ``max_newton`` (7) iterations, else h / 2.
- Error estimate: the embedded order-3 formula with weight ``1/gamma`` on f(t, y) (IV.8,
  (8.16)-(8.20)) filtered by ``(gamma/h - J)^-1`` (once more with f(t, y + err) after a
  rejection or on the first step), in the RMS norm scaled by ``atol + rtol |y|`` (the
  tolerances mean what they mean for the other methods; RADAU5 itself rescales them).
- Step control: ``h_new = h / max(1/8, min(5, err^(1/4) / fac))`` with ``fac = 0.9 (2
  max_newton + 1) / (iterations + 2 max_newton)``, the predictive (Gustafsson) controller
  after an accepted step, h kept when the change is within [1, 1.2] (LU reused).
- Dense output: the collocation polynomial through y, y + Z1, y + Z2, y_new (cubic, no
  evaluation), in the rows of ``_events.dense_eval``: ``t_eval``, events and singular
  stops as the explicit methods (``loop.after_step``, ``loop.output``); after the run
  ``collocation`` gives it again from a step's start and size (``Trajectory.at``).

Reference: E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd ed.,
Springer 1996, section IV.8 (and IV.5 for the collocation form).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numba
import numpy as np

from ._common import (
    ENDPOINTS, ENSEMBLE_OUT, EVENT, EVERY_STEP, FINISHED, MAX_STEPS, NONFINITE,
    SINGULAR, STOPPED, TOO_SMALL_STEP, all_finite, apart, callback_at, collect, compiled,
    copy_into, f8, function_at, i8, jit, min_step, start, store, take_next)
from ._events import dense_eval, watch_end, watch_next
from . import projection
from .loop import (ALL, CONTROL, EMBEDDED, GIVEN, WATCHED, after_step, counts,
                   finite_status, no_events, output, outputs, watch_result, watch_start)

ORDER = 5
ERROR_ORDER = 3
#: the Jacobian callback: jac(t, y, p, J) fills J[i, j] = d rhs_i / d y_j
JAC_SIGNATURE = numba.types.void(f8, f8[::1], f8[::1], f8[:, ::1])
JAC = numba.types.FunctionType(JAC_SIGNATURE)


#: the Jacobian (type ``JAC``) at an address, as ``function_at`` for the right-hand side
jacobian_at = callback_at(JAC)

#: Newton options of one run (``tol`` 0: automatic)
Newton = namedtuple("Newton", "tol max_iter")
NEWTON = numba.typeof(Newton(0.0, 7))
SAFETY = 0.9
#: Newton contraction below which the Jacobian is kept for the next step
KEEP_JACOBIAN = 1e-3


def _method():
    """Nodes, A, T, T^-1, the eigenvalues and the error weights, derived from the nodes."""
    s6 = math.sqrt(6.0)
    c = np.array([(4.0 - s6) / 10.0, (4.0 + s6) / 10.0, 1.0])
    A = np.empty((3, 3))
    for j in range(3):
        others = [c[k] for k in range(3) if k != j]
        lj = np.polynomial.Polynomial.fromroots(others) / np.prod([c[j] - o for o in others])
        integral = lj.integ()
        A[:, j] = integral(c) - integral(0.0)
    Ainv = np.linalg.inv(A)
    vals, vecs = np.linalg.eig(Ainv)
    r = int(np.argmin(np.abs(vals.imag)))
    k = int(np.argmax(vals.imag))
    T = np.column_stack([vecs[:, r].real, vecs[:, k].real, vecs[:, k].imag])
    TI = np.linalg.inv(T)
    lam = TI @ Ainv @ T
    gamma, alpha, beta = lam[0, 0], lam[1, 1], lam[1, 2]
    # embedded order-3 weights: gamma0 = 1/gamma on f(t, y), bh on the stages
    V = np.vander(c, 3, increasing=True).T
    bh = np.linalg.solve(V, np.array([1.0 - 1.0 / gamma, 0.5, 1.0 / 3.0]))
    b = A[2]
    err_w = gamma * (bh - b) @ Ainv
    return c, A, T, TI, lam, gamma, alpha, beta, err_w


C, A, T, TI, LAMBDA, GAMMA, ALPHA, BETA, ERR_W = _method()
#: the loop's view of the method (``loop.after_step``): dense rows filled here
TAB = (C.copy(), np.zeros((3, 3)), np.zeros(3), np.zeros(1), np.zeros(1), np.zeros((0, 1)),
       np.array([3, EMBEDDED, GIVEN, ERROR_ORDER], dtype=np.int64), 1.0)


def newton_options(tol, max_iter) -> Newton:
    """``Newton`` from ``run``'s ``newton_tol``, ``max_newton`` (None: the defaults)."""
    from .. import arguments

    return Newton(0.0 if tol is None else arguments.positive(tol, "newton_tol"),
                  7 if max_iter is None else arguments.count(max_iter, "max_newton",
                                                             limit=1000))


@jit
def lu_factor(M, piv):
    """LU with partial pivoting in place (real or complex); False if singular."""
    n = M.shape[0]
    for c in range(n):
        k = c
        big = abs(M[c, c])
        for r in range(c + 1, n):
            if abs(M[r, c]) > big:
                big = abs(M[r, c])
                k = r
        piv[c] = k
        if big == 0.0 or not math.isfinite(big):
            return False
        if k != c:
            for j in range(n):
                M[c, j], M[k, j] = M[k, j], M[c, j]
        inv = 1.0 / M[c, c]
        for r in range(c + 1, n):
            m = M[r, c] * inv
            M[r, c] = m
            if m != 0.0:
                for j in range(c + 1, n):
                    M[r, j] -= m * M[c, j]
    return True


@jit
def lu_solve(M, piv, b):
    """Solve with the factors of ``lu_factor``; b is overwritten by the solution."""
    n = M.shape[0]
    for c in range(n):              # the row exchanges (whole rows were exchanged)
        k = piv[c]
        if k != c:
            b[c], b[k] = b[k], b[c]
    for c in range(n):
        for r in range(c + 1, n):
            b[r] -= M[r, c] * b[c]
    for r in range(n - 1, -1, -1):
        s = b[r]
        for j in range(r + 1, n):
            s -= M[r, j] * b[j]
        b[r] = s / M[r, r]


@jit
def _factor(Jm, h, E1, E2, piv1, piv2):
    """E1 = gamma/h - J, E2 = (alpha - i beta)/h - J, factored."""
    n = Jm.shape[0]
    g = GAMMA / h
    s = complex(ALPHA / h, -BETA / h)
    for i in range(n):
        for j in range(n):
            E1[i, j] = -Jm[i, j]
            E2[i, j] = -Jm[i, j]
        E1[i, i] += g
        E2[i, i] += s
    return lu_factor(E1, piv1) and lu_factor(E2, piv2)


@jit
def _rms(v, scale):
    s = 0.0
    for i in range(v.shape[0]):
        s += (v[i] / scale[i]) ** 2
    return math.sqrt(s / max(v.shape[0], 1))


@jit
def _newton(rhs, t, h, y, p, W, Z, Fs, ytmp, r, cb, E1, E2, piv1, piv2, scale, tol, max_iter,
            rate, stats):
    """Simplified Newton for the stages in the eigenbasis (W = T^-1 Z, given the starting
    W).  Returns (converged, iterations, rate)."""
    n = y.shape[0]
    d_old = 0.0
    # the first iteration is judged by the last step's contraction (as RADAU5 does)
    rate = min(max(rate, 1e-16) ** 0.8, 0.9)
    for it in range(max_iter):
        for s in range(3):
            for i in range(n):
                Z[s, i] = T[s, 0] * W[0, i] + T[s, 1] * W[1, i] + T[s, 2] * W[2, i]
                ytmp[i] = y[i] + Z[s, i]
            rhs(t + C[s] * h, ytmp, p, Fs[s])
        stats[2] += 3
        if not (all_finite(Fs[0]) and all_finite(Fs[1]) and all_finite(Fs[2])):
            return False, it + 1, rate
        for i in range(n):
            for k in range(3):
                r[k, i] = (TI[k, 0] * Fs[0, i] + TI[k, 1] * Fs[1, i] + TI[k, 2] * Fs[2, i]
                           - (LAMBDA[k, 0] * W[0, i] + LAMBDA[k, 1] * W[1, i]
                              + LAMBDA[k, 2] * W[2, i]) / h)
            cb[i] = complex(r[1, i], r[2, i])
        lu_solve(E1, piv1, r[0])
        lu_solve(E2, piv2, cb)
        d = 0.0
        for i in range(n):
            r[1, i] = cb[i].real
            r[2, i] = cb[i].imag
            for k in range(3):
                W[k, i] += r[k, i]
                d += (r[k, i] / scale[i]) ** 2
        d = math.sqrt(d / max(3 * n, 1))
        if not math.isfinite(d):
            return False, it + 1, rate
        if it > 0:
            rate = d / d_old
            if rate >= 1.0:
                return False, it + 1, rate
            # predicted not to converge within max_iter iterations
            if rate ** (max_iter - 1 - it) / (1.0 - rate) * d > tol:
                return False, it + 1, rate
        if d == 0.0 or rate / (1.0 - rate) * d <= tol:
            for s in range(3):
                for i in range(n):
                    Z[s, i] = T[s, 0] * W[0, i] + T[s, 1] * W[1, i] + T[s, 2] * W[2, i]
            return True, it + 1, rate
        d_old = d
    return False, max_iter, rate


@jit
def _error(rhs, t, h, y, f0, Z, p, E1, piv1, scale, err_v, f1, ytmp, again, stats):
    """The scaled error of the step: (gamma/h - J)^-1 (f(t, y) + sum_j w_j Z_j / h); with
    ``again`` once more through f(t, y + err) (the stiff filter of IV.8)."""
    n = y.shape[0]
    for i in range(n):
        f1[i] = (ERR_W[0] * Z[0, i] + ERR_W[1] * Z[1, i] + ERR_W[2] * Z[2, i]) / h
        err_v[i] = f0[i] + f1[i]
    lu_solve(E1, piv1, err_v)
    err = _rms(err_v, scale)
    if again and err >= 1.0:
        for i in range(n):
            ytmp[i] = y[i] + err_v[i]
        rhs(t, ytmp, p, err_v)
        stats[2] += 1
        for i in range(n):
            err_v[i] += f1[i]
        lu_solve(E1, piv1, err_v)
        err = _rms(err_v, scale)
    return err


@jit
def _dense(y, Z, F):
    """Rows of the collocation polynomial (``_events.dense_eval``) through (0, y),
    (c1, y + Z1), (c2, y + Z2), (1, y + Z3)."""
    c1 = C[0]
    c2 = C[1]
    for i in range(y.shape[0]):
        g1 = (Z[0, i] - c1 * Z[2, i]) / (c1 * (1.0 - c1))
        g2 = (Z[1, i] - c2 * Z[2, i]) / (c2 * (1.0 - c2))
        F[0, i] = Z[2, i]
        F[2, i] = (g1 - g2) / (c1 - c2)
        F[1, i] = g1 - c1 * F[2, i]


def collocation(rhs, jac, t, h, y, p, max_iter=20) -> np.ndarray | None:
    """The rows F (``_dense``) of the collocation polynomial of the step from (t, y) of
    size h: the stage equations ``Z = h (A x I) F(y + Z)`` solved by full Newton (the
    Jacobian ``jac(t, y, p, J)`` at every stage, one 3n x 3n system an iteration) from
    Z = 0 until the update is at rounding level; None if it does not converge.  The
    run's own polynomial is this one to its Newton tolerance (``newton_tol``): a step
    is a function of (t, y, h) up to that tolerance, not of the Newton iterations
    before it (``numeric.dense``)."""
    n = y.shape[0]
    Z = np.zeros((3, n))
    f = np.empty((3, n))
    Js = np.empty((3, n, n))
    U = np.empty(n)
    M = np.empty((3 * n, 3 * n))
    last = np.inf
    for _ in range(max_iter):
        for j in range(3):
            U[:] = y + Z[j]
            rhs(t + C[j] * h, U, p, f[j])
            jac(t + C[j] * h, U, p, Js[j])
        r = Z - h * (A @ f)
        for i in range(3):
            for j in range(3):
                M[i * n:(i + 1) * n, j * n:(j + 1) * n] = -h * A[i, j] * Js[j]
        M[np.diag_indices(3 * n)] += 1.0
        try:
            dZ = np.linalg.solve(M, r.ravel()).reshape(3, n)
        except np.linalg.LinAlgError:
            return None
        if not np.all(np.isfinite(dZ)):
            return None
        Z -= dZ
        size = float(np.max(np.abs(dZ) / (np.abs(Z) + np.abs(y) + 1e-300)))
        # at rounding level, or no longer shrinking there (the rounding of f)
        if size <= 1e-14 or (size <= 1e-10 and size > 0.5 * last):
            F = np.empty((3, n))
            _dense(y, Z, F)
            return F
        last = size
    return None


def _solve(rhs_at, jac_at, sing_at, uev_at, hol_at, t0, t_end, y0, p, ctl, newton, t_eval,
           mode, watch, halt):
    """Integrate y' = rhs(t, y, p) from t0 to t_end with Radau IIA (5); ``jac(t, y, p, J)``
    its Jacobian; the five callbacks given by their addresses (``_common.function_at``,
    ``jacobian_at``); the other arguments and the ``Result`` fields as for ``loop._solve``
    (``newton``: ``Newton``; the parts ``WATCH``, ``PROJECT``, ``DENSE`` are compile-time
    constants, as there: ``_specialised``)."""
    rhs, jac = function_at(rhs_at), jacobian_at(jac_at)
    sing, uev, hol = function_at(sing_at), function_at(uev_at), function_at(hol_at)
    rtol, atol, max_step, max_steps = ctl.rtol, ctl.atol, ctl.max_step, ctl.max_steps
    if PROJECT:
        hw = projection.workspace(ctl.n_hol, ctl.n_coord, ctl.n_sens)
    tol = newton[0]
    max_iter = newton[1]
    if tol <= 0.0:
        tol = max(10.0 * 2.220446049250313e-16 / rtol, min(0.03, rtol ** 0.5))
    n = y0.shape[0]
    direction = 1.0 if t_end >= t0 else -1.0
    y = y0.copy()
    y_new = np.empty(n)
    ytmp = np.empty(n)
    fmid = np.empty(n)
    y_stop = np.empty(n)
    scale = np.empty(n)
    f0 = np.empty(n)
    f1 = np.empty(n)
    err_v = np.empty(n)
    K = np.empty((4, n))
    F = np.empty((3, n))
    F_prev = np.zeros((3, n))
    y_prev = np.empty(n)
    W = np.empty((3, n))
    Z = np.empty((3, n))
    Fs = np.empty((3, n))
    r = np.empty((3, n))
    cb = np.empty(n, dtype=np.complex128)
    Jm = np.empty((n, n))
    E1 = np.empty((n, n))
    E2 = np.empty((n, n), dtype=np.complex128)
    piv1 = np.empty(n, dtype=np.int64)
    piv2 = np.empty(n, dtype=np.int64)
    stats = np.zeros(3, dtype=np.int64)
    ts, ys, n_out, j_eval = outputs(n, mode, t_eval, 64)
    t = t0
    ev_t, ev_i, ev_y, n_ev = no_events(F, watch.ev_dir)
    sing_index = -1
    if WATCH:
        ws, sing_index = watch_start(sing, uev, watch, t, y, p)
        n_sing, ev_dir = watch.n_sing, watch.ev_dir
        gs, gs_old, gref, sig, eps, gu_old, gu_new = ws[:7]
        if sing_index >= 0:
            ts, ys, n_out = store(ts, ys, n_out, t, y)
            return (SINGULAR, ts, ys, n_out, counts(stats), t, y, ev_t, ev_i, ev_y, n_ev,
                          sing_index)
    go, h_abs, ts, ys, n_out = start(rhs, t, y, p, f0, K[0], ytmp, scale, ctl, ERROR_ORDER,
                                     t_end, stats, mode, t_eval, ts, ys, n_out)
    if go >= 0:
        go = finite_status(go, ys, n_out, y, ctl.n_sens)
        return (go, ts, ys, n_out, counts(stats), t, y, ev_t, ev_i, ev_y, n_ev, sing_index)
    jac(t, y, p, Jm)
    jac_fresh = True
    h_lu = 0.0                  # the h of the current LU factors (0: none)
    rate = 1.0
    h_prev = 0.0                # the last accepted step (0: none yet)
    h_acc = 0.0
    err_acc = 1e-2
    first = True
    status = FINISHED
    t_start = t
    while direction * (t_end - t) > 0.0:
        if stats[0] >= max_steps:
            status = MAX_STEPS
            break
        if halt[0] != 0:
            status = STOPPED
            break
        hmin = min_step(t, direction)
        for i in range(n):
            scale[i] = atol[i] + abs(y[i]) * rtol
        rejected = False
        while True:
            if h_abs > max_step:
                h_abs = max_step
            if h_abs < hmin:
                status = TOO_SMALL_STEP
                break
            t_new = t + h_abs * direction
            if direction * (t_new - t_end) > 0.0:
                t_new = t_end
            h = t_new - t
            h_abs = abs(h)
            if h != h_lu:
                if not _factor(Jm, h, E1, E2, piv1, piv2):
                    h_lu = 0.0
                    h_abs *= 0.5
                    stats[1] += 1
                    rejected = True
                    continue
                h_lu = h
            # starting values: the previous collocation polynomial, extrapolated
            if h_prev != 0.0:
                for s in range(3):
                    dense_eval(1.0 + C[s] * h / h_prev, y_prev, F_prev, ytmp)
                    for i in range(n):
                        Z[s, i] = ytmp[i] - y[i]
            else:
                for s in range(3):
                    for i in range(n):
                        Z[s, i] = 0.0
            for k in range(3):
                for i in range(n):
                    W[k, i] = TI[k, 0] * Z[0, i] + TI[k, 1] * Z[1, i] + TI[k, 2] * Z[2, i]
            ok, iters, rate = _newton(rhs, t, h, y, p, W, Z, Fs, ytmp, r, cb, E1, E2, piv1,
                                      piv2, scale, tol, max_iter, rate, stats)
            if not ok:
                stats[1] += 1
                rejected = True
                h_abs *= 0.5
                if not jac_fresh:
                    jac(t, y, p, Jm)
                    jac_fresh = True
                    h_lu = 0.0
                continue
            for i in range(n):
                y_new[i] = y[i] + Z[2, i]
            err = _error(rhs, t, h, y, f0, Z, p, E1, piv1, scale, err_v, f1, ytmp,
                         first or rejected, stats)
            fac = min(SAFETY, SAFETY * (2 * max_iter + 1) / (iters + 2 * max_iter))
            if not math.isfinite(err):
                stats[1] += 1
                rejected = True
                h_abs *= 0.5
                continue
            quot = max(0.125, min(5.0, err ** 0.25 / fac))
            if err < 1.0:
                if not first:
                    gus = (h_acc / h_abs) * (err * err / err_acc) ** 0.25 / SAFETY
                    quot = max(quot, max(0.125, min(5.0, gus)))
                h_acc = h_abs
                err_acc = max(1e-2, err)
                h_new_abs = h_abs / quot
                if rejected:
                    h_new_abs = min(h_new_abs, h_abs)
                break
            stats[1] += 1
            rejected = True
            h_abs = h_abs * 0.1 if first else h_abs / quot
        if status != FINISHED:
            break
        first = False
        stats[0] += 1
        if PROJECT:
            if ctl.n_hol > 0:
                projection.project(hol, ctl, t_new, y_new, p, hw)
        _dense(y, Z, F)
        rhs(t_new, y_new, p, f1)
        stats[2] += 1
        if not all_finite(f1):
            status = NONFINITE
            break
        stop = 0
        t_stop = t_new
        if WATCH:
            si, more = watch_end(sing, uev, n_sing, t_new, y_new, p, gs, gs_old, sig, eps,
                                 gref, gu_old, gu_new, ev_dir, stats[0] == 1)
            if more:
                stop, t_stop, sing_index, have_dense, ev_t, ev_i, ev_y, n_ev = after_step(
                    TAB, False, rhs, sing, uev, p, t, h, t_new, y, y_new, K, F, ytmp, fmid,
                    y_stop, stats, watch, ws, si, sing_index, ev_t, ev_i, ev_y, n_ev,
                    stats[0] == 1)
            watch_next(n_sing, gs, gs_old, gu_old, gu_new)
        if WATCH or DENSE:
            ts, ys, n_out, j_eval = output(TAB, False, rhs, p, t, h, t_new, y, y_new, K, F,
                                           ytmp, y_stop, stop, t_stop, True, stats, mode,
                                           t_eval, j_eval, direction, ts, ys, n_out)
        elif mode == EVERY_STEP:
            ts, ys, n_out = store(ts, ys, n_out, t_new, y_new)
        if stop != 0:
            t_start = t             # the step's start: row n_out at the end (``loop``)
            copy_into(y_new, y)
            t = t_stop
            copy_into(y, y_stop)
            status = stop
            break
        copy_into(y_prev, y)
        t = t_new
        copy_into(y, y_new)
        copy_into(f0, f1)
        for k in range(3):
            copy_into(F_prev[k], F[k])
        h_prev = h
        # the next step: keep h (and the LU) for a small increase, keep J if Newton was fast
        if h_new_abs >= h_abs and h_new_abs <= 1.2 * h_abs and rate <= KEEP_JACOBIAN:
            h_new_abs = h_abs
        if rate > KEEP_JACOBIAN:
            jac(t, y, p, Jm)
            jac_fresh = True
            h_lu = 0.0
        else:
            jac_fresh = False
        h_abs = h_new_abs
    if mode == ENDPOINTS:
        ts, ys, n_out = store(ts, ys, n_out, t, y)
    status = finite_status(status, ys, n_out, y, ctl.n_sens)
    if status == EVENT or status == SINGULAR:
        ts, ys, _ = store(ts, ys, n_out, t_start, y_new)
    return (status, ts, ys, n_out, counts(stats), t, y, ev_t, ev_i, ev_y, n_ev, sing_index)


ARGS = (i8, i8, i8, i8, i8, f8, f8, f8[::1], f8[::1], CONTROL, NEWTON, f8[::1], i8,
        WATCHED, i8[::1])


def _entry(rhs_at, jac_at, sing_at, uev_at, hol_at, t0, t_end, y0, p, ctl, newton, t_eval,
           mode, watch, halt):
    """The entry of the loop: ``_solve`` (``body``, compiled apart) with its tuple made
    ``loop.watch_result``'s (as ``loop._watching``)."""
    return watch_result(body(rhs_at, jac_at, sing_at, uev_at, hol_at, t0, t_end, y0, p, ctl,
                             newton, t_eval, mode, watch, halt), watch.ev_dir.shape[0])


#: the parts of a specialised loop, its body and the compiled loop in the namespace of
#: the ensemble drivers (``_specialised``, ``ensemble_solver``; unbound here)
WATCH = PROJECT = DENSE = None
run = body = None
_SPECIALISED = {}


def _specialised(parts=ALL):
    """The globals of this module with the parts of the loop a run needs bound (``WATCH,
    PROJECT, DENSE = parts[:3]``: ``loop.features``) and ``run`` to ``_solve`` compiled over
    them (``_entry``): a run without events, indicators, projection and ``t_eval``
    compiles none of their code (``loop._specialised``).  The per-step store is in every
    radau loop (the fourth part of ``loop.features`` is ignored): next to a step's linear
    algebra it costs nothing, and without it a run that keeps only its end would need a
    loop of its own."""
    parts = tuple(bool(f) for f in parts[:3])
    if parts not in _SPECIALISED:
        namespace = dict(globals())
        namespace["WATCH"], namespace["PROJECT"], namespace["DENSE"] = parts
        tag = "" if parts == ALL[:3] else "_" + "".join(c for c, f in zip("wpd", parts) if f)
        namespace["body"] = apart(_solve, namespace, tag)
        namespace["run"] = compiled(_entry, ARGS, namespace=namespace, tag=tag)
        _SPECIALISED[parts] = namespace
    return _SPECIALISED[parts]


def solver(parts=ALL):
    """The compiled ``solve(rhs, jac, sing, uev, hol, t0, t_end, y0, p, ctl, newton, t_eval,
    mode, watch, halt)`` with the ``parts`` of ``loop.features`` (default: all; a run that
    needs a part the loop lacks is not to be given to it)."""
    return _specialised(parts)["run"]


def _ensemble_parallel(rhs_at, jac_at, sing_at, uev_at, hol_at, t0, t_end, Y0, P, ctl, newton,
                       t_eval, mode, watch, halt, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N,
                       EV_T):
    n_runs = Y0.shape[0]
    taken = np.zeros(1, dtype=np.int64)
    for _ in numba.prange(n_runs):       # (as loop._ensemble_parallel)
        r = take_next(taken)
        while r < n_runs:
            res = run(rhs_at, jac_at, sing_at, uev_at, hol_at, t0, t_end, Y0[r], P[r], ctl,
                      newton, t_eval, mode, watch, halt)
            collect(r, res, mode, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T)
            r = take_next(taken)


def _ensemble_serial(rhs_at, jac_at, sing_at, uev_at, hol_at, t0, t_end, Y0, P, ctl, newton,
                     t_eval, mode, watch, halt, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N,
                     EV_T):
    for r in range(Y0.shape[0]):
        res = run(rhs_at, jac_at, sing_at, uev_at, hol_at, t0, t_end, Y0[r], P[r], ctl,
                  newton, t_eval, mode, watch, halt)
        collect(r, res, mode, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T)


ENSEMBLE_ARGS = ARGS[:7] + (f8[:, ::1], f8[:, ::1]) + ARGS[9:] + ENSEMBLE_OUT


def ensemble_solver(parallel=True):
    """The compiled ensemble driver (``loop.ensemble_solver``, with ``jac`` and
    ``newton``)."""
    return compiled(_ensemble_parallel if parallel else _ensemble_serial, ENSEMBLE_ARGS,
                    parallel=parallel, namespace=dict(globals(), run=solver()))
