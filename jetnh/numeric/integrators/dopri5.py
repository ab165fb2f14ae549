"""Dormand-Prince 5(4): explicit Runge-Kutta, order 5, embedded order-4 error estimate.

- Order 5 (local extrapolation), FSAL: six right-hand-side evaluations per step.
- Error estimate: the difference to the embedded 4th-order solution, measured in the
  RMS norm scaled by ``atol + rtol * max(|y_n|, |y_n+1|)``.
- Step control: ``h_new = h * min(10, max(0.2, 0.9 * err^(-1/5)))``, no increase right
  after a rejection; starting step by the heuristic of Hairer-Norsett-Wanner II.4.
  This is the controller of scipy's ``RK45``, so both take the same steps.
- Dense output: Hairer's 4th-order continuous extension (``contd5`` of DOPRI5), free
  (no extra evaluation); used for ``t_eval``, events and singularity stops (``_events``).

References: J. R. Dormand, P. J. Prince, "A family of embedded Runge-Kutta formulae",
J. Comput. Appl. Math. 6 (1980) 19-26; E. Hairer, S. P. Norsett, G. Wanner, *Solving
Ordinary Differential Equations I*, 2nd ed., Springer 1993, sections II.4-II.6.

``solver()`` returns the compiled ``solve(rhs, ...)``; ``rhs`` is a first-class numba
function (``_common.RHS``), so the loop is compiled once for every scene and cached on
disk, and only the right-hand side is compiled per scene.
"""

import math

import numba
import numpy as np

from ._common import (
    AT_T_EVAL, ENDPOINTS, EVERY_STEP, FINISHED, MAX_FACTOR, MAX_STEPS, MIN_FACTOR,
    NONFINITE, RHS, SAFETY, STOPPED, TOO_SMALL_STEP, all_finite, compiled, copy_into, f8, i8,
    collect, initial_step_h0, initial_step_h1, jit, min_step, store)
from ._common import ENSEMBLE_OUT
from ._events import (SINGULAR, any_user_active, dense_eval, locate, sing_dip, sing_init,
                      sing_violated, sing_watch)

ORDER = 5
ERROR_ORDER = 4
STAGES_PER_STEP = 6

C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0])
A = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0],
    [1 / 5, 0.0, 0.0, 0.0, 0.0],
    [3 / 40, 9 / 40, 0.0, 0.0, 0.0],
    [44 / 45, -56 / 15, 32 / 9, 0.0, 0.0],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0.0],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
])
B = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84])
# y5 - y4, over the 7 stages (the 7th is f(t + h, y_new))
E = np.array([71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40])
# Hairer's contd5 coefficients
DENSE = np.array([-12715105075 / 11282082432, 0.0, 87487479700 / 32700410799,
                  -10690763975 / 1880347072, 701980252875 / 199316789632,
                  -1453857185 / 822651844, 69997945 / 29380423])


@jit
def _dense_rows(h, y_old, y_new, K, F):
    """Hairer's contd5 coefficients in the form of ``_events.dense_eval`` (4 rows)."""
    for i in range(y_old.shape[0]):
        r2 = y_new[i] - y_old[i]
        r3 = h * K[0, i] - r2
        F[0, i] = r2
        F[1, i] = r3
        F[2, i] = r2 - h * K[6, i] - r3
        r5 = 0.0
        for s in range(7):
            r5 += DENSE[s] * K[s, i]
        F[3, i] = h * r5


