"""The classical fourth-order Runge-Kutta method with a fixed step.

- Order 4; four right-hand-side evaluations per step; no error estimate.
- ``n_steps`` equal steps of ``h = (t_end - t0) / n_steps``.

Reference: W. Kutta, "Beitrag zur naeherungsweisen Integration totaler
Differentialgleichungen", Z. Math. Phys. 46 (1901) 435-453; E. Hairer, S. P. Norsett,
G. Wanner, *Solving Ordinary Differential Equations I*, section II.1.

``solver()`` returns the compiled ``solve(rhs, ...)``; ``rhs`` is a first-class numba
function (``_common.RHS``), so the loop is compiled once for every scene and cached on
disk, and only the right-hand side is compiled per scene.
"""

import numba
import numpy as np

from ._common import (
    ENDPOINTS, ENSEMBLE_OUT, FINISHED, NONFINITE, RHS, STOPPED, all_finite, collect, compiled,
    copy_into, f8, i8, store)
from ._events import (SINGULAR, any_user_active, hermite_defect, hermite_rows, locate,
                      most_watched, sing_dip, sing_init, sing_violated, sing_watch)

ORDER = 4
STAGES_PER_STEP = 4
#: relative defect of the step's Hermite interpolant that marks a kink (see below)
KINK = 0.25


def _solve(rhs, sing, uev, t0, t_end, y0, p, n_steps, mode, n_sing, sing_tol, ev_dir,
           ev_max, halt):
    """``n_steps`` RK4 steps from t0 to t_end.

    Returns ``(status, ts, ys, n_out, stats, t, y, ev_t, ev_i, ev_y, n_ev, sing_index)`` as
    the adaptive methods do (``stats = [steps, 0, rhs evaluations]``); ``mode`` ENDPOINTS
    stores only the ends.  Events and singularity indicators are located on the cubic
    Hermite interpolant of the step (one extra evaluation in a step that needs it).
    A fixed step can jump over a zero that an indicator only touches (the Appell-Hamel
    speed at a velocity reversal) and settle on a spurious state; so where an indicator
    is watched (below 1 % of its initial size) and the interpolant's defect at the
    middle of the step exceeds ``KINK`` (the right-hand side has a kink in the step),
    the run stops at the start of that step as a singular stop.
    """
    n = y0.shape[0]
    h = (t_end - t0) / n_steps
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    ytmp = np.empty(n)
    y_new = np.empty(n)
    y_stop = np.empty(n)
    F = np.empty((3, n))
    y = y0.copy()
    stats = np.zeros(3, dtype=np.int64)
    cap = 2 if mode == ENDPOINTS else n_steps + 1
    ts = np.empty(cap)
    ys = np.empty((cap, n))
    n_out = np.int64(0)
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
    ts, ys, n_out = store(ts, ys, n_out, t, y)
    sing_index = sing_init(sing, n_sing, sing_tol, t, y, p, gs, sig, eps, gref)
    copy_into(gs_old, gs)
    if sing_index >= 0:
        return SINGULAR, ts, ys, n_out, stats, t, y, ev_t, ev_i, ev_y, n_ev, sing_index
    if n_user > 0:
        uev(t, y, p, gu_old)
    status = FINISHED
    for step in range(n_steps):
        if halt[0] != 0:
            status = STOPPED
            break
        rhs(t, y, p, k1)
        for i in range(n):
            ytmp[i] = y[i] + 0.5 * h * k1[i]
        rhs(t + 0.5 * h, ytmp, p, k2)
        for i in range(n):
            ytmp[i] = y[i] + 0.5 * h * k2[i]
        rhs(t + 0.5 * h, ytmp, p, k3)
        for i in range(n):
            ytmp[i] = y[i] + h * k3[i]
        rhs(t + h, ytmp, p, k4)
        stats[2] += 4
        for i in range(n):
            y_new[i] = y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        if not all_finite(y_new):
            status = NONFINITE
            break
        t_new = t0 + (step + 1) * h
        stats[0] += 1
        stop = 0
        t_stop = t_new
        if n_sing > 0 or n_user > 0:
            si = -1
            theta_hi = 1.0
            active = False
            have_dense = False
            if n_sing > 0:
                si = sing_violated(sing, n_sing, t_new, y_new, p, gs, sig, eps)
                if si < 0 and sing_watch(n_sing, gs_old, gs, sig, gref):
                    rhs(t_new, y_new, p, k2)
                    stats[2] += 1
                    hermite_rows(t_new - t, y, y_new, k1, k2, F)
                    have_dense = True
                    theta_hi = sing_dip(sing, n_sing, t, t_new - t, y, F, p, gs_old, sig,
                                        eps, gref, ytmp)
                    if theta_hi > 0.0:
                        si = 0
                    elif hermite_defect(rhs, t, t_new - t, y, F, p, ytmp, k3) > KINK:
                        # the step straddles a kink next to a watched indicator: stop at
                        # its start (theta_hi below the resolution of t)
                        stats[2] += 1
                        si = most_watched(n_sing, gs, sig, gref)
                        theta_hi = 1e-300
                    else:
                        stats[2] += 1
                        theta_hi = 1.0
                copy_into(gs_old, gs)
                active = si >= 0
            if n_user > 0:
                uev(t_new, y_new, p, gu_new)
                if any_user_active(gu_old, gu_new, ev_dir):
                    active = True
            if active:
                if not have_dense:
                    rhs(t_new, y_new, p, k2)
                    stats[2] += 1
                    hermite_rows(t_new - t, y, y_new, k1, k2, F)
                stop, t_stop, sing_index, ev_t, ev_i, ev_y, n_ev = locate(
                    sing, uev, n_sing, si, theta_hi, t, t_new - t, y, F, p, gs, sig, eps,
                    gu_old, gu_new, ev_dir, ev_max, counts, ytmp, gtmp, roots, which, ev_t,
                    ev_i, ev_y, n_ev, y_stop)
            for i in range(n_user):
                gu_old[i] = gu_new[i]
        if stop != 0:
            t = t_stop
            copy_into(y, y_stop)
            status = stop
            if mode != ENDPOINTS and t != ts[n_out - 1]:   # a stop at the step's start
                ts, ys, n_out = store(ts, ys, n_out, t, y)  # is the row stored already
            break
        copy_into(y, y_new)
        t = t_new
        if mode != ENDPOINTS:
            ts, ys, n_out = store(ts, ys, n_out, t, y)
    if mode == ENDPOINTS:
        ts, ys, n_out = store(ts, ys, n_out, t, y)
    return status, ts, ys, n_out, stats, t, y, ev_t, ev_i, ev_y, n_ev, sing_index


