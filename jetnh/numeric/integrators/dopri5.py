"""Dormand-Prince 5(4): explicit Runge-Kutta, order 5, embedded order-4 error estimate.

- Order 5 (local extrapolation), FSAL: six right-hand-side evaluations per step.
- Error estimate: the difference to the embedded 4th-order solution, measured in the
  RMS norm scaled by ``atol + rtol * max(|y_n|, |y_n+1|)``.
- Step control: ``h_new = h * min(10, max(0.2, 0.9 * err^(-1/5)))``, no increase right
  after a rejection; starting step by the heuristic of Hairer-Norsett-Wanner II.4.
  This is the controller of scipy's ``RK45``, so both take the same steps.
- Dense output: Hairer's 4th-order continuous extension (``contd5`` of DOPRI5).

References: J. R. Dormand, P. J. Prince, "A family of embedded Runge-Kutta formulae",
J. Comput. Appl. Math. 6 (1980) 19-26; E. Hairer, S. P. Norsett, G. Wanner, *Solving
Ordinary Differential Equations I*, 2nd ed., Springer 1993, sections II.4-II.6.

``solver()`` returns the compiled ``solve(rhs, ...)``; ``rhs`` is a first-class numba
function (``_common.RHS``), so the loop is compiled once for every scene and cached on
disk, and only the right-hand side is compiled per scene.
"""

import math

import numpy as np

from ._common import (
    AT_T_EVAL, ENDPOINTS, EVERY_STEP, FINISHED, MAX_FACTOR, MAX_STEPS, MIN_FACTOR,
    NONFINITE, RHS, SAFETY, TOO_SMALL_STEP, all_finite, compiled, copy_into, f8, i8,
    initial_step_h0, initial_step_h1, jit, min_step, store)

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
def _dense(theta, h, y_old, y_new, K, out):
    th1 = 1.0 - theta
    for i in range(y_old.shape[0]):
        r2 = y_new[i] - y_old[i]
        r3 = h * K[0, i] - r2
        r4 = r2 - h * K[6, i] - r3
        r5 = 0.0
        for s in range(7):
            r5 += DENSE[s] * K[s, i]
        r5 *= h
        out[i] = y_old[i] + theta * (r2 + th1 * (r3 + theta * (r4 + th1 * r5)))


def _solve(rhs, t0, t_end, y0, p, rtol, atol, first_step, max_step, max_steps, t_eval, mode):
    """Integrate y' = rhs(t, y, p) from t0 to t_end.

    Returns ``(status, ts, ys, n_out, stats, t, y)``: the output rows ``ts[:n_out]``,
    ``ys[:n_out]`` (every accepted step, the points of ``t_eval``, or the two endpoints,
    by ``mode``), ``stats = [accepted, rejected, rhs evaluations]`` and the last state.
    """
    n = y0.shape[0]
    direction = 1.0 if t_end >= t0 else -1.0
    interval = abs(t_end - t0)
    K = np.empty((7, n))
    y = y0.copy()
    y_new = np.empty(n)
    ytmp = np.empty(n)
    scale = np.empty(n)
    stats = np.zeros(3, dtype=np.int64)
    cap = t_eval.shape[0] if mode == AT_T_EVAL else (2 if mode == ENDPOINTS else 64)
    ts = np.empty(max(cap, 1))
    ys = np.empty((max(cap, 1), n))
    n_out = 0
    j_eval = 0
    t = t0
    rhs(t, y, p, K[0])
    stats[2] += 1
    if not all_finite(K[0]):
        return NONFINITE, ts, ys, n_out, stats, t, y
    if mode != AT_T_EVAL:
        ts, ys, n_out = store(ts, ys, n_out, t, y)
    if interval == 0.0:
        if mode == AT_T_EVAL:
            while j_eval < t_eval.shape[0] and t_eval[j_eval] == t:
                ts, ys, n_out = store(ts, ys, n_out, t, y)
                j_eval += 1
        return FINISHED, ts, ys, n_out, stats, t, y
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
        if mode == AT_T_EVAL:
            while j_eval < t_eval.shape[0] and direction * (t_eval[j_eval] - t_new) <= 0.0:
                _dense((t_eval[j_eval] - t) / h, h, y, y_new, K, ytmp)
                ts, ys, n_out = store(ts, ys, n_out, t_eval[j_eval], ytmp)
                j_eval += 1
        elif mode == EVERY_STEP:
            ts, ys, n_out = store(ts, ys, n_out, t_new, y_new)
        t = t_new
        copy_into(y, y_new)
        copy_into(K[0], K[6])
    if mode == ENDPOINTS:
        ts, ys, n_out = store(ts, ys, n_out, t, y)
    return status, ts, ys, n_out, stats, t, y


ARGS = (RHS, f8, f8, f8[::1], f8[::1], f8, f8[::1], f8, f8, i8, f8[::1], i8)


def solver():
    """The compiled ``solve(rhs, t0, t_end, y0, p, rtol, atol, first_step, max_step,
    max_steps, t_eval, mode)``."""
    return compiled(_solve, ARGS)