def _solve(rhs, sing, uev, t0, t_end, y0, p, rtol, atol, first_step, max_step, max_steps,
           t_eval, mode, n_sing, sing_tol, ev_dir, ev_max, halt):
    """Integrate y' = rhs(t, y, p) from t0 to t_end; arguments and results as in
    ``dop853._solve`` (events and singularity indicators: ``_events``)."""
    n = y0.shape[0]
    direction = 1.0 if t_end >= t0 else -1.0
    interval = abs(t_end - t0)
    K = np.empty((7, n))
    F = np.empty((4, n))
    y = y0.copy()
    y_new = np.empty(n)
    ytmp = np.empty(n)
    y_stop = np.empty(n)
    scale = np.empty(n)
    stats = np.zeros(3, dtype=np.int64)
    cap = t_eval.shape[0] if mode == AT_T_EVAL else (2 if mode == ENDPOINTS else 64)
    ts = np.empty(max(cap, 1))
    ys = np.empty((max(cap, 1), n))
    n_out = np.int64(0)
    j_eval = np.int64(0)
    t = t0
    n_user = ev_dir.shape[0]
    gs = np.empty(max(n_sing, 1))
    gs_old = np.empty(max(n_sing, 1))
    gref = np.empty(max(n_sing, 1))
    sig = np.empty(max(n_sing, 1))
    eps = np.empty(max(n_sing, 1))
    gu_old = np.empty(max(n_user, 1))
    gu_new = np.empty(max(n_user, 1))
    gtmp = np.empty(max(n_user, 1))
    counts = np.zeros(max(n_user, 1), dtype=np.int64)
    roots = np.empty(max(n_user, 1))
    which = np.empty(max(n_user, 1), dtype=np.int64)
    ev_t = np.empty(0)
    ev_i = np.empty(0, dtype=np.int64)
    ev_y = np.empty((0, n))
    n_ev = np.int64(0)
    sing_index = sing_init(sing, n_sing, sing_tol, t, y, p, gs, sig, eps, gref)
    copy_into(gs_old, gs)
    if sing_index >= 0:
        ts, ys, n_out = store(ts, ys, n_out, t, y)
        return SINGULAR, ts, ys, n_out, stats, t, y, ev_t, ev_i, ev_y, n_ev, sing_index
    if n_user > 0:
        uev(t, y, p, gu_old)
    rhs(t, y, p, K[0])
    stats[2] += 1
    if not all_finite(K[0]):
        return NONFINITE, ts, ys, n_out, stats, t, y, ev_t, ev_i, ev_y, n_ev, sing_index
    if mode != AT_T_EVAL:
        ts, ys, n_out = store(ts, ys, n_out, t, y)
    if interval == 0.0:
        if mode == AT_T_EVAL:
            while j_eval < t_eval.shape[0] and t_eval[j_eval] == t:
                ts, ys, n_out = store(ts, ys, n_out, t, y)
                j_eval += 1
        return FINISHED, ts, ys, n_out, stats, t, y, ev_t, ev_i, ev_y, n_ev, sing_index
    if first_step > 0.0:
        h_abs = first_step
    else:
        h0, d1 = initial_step_h0(y, K[0], rtol, atol, interval, scale)
        for i in range(n):
            ytmp[i] = y[i] + h0 * direction * K[0, i]
        rhs(t + h0 * direction, ytmp, p, K[1])
        stats[2] += 1
        h_abs = initial_step_h1(K[0], K[1], h0, d1, scale, ERROR_ORDER, interval, max_step)
    exponent = -1.0 / (ERROR_ORDER + 1)
    status = FINISHED
    while direction * (t_end - t) > 0.0:
        if stats[0] >= max_steps:
            status = MAX_STEPS
            break
        if halt[0] != 0:
            status = STOPPED
            break
        hmin = min_step(t, direction)
        if h_abs > max_step:
            h_abs = max_step
        elif h_abs < hmin:
            h_abs = hmin
        rejected = False
        nonfinite = False
        while True:
            if h_abs < hmin:
                status = NONFINITE if nonfinite else TOO_SMALL_STEP
                break
            t_new = t + h_abs * direction
            if direction * (t_new - t_end) > 0.0:
                t_new = t_end
            h = t_new - t
            h_abs = abs(h)
            for s in range(1, 6):
                for i in range(n):
                    acc = 0.0
                    for r in range(s):
                        acc += A[s, r] * K[r, i]
                    ytmp[i] = y[i] + h * acc
                rhs(t + C[s] * h, ytmp, p, K[s])
            for i in range(n):
                acc = 0.0
                for r in range(6):
                    acc += B[r] * K[r, i]
                y_new[i] = y[i] + h * acc
            rhs(t_new, y_new, p, K[6])
            stats[2] += 6
            err = 0.0
            for i in range(n):
                e = 0.0
                for r in range(7):
                    e += E[r] * K[r, i]
                sc = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol
                err += (h * e / sc) ** 2
            err = math.sqrt(err / n)
            if not math.isfinite(err) or not all_finite(K[6]):
                nonfinite = True
                h_abs *= MIN_FACTOR
                rejected = True
                stats[1] += 1
                continue
            nonfinite = False
            if err < 1.0:
                if err == 0.0:
                    factor = MAX_FACTOR
                else:
                    factor = min(MAX_FACTOR, SAFETY * err ** exponent)
                if rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                break
            h_abs *= max(MIN_FACTOR, SAFETY * err ** exponent)
            rejected = True
            stats[1] += 1
        if status != FINISHED:
            break
        stats[0] += 1
        have_dense = False
        stop = 0
        t_stop = t_new
        if n_sing > 0 or n_user > 0:
            si = -1
            theta_hi = 1.0
            active = False
            if n_sing > 0:
                si = sing_violated(sing, n_sing, t_new, y_new, p, gs, sig, eps)
                if si < 0 and sing_watch(n_sing, gs_old, gs, sig, gref):
                    if not have_dense:
                        _dense_rows(h, y, y_new, K, F)
                        have_dense = True
                    theta_hi = sing_dip(sing, n_sing, t, h, y, F, p, gs_old, sig, eps,
                                        gref, ytmp)
                    if theta_hi > 0.0:
                        si = 0
                    else:
                        theta_hi = 1.0
                copy_into(gs_old, gs)
                active = si >= 0
            if n_user > 0:
                uev(t_new, y_new, p, gu_new)
                if any_user_active(gu_old, gu_new, ev_dir):
                    active = True
            if active:
                if not have_dense:
                    _dense_rows(h, y, y_new, K, F)
                    have_dense = True
                stop, t_stop, sing_index, ev_t, ev_i, ev_y, n_ev = locate(
                    sing, uev, n_sing, si, theta_hi, t, h, y, F, p, gs, sig, eps, gu_old,
                    gu_new, ev_dir, ev_max, counts, ytmp, gtmp, roots, which, ev_t, ev_i, ev_y,
                    n_ev, y_stop)
            for i in range(n_user):
                gu_old[i] = gu_new[i]
        if mode == AT_T_EVAL:
            while j_eval < t_eval.shape[0] and direction * (t_eval[j_eval] - t_stop) <= 0.0:
                if not have_dense:
                    _dense_rows(h, y, y_new, K, F)
                    have_dense = True
                dense_eval((t_eval[j_eval] - t) / h, y, F, ytmp)
                ts, ys, n_out = store(ts, ys, n_out, t_eval[j_eval], ytmp)
                j_eval += 1
        elif mode == EVERY_STEP:
            if stop != 0:
                ts, ys, n_out = store(ts, ys, n_out, t_stop, y_stop)
            else:
                ts, ys, n_out = store(ts, ys, n_out, t_new, y_new)
        if stop != 0:
            t = t_stop
            copy_into(y, y_stop)
            status = stop
            break
        t = t_new
        copy_into(y, y_new)
        copy_into(K[0], K[6])
    if mode == ENDPOINTS:
        ts, ys, n_out = store(ts, ys, n_out, t, y)
    return status, ts, ys, n_out, stats, t, y, ev_t, ev_i, ev_y, n_ev, sing_index