ARGS = (RHS, RHS, RHS, f8, f8, f8[::1], f8[::1], i8, i8, i8, f8, i8[::1], i8[::1], i8[::1])


def solver():
    """The compiled ``solve(rhs, sing, uev, t0, t_end, y0, p, n_steps, mode, n_sing,
    sing_tol, ev_dir, ev_max, halt)``; ``halt[0]`` nonzero stops the loop (STOPPED)."""
    return compiled(_solve, ARGS)


# ---------------------------------------------------------------------- ensembles
def _ensemble_parallel(rhs, sing, uev, t0, t_end, Y0, P, n_steps, mode, n_sing, sing_tol,
                       ev_dir, ev_max, halt, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T):
    for r in numba.prange(Y0.shape[0]):
        res = _SOLVE(rhs, sing, uev, t0, t_end, Y0[r], P[r], n_steps, mode, n_sing,
                     sing_tol, ev_dir, ev_max, halt)
        collect(r, res, mode, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T)


def _ensemble_serial(rhs, sing, uev, t0, t_end, Y0, P, n_steps, mode, n_sing, sing_tol,
                     ev_dir, ev_max, halt, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T):
    for r in range(Y0.shape[0]):
        res = _SOLVE(rhs, sing, uev, t0, t_end, Y0[r], P[r], n_steps, mode, n_sing,
                     sing_tol, ev_dir, ev_max, halt)
        collect(r, res, mode, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T)


ENSEMBLE_ARGS = ARGS[:5] + (f8[:, ::1], f8[:, ::1]) + ARGS[7:] + ENSEMBLE_OUT
_SOLVE = None


def ensemble_solver(parallel=True):
    """The compiled ensemble driver (see ``dop853.ensemble_solver``)."""
    global _SOLVE
    _SOLVE = solver()
    return compiled(_ensemble_parallel if parallel else _ensemble_serial, ENSEMBLE_ARGS,
                    parallel=parallel)
