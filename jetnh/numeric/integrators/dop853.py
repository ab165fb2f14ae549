"""DOP853: explicit Runge-Kutta of order 8 with a 5th- and 3rd-order error estimate.

- Order 8 (Dormand-Prince 8(7) coefficients as arranged by Hairer), FSAL: twelve
  right-hand-side evaluations per step.
- Error estimate: Hairer's combination of the embedded 5th- and 3rd-order estimates,
  ``err = |h| e5^2 / sqrt(n (e5^2 + 0.01 e3^2))`` with ``e5, e3`` the scaled 2-norms
  (scale ``atol + rtol * max(|y_n|, |y_n+1|)``); it behaves like an order-7 estimate.
- Step control: ``h_new = h * min(10, max(0.2, 0.9 * err^(-1/8)))``, no increase right
  after a rejection; starting step by Hairer-Norsett-Wanner II.4.  These are the rules of
  scipy's ``DOP853``, so both take the same steps.
- Dense output of order 7 (``contd8``), three extra evaluations in a step that needs it
  (output at ``t_eval``, or locating an event or a singularity: ``_events``).

References: E. Hairer, S. P. Norsett, G. Wanner, *Solving Ordinary Differential
Equations I*, 2nd ed., Springer 1993, sections II.5 (the method), II.6 (dense output),
II.10 (the code DOP853); P. J. Prince, J. R. Dormand, "High order embedded Runge-Kutta
formulae", J. Comput. Appl. Math. 7 (1981) 67-75.  The coefficients are the published
values of Hairer's dop853.f (also printed in scipy's ``dop853_coefficients``).

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

ORDER = 8
ERROR_ORDER = 7
STAGES_PER_STEP = 12
N_STAGES = 12

# ---- tableau (stages 0-11 the method, 12 = f(t+h, y_new), 13-15 dense output)
C = np.array([
    0.0, 0.05260015195876773, 0.0789002279381516, 0.1183503419072274, 0.2816496580927726,
    0.3333333333333333, 0.25, 0.3076923076923077, 0.6512820512820513, 0.6,
    0.8571428571428571, 1.0, 1.0, 0.1, 0.2, 0.7777777777777778])
A = np.zeros((16, 16))
A[1, 0] = 0.05260015195876773
A[2, 0] = 0.0197250569845379
A[2, 1] = 0.0591751709536137
A[3, 0] = 0.02958758547680685
A[3, 2] = 0.08876275643042054
A[4, 0] = 0.2413651341592667
A[4, 2] = -0.8845494793282861
A[4, 3] = 0.924834003261792
A[5, 0] = 0.037037037037037035
A[5, 3] = 0.17082860872947386
A[5, 4] = 0.12546768756682242
A[6, 0] = 0.037109375
A[6, 3] = 0.17025221101954405
A[6, 4] = 0.06021653898045596
A[6, 5] = -0.017578125
A[7, 0] = 0.03709200011850479
A[7, 3] = 0.17038392571223998
A[7, 4] = 0.10726203044637328
A[7, 5] = -0.015319437748624402
A[7, 6] = 0.008273789163814023
A[8, 0] = 0.6241109587160757
A[8, 3] = -3.3608926294469414
A[8, 4] = -0.868219346841726
A[8, 5] = 27.59209969944671
A[8, 6] = 20.154067550477894
A[8, 7] = -43.48988418106996
A[9, 0] = 0.47766253643826434
A[9, 3] = -2.4881146199716677
A[9, 4] = -0.590290826836843
A[9, 5] = 21.230051448181193
A[9, 6] = 15.279233632882423
A[9, 7] = -33.28821096898486
A[9, 8] = -0.020331201708508627
A[10, 0] = -0.9371424300859873
A[10, 3] = 5.186372428844064
A[10, 4] = 1.0914373489967295
A[10, 5] = -8.149787010746927
A[10, 6] = -18.52006565999696
A[10, 7] = 22.739487099350505
A[10, 8] = 2.4936055526796523
A[10, 9] = -3.0467644718982196
A[11, 0] = 2.273310147516538
A[11, 3] = -10.53449546673725
A[11, 4] = -2.0008720582248625
A[11, 5] = -17.9589318631188
A[11, 6] = 27.94888452941996
A[11, 7] = -2.8589982771350235
A[11, 8] = -8.87285693353063
A[11, 9] = 12.360567175794303
A[11, 10] = 0.6433927460157636
A[12, 0] = 0.054293734116568765
A[12, 5] = 4.450312892752409
A[12, 6] = 1.8915178993145003
A[12, 7] = -5.801203960010585
A[12, 8] = 0.3111643669578199
A[12, 9] = -0.1521609496625161
A[12, 10] = 0.20136540080403034
A[12, 11] = 0.04471061572777259
A[13, 0] = 0.056167502283047954
A[13, 6] = 0.25350021021662483
A[13, 7] = -0.2462390374708025
A[13, 8] = -0.12419142326381637
A[13, 9] = 0.15329179827876568
A[13, 10] = 0.00820105229563469
A[13, 11] = 0.007567897660545699
A[13, 12] = -0.008298
A[14, 0] = 0.03183464816350214
A[14, 5] = 0.028300909672366776
A[14, 6] = 0.053541988307438566
A[14, 7] = -0.05492374857139099
A[14, 10] = -0.00010834732869724932
A[14, 11] = 0.0003825710908356584
A[14, 12] = -0.00034046500868740456
A[14, 13] = 0.1413124436746325
A[15, 0] = -0.42889630158379194
A[15, 5] = -4.697621415361164
A[15, 6] = 7.683421196062599
A[15, 7] = 4.06898981839711
A[15, 8] = 0.3567271874552811
A[15, 12] = -0.0013990241651590145
A[15, 13] = 2.9475147891527724
A[15, 14] = -9.15095847217987
E3 = np.zeros(13)
E3[0] = -0.18980075407240762
E3[5] = 4.450312892752409
E3[6] = 1.8915178993145003
E3[7] = -5.801203960010585
E3[8] = -0.4226823213237919
E3[9] = -0.1521609496625161
E3[10] = 0.20136540080403034
E3[11] = 0.02265179219836082
E5 = np.zeros(13)
E5[0] = 0.01312004499419488
E5[5] = -1.2251564463762044
E5[6] = -0.4957589496572502
E5[7] = 1.6643771824549864
E5[8] = -0.35032884874997366
E5[9] = 0.3341791187130175
E5[10] = 0.08192320648511571
E5[11] = -0.022355307863886294
D = np.zeros((4, 16))
D[0, 0] = -8.428938276109013
D[0, 5] = 0.5667149535193777
D[0, 6] = -3.0689499459498917
D[0, 7] = 2.38466765651207
D[0, 8] = 2.117034582445028
D[0, 9] = -0.871391583777973
D[0, 10] = 2.2404374302607883
D[0, 11] = 0.6315787787694688
D[0, 12] = -0.08899033645133331
D[0, 13] = 18.148505520854727
D[0, 14] = -9.194632392478356
D[0, 15] = -4.436036387594894
D[1, 0] = 10.427508642579134
D[1, 5] = 242.28349177525817
D[1, 6] = 165.20045171727028
D[1, 7] = -374.5467547226902
D[1, 8] = -22.113666853125306
D[1, 9] = 7.733432668472264
D[1, 10] = -30.674084731089398
D[1, 11] = -9.332130526430229
D[1, 12] = 15.697238121770845
D[1, 13] = -31.139403219565178
D[1, 14] = -9.35292435884448
D[1, 15] = 35.81684148639408
D[2, 0] = 19.985053242002433
D[2, 5] = -387.0373087493518
D[2, 6] = -189.17813819516758
D[2, 7] = 527.8081592054236
D[2, 8] = -11.57390253995963
D[2, 9] = 6.8812326946963
D[2, 10] = -1.0006050966910838
D[2, 11] = 0.7777137798053443
D[2, 12] = -2.778205752353508
D[2, 13] = -60.19669523126412
D[2, 14] = 84.32040550667716
D[2, 15] = 11.99229113618279
D[3, 0] = -25.69393346270375
D[3, 5] = -154.18974869023643
D[3, 6] = -231.5293791760455
D[3, 7] = 357.6391179106141
D[3, 8] = 93.40532418362432
D[3, 9] = -37.45832313645163
D[3, 10] = 104.0996495089623
D[3, 11] = 29.8402934266605
D[3, 12] = -43.53345659001114
D[3, 13] = 96.32455395918828
D[3, 14] = -39.17726167561544
D[3, 15] = -149.72683625798564


@jit
def _dense_coefficients(rhs, t, h, y, y_new, K, F, ytmp, p):
    """The three extra stages and the seven coefficient rows of the interpolant."""
    n = y.shape[0]
    for s in range(13, 16):
        for i in range(n):
            acc = 0.0
            for r in range(s):
                acc += A[s, r] * K[r, i]
            ytmp[i] = y[i] + h * acc
        rhs(t + C[s] * h, ytmp, p, K[s])
    for i in range(n):
        dy = y_new[i] - y[i]
        F[0, i] = dy
        F[1, i] = h * K[0, i] - dy
        F[2, i] = 2.0 * dy - h * (K[12, i] + K[0, i])
        for m in range(4):
            acc = 0.0
            for r in range(16):
                acc += D[m, r] * K[r, i]
            F[3 + m, i] = h * acc


def _solve(rhs, sing, uev, t0, t_end, y0, p, rtol, atol, first_step, max_step, max_steps,
           t_eval, mode, n_sing, sing_tol, ev_dir, ev_max, halt):
    """Integrate y' = rhs(t, y, p) from t0 to t_end.

    ``sing`` computes ``n_sing`` singularity indicators (stop where one of them crosses
    zero or falls below ``sing_tol`` times its initial size; ``n_sing = 0`` disables) and
    ``uev`` the ``ev_dir.shape[0]`` user event functions (direction ``ev_dir``, terminal at
    the ``ev_max``-th occurrence, 0 = never); see ``_events``.  The loop stops with
    status STOPPED before a step when ``halt[0]`` is nonzero (set by another thread).

    Returns ``(status, ts, ys, n_out, stats, t, y, ev_t, ev_i, ev_y, n_ev, sing_index)``:
    the output rows ``ts[:n_out]``, ``ys[:n_out]`` (every accepted step, the points of
    ``t_eval``, or the two endpoints, by ``mode``), ``stats = [accepted, rejected, rhs
    evaluations]``, the last state, the event records (time, event index, state) and the
    index of the indicator that stopped the integration (-1 if none).
    """
    n = y0.shape[0]
    direction = 1.0 if t_end >= t0 else -1.0
    interval = abs(t_end - t0)
    K = np.empty((16, n))
    F = np.empty((7, n))
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
    # events and singularity indicators
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
            for s in range(1, N_STAGES):
                for i in range(n):
                    acc = 0.0
                    for r in range(s):
                        acc += A[s, r] * K[r, i]
                    ytmp[i] = y[i] + h * acc
                rhs(t + C[s] * h, ytmp, p, K[s])
            for i in range(n):
                acc = 0.0
                for r in range(N_STAGES):
                    acc += A[12, r] * K[r, i]
                y_new[i] = y[i] + h * acc
            rhs(t_new, y_new, p, K[12])
            stats[2] += 12
            e5 = 0.0
            e3 = 0.0
            for i in range(n):
                a5 = 0.0
                a3 = 0.0
                for r in range(13):
                    a5 += E5[r] * K[r, i]
                    a3 += E3[r] * K[r, i]
                sc = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol
                e5 += (a5 / sc) ** 2
                e3 += (a3 / sc) ** 2
            if e5 == 0.0 and e3 == 0.0:
                err = 0.0
            else:
                err = abs(h) * e5 / math.sqrt((e5 + 0.01 * e3) * n)
            if not math.isfinite(err) or not all_finite(K[12]):
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
                        _dense_coefficients(rhs, t, h, y, y_new, K, F, ytmp, p)
                        stats[2] += 3
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
                    _dense_coefficients(rhs, t, h, y, y_new, K, F, ytmp, p)
                    stats[2] += 3
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
                    _dense_coefficients(rhs, t, h, y, y_new, K, F, ytmp, p)
                    stats[2] += 3
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
        copy_into(K[0], K[12])
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