ARGS = (RHS, RHS, RHS, f8, f8, f8[::1], f8[::1], f8, f8[::1], f8, f8, i8, f8[::1], i8, i8, f8,
        i8[::1], i8[::1], i8[::1])


def solver():
    """The compiled ``solve(rhs, sing, uev, t0, t_end, y0, p, rtol, atol, first_step,
    max_step, max_steps, t_eval, mode, n_sing, sing_tol, ev_dir, ev_max, halt)``."""
    return compiled(_solve, ARGS)


# ---------------------------------------------------------------------- ensembles
# Two copies of one driver (numba's cache cannot hold a function compiled both with and
# without ``parallel``): run r of the ensemble is ``_solve`` on Y0[r], P[r].
def _ensemble_parallel(rhs, sing, uev, t0, t_end, Y0, P, rtol, atol, first_step, max_step,
                       max_steps, t_eval, mode, n_sing, sing_tol, ev_dir, ev_max, halt, OUT_T,
                       OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T):
    for r in numba.prange(Y0.shape[0]):
        res = _SOLVE(rhs, sing, uev, t0, t_end, Y0[r], P[r], rtol, atol, first_step,
                     max_step, max_steps, t_eval, mode, n_sing, sing_tol, ev_dir, ev_max, halt)
        collect(r, res, mode, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T)


def _ensemble_serial(rhs, sing, uev, t0, t_end, Y0, P, rtol, atol, first_step, max_step,
                     max_steps, t_eval, mode, n_sing, sing_tol, ev_dir, ev_max, halt, OUT_T, OUT_Y,
                     INFO, T_LAST, Y_LAST, EV_N, EV_T):
    for r in range(Y0.shape[0]):
        res = _SOLVE(rhs, sing, uev, t0, t_end, Y0[r], P[r], rtol, atol, first_step,
                     max_step, max_steps, t_eval, mode, n_sing, sing_tol, ev_dir, ev_max, halt)
        collect(r, res, mode, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T)


ENSEMBLE_ARGS = ARGS[:5] + (f8[:, ::1], f8[:, ::1]) + ARGS[7:] + ENSEMBLE_OUT
_SOLVE = None


def ensemble_solver(parallel=True):
    """The compiled ensemble driver ``drive(rhs, sing, uev, t0, t_end, Y0, P, <solve's
    other arguments>, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T)``: numba threads
    over the runs (``parallel``) or one loop (for a Python thread pool)."""
    global _SOLVE
    _SOLVE = solver()
    return compiled(_ensemble_parallel if parallel else _ensemble_serial, ENSEMBLE_ARGS,
                    parallel=parallel)
