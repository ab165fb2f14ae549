"""The one compiled loop of the explicit Runge-Kutta methods.

A method is a small immutable value, ``ExplicitRK`` (its tableau, order, error estimator
and dense output; one short module each: ``dopri5``, ``dop853``, ``rk4``); the loop
``_solve`` reads the method's arrays as compile-time constants (``_specialised``: one
compilation per method, at the per-evaluation cost of a hand-written loop) and does
everything else: the first step, adaptive step control (Hairer-Norsett-Wanner I, II.4,
with scipy's constants) or equal fixed steps, the budgets (``max_steps``, the ``halt``
flag of ``interrupt``), singularity stops and user events on the dense output
(``_events``), and the output (every step, the points of ``t_eval``, or the two ends).
Each method's loop serves every scene (the right-hand side is a callback at an address)
and is cached on disk; ensembles run the same loop over the rows of an array
(``ensemble_solver``).

Arithmetic: a stage is ``y + h * sum_r A[s, r] K[r]`` summed over the earlier stages in
order, the new state ``y + (h / b_den) * sum_r B[r] K[r]``, written out per method with
its nonzero coefficients only (``sums``); with these forms the results are those of the
hand-written loops of each method that preceded this one, bit for bit
(``tests/test_numeric_reference.py``).

Error estimators (``error``): ``EMBEDDED`` the RMS norm of ``h sum_r E[r] K[r]`` over the
stages and ``f(t + h, y_new)`` (DOPRI5); ``DOP853`` Hairer's combination of a 5th- and a
3rd-order estimate (rows ``E`` and ``E3``); ``NONE`` (fixed step).  Dense output (``dense``,
in the form of ``_events.dense_eval``): ``HERMITE`` the cubic Hermite rows of the step
plus ``D @ K`` rows (DOPRI5's ``contd5``; plain Hermite for RK4), ``DOP853`` Hairer's
``contd8`` with three extra stages (rows ``n_stages + 1 ..`` of ``A``), ``GIVEN`` rows the
method fills itself (radau's collocation polynomial).  ``after_step`` and ``output`` are
what every loop does after an accepted step, ``_common.start`` what it does first (radau's
too).

Stiffness (``stiff_bound`` > 0: dopri5, dop853): Hairer's test of DOPRI5 and DOP853
(HNW II, IV.2; ``stiff_ratio``).  The method's last stage and ``f(t + h, y_new)`` are
both taken at t + h, at two states a local error apart, so the ratio of their
differences estimates h |lambda| for the dominant eigenvalue of the Jacobian there.
Every ``STIFF_EVERY``-th accepted step, and after every step once a test was positive,
it is compared with the method's bound (a point near the boundary of its stability
region on the negative real axis: 3.25 for dopri5, 6.1 for dop853); ``STIFF_RUN``
positive tests in a row (``STIFF_RESET`` negative ones clear the count) stop the run
with status ``STIFF`` after the step (as Hairer's codes do): its steps are held by
stability, not by the tolerance, as on a stiff problem or on a motion that runs into a
singular set of the equations, and an explicit method would grind on at ~|lambda| steps
per unit of time, where radau follows the solution's own time scale.  The test reads
values the step computed anyway and changes no step (the accepted steps are those of a
run without it, bit for bit); it costs a counter a step and 2n products every
``STIFF_EVERY`` steps.  A watched singularity indicator that crawls toward zero
(``_events.sing_crawl``) for ``STIFF_RUN`` steps in a row stops the run as SINGULAR at
the end of the step.
"""

from __future__ import annotations

import math
from collections import namedtuple
from dataclasses import dataclass, field
from functools import cached_property

import numba
import numpy as np

from ._common import (
    AT_T_EVAL, ENDPOINTS, ENSEMBLE_OUT, EVENT, EVERY_STEP, FINISHED, MAX_FACTOR, MAX_STEPS,
    MIN_FACTOR, NONFINITE, SAFETY, SINGULAR, STIFF, STOPPED, TOO_SMALL_STEP, all_finite,
    apart, collect, compiled, copy_into, f8, function_at, i8, inline, jit, min_step, start,
    store, take_next)
from . import projection
from .sums import DOP853, EMBEDDED, NONE, functions as sums  # noqa: F401 (the codes)
from ._events import (CRAWL, any_user_active, dense_eval, hermite_defect, locate,
                      most_watched, crossed, near, sing_crawl, sing_dip, sing_init,
                      sing_watch)

#: dense outputs (see the module docstring; the error estimators: ``sums``)
HERMITE, GIVEN = 1, 3
#: relative defect of a fixed step's Hermite interpolant that marks a kink (``solve``)
KINK = 0.25
#: the stiffness test (module docstring, as in Hairer's codes): every STIFF_EVERY-th
#: accepted step (his NSTIFF default); STIFF_RUN positive tests in a row declare the
#: problem stiff, STIFF_RESET negative ones in a row clear the count
STIFF_EVERY, STIFF_RUN, STIFF_RESET = 1000, 15, 6

#: what every solve returns (``ev_t ev_i ev_y`` None where it recorded no event, ``y``
#: None where it then finished: its last time and state in row ``n_out``)
Result = namedtuple("Result", "status ts ys n_out stats t y ev_t ev_i ev_y n_ev sing_index")
#: the step control of one run: tolerances and limits (``n_steps`` > 0: fixed steps);
#: ``n_hol`` > 0: project every accepted step onto the ``n_hol`` holonomic constraints of
#: the first ``n_coord`` states (``projection``); ``n_sens`` > 0: the state is followed by
#: its sensitivities, ``n_sens`` columns a row, projected with it; ``edge`` > 0: the run
#: watches its chart's edge as its last event (``numeric.atlas``): a fixed step with a
#: stage past it stops at its start (``past_edge``), an adaptive step is no longer than
#: ``edge`` times the time to the singular set (``near_zero``); ``edge`` < 0 (an adaptive
#: run of ``atlas.run``'s quick route): a run that starts past that edge returns at once
#: as SINGULAR with ``sing_index`` ``PAST_EDGE``, else it runs as with ``edge`` = 0
Control = namedtuple("Control",
                     "rtol atol first_step max_step max_steps n_steps n_hol n_coord n_sens "
                     "edge", defaults=(0, 0, 0, 0.0))
#: what to watch: singularity indicators (``n_sing`` of them, threshold ``sing_tol``)
#: and user events (direction, terminal count)
Watch = namedtuple("Watch", "n_sing sing_tol ev_dir ev_max")
#: the ``sing_index`` of a run that started past its chart's edge (``Control.edge`` < 0)
PAST_EDGE = -2


@dataclass(frozen=True)
class ExplicitRK:
    """An explicit Runge-Kutta method as a value: nodes ``C``, stage matrix ``A`` (its rows
    past ``n_stages`` are the extra stages of the dense output), weights ``B / b_den``,
    error rows ``E`` (and ``E3``), dense-output rows ``D``; ``error`` and ``dense`` name
    the estimator and the interpolant (module docstring); ``stiff_bound`` > 0: the bound
    of h |lambda| of the stiffness test (module docstring; the last stage must be at
    C = 1)."""

    name: str
    order: int
    error_order: int
    C: np.ndarray
    A: np.ndarray
    B: np.ndarray
    error: int
    dense: int
    E: np.ndarray = field(default_factory=lambda: np.zeros(1))
    E3: np.ndarray = field(default_factory=lambda: np.zeros(1))
    D: np.ndarray = field(default_factory=lambda: np.zeros((0, 1)))
    b_den: float = 1.0
    stiff_bound: float = 0.0

    def __post_init__(self):
        if self.stiff_bound > 0.0 and self.C[self.n_stages - 1] != 1.0:
            raise ValueError(f"{self.name}: the stiffness test needs a last stage at C = 1")

    @property
    def n_stages(self) -> int:
        return self.B.shape[0]

    @property
    def adaptive(self) -> bool:
        return self.error != NONE

    @cached_property
    def arrays(self):
        """The method as the loop receives it (built once)."""
        info = np.array([self.n_stages, self.error, self.dense, self.error_order],
                        dtype=np.int64)
        f = np.ascontiguousarray
        return (f(self.C, dtype=float), f(self.A, dtype=float), f(self.B, dtype=float),
                f(self.E, dtype=float), f(self.E3, dtype=float), f(self.D, dtype=float),
                info, float(self.b_den))


@jit
def _dense_rows(tab, rhs, t, h, y, y_new, K, F, ytmp, p):
    """The rows of the step's interpolant (``_events.dense_eval``); K[n_stages] holds
    f(t + h, y_new).  Returns the number of extra rhs evaluations."""
    C, A, B, E, E3, D, info, b_den = tab
    ns = info[0]
    n = y.shape[0]
    if info[2] == GIVEN:             # filled by the method itself (radau)
        return 0
    if info[2] == DOP853:
        _stages(ns + 1, ns + 4, C, A, rhs, t, h, y, K, ytmp, p)
        for i in range(n):
            dy = y_new[i] - y[i]
            F[0, i] = dy
            F[1, i] = h * K[0, i] - dy
            F[2, i] = 2.0 * dy - h * (K[ns, i] + K[0, i])
            for m in range(D.shape[0]):
                acc = 0.0
                for r in range(D.shape[1]):
                    acc += D[m, r] * K[r, i]
                F[3 + m, i] = h * acc
        return 3
    for i in range(n):
        d = y_new[i] - y[i]
        F[0, i] = d
        F[1, i] = h * K[0, i] - d
        F[2, i] = d - h * K[ns, i] - F[1, i]
        for m in range(D.shape[0]):
            acc = 0.0
            for r in range(D.shape[1]):
                acc += D[m, r] * K[r, i]
            F[3 + m, i] = h * acc
    return 0


@inline
def _stages(first, last, C, A, rhs, t, h, y, K, ytmp, p):
    """Stages ``first .. last - 1``: K[s] = f(t + C[s] h, y + h sum_{r < s} A[s, r] K[r])
    (DOP853's extra dense-output stages; the steps' stages are ``sums.source``)."""
    for s in range(first, last):
        for i in range(y.shape[0]):
            acc = 0.0
            for r in range(s):
                acc += A[s, r] * K[r, i]
            ytmp[i] = y[i] + h * acc
        rhs(t + C[s] * h, ytmp, p, K[s])


@inline
def stiff_ratio(h, y_new, y_last, f_new, f_last):
    """Hairer's estimate of h |lambda|: ``|h| |f_new - f_last| / |y_new - y_last|`` with
    ``f_last`` the last stage, taken at ``y_last`` and t + h, and ``f_new = f(t + h,
    y_new)`` (0 where the two states are equal)."""
    num = 0.0
    den = 0.0
    for i in range(y_new.shape[0]):
        num += (f_new[i] - f_last[i]) ** 2
        den += (y_new[i] - y_last[i]) ** 2
    if den > 0.0:
        return abs(h) * math.sqrt(num / den)
    return 0.0


@inline
def workspace(n_sing, n_user):
    """The arrays of the singularity indicators and the user events (``after_step``),
    rows of two allocations: ``(gs, gs_old, gref, sig, eps)`` of the indicators (their
    values at the step's end and start, initial sizes, signs, thresholds), ``(gu_old,
    gu_new, gtmp, roots)`` and ``(counts, which)`` of the user events, then the rates at
    which the indicators approach zero (``near_zero``)."""
    G = np.empty((10, max(n_sing, n_user, 1)))
    C = np.zeros((2, max(n_user, 1)), dtype=np.int64)
    return G[0], G[1], G[2], G[3], G[4], G[5], G[6], G[7], C[0], G[8], C[1], G[9]


@inline
def outputs(n, mode, t_eval, cap_steps):
    """The output arrays ``(ts, ys, n_out, j_eval)`` of a run in ``mode``: room for the
    points of ``t_eval``, the two ends, or ``cap_steps`` steps (grown as needed), and a
    row for the last time and state (``_solve``)."""
    if mode == AT_T_EVAL:
        cap = t_eval.shape[0]
    elif mode == ENDPOINTS:
        cap = 2
    else:
        cap = cap_steps
    return np.empty(cap + 1), np.empty((cap + 1, n)), np.int64(0), np.int64(0)


@inline
def watch_start(sing, uev, watch, t, y, p):
    """The watched quantities at the start (t, y): their workspace (``workspace``) and
    the index of an indicator that is singular there already (-1: none)."""
    n_sing, sing_tol, ev_dir, _ = watch
    ws = workspace(n_sing, ev_dir.shape[0])
    gs, gs_old, gref, sig, eps, gu_old = ws[:6]
    sing_index = sing_init(sing, n_sing, sing_tol, t, y, p, gs, sig, eps, gref)
    copy_into(gs_old, gs)
    if sing_index < 0 and ev_dir.shape[0] > 0:
        uev(t, y, p, gu_old)
    return ws, sing_index


@inline
def counts(stats):
    """``stats`` (accepted, rejected, evaluations) as the tuple a run returns: three
    integers box cheaply where an array, like every array a compiled call returns to
    Python, costs a fraction of a microsecond."""
    return stats[0], stats[1], stats[2]


@inline
def no_events(rows, ev_dir):
    """Empty event records (time, index, state) and their count: views of the loop's
    rows ``rows`` (n columns) and of the events' directions ``ev_dir`` (no allocation;
    ``_events.store_event`` allocates on the first record)."""
    return rows[0, :0], ev_dir[:0], rows[:0], np.int64(0)


@inline
def watch_result(res, n_user):
    """The tuple of a loop that watches (``_solve``'s, ``res``) as its entry returns it:
    the event records None where the run recorded no event (it watches no user events,
    ``n_user`` 0, or none occurred), and so is the last state where such a run finished
    (FINISHED): its last time and state are then row ``n_out`` of ``ts``, ``ys``, as in a
    loop that watches nothing.  An array returned to Python costs ~0.3 us to box, None
    nothing (``watching``)."""
    if n_user > 0 and res[10] > 0:
        return res
    status, ts, ys, n_out, stats, t, y, _, _, _, n_ev, sing_index = res
    if status == FINISHED:
        ts, ys, _ = store(ts, ys, n_out, t, y)
        return status, ts, ys, n_out, stats, t, None, None, None, None, n_ev, sing_index
    return status, ts, ys, n_out, stats, t, y, None, None, None, n_ev, sing_index


@inline
def finite_status(status, ys, n_out, y, n_sens):
    """``status``, or NONFINITE where it is a success (FINISHED, EVENT) with a NaN or an
    infinity in the states of the output rows ``ys[:n_out]`` or of the last state ``y``
    (each state followed by ``n_sens`` columns of sensitivities, not looked at): never a
    success with such a state."""
    if status != FINISHED and status != EVENT:
        return status
    n = y.shape[0] // (1 + n_sens)
    for i in range(n):
        if not math.isfinite(y[i]):
            return NONFINITE
    for k in range(n_out):
        for i in range(n):
            if not math.isfinite(ys[k, i]):
                return NONFINITE
    return status


@jit
def after_step(tab, fixed, rhs, sing, uev, p, t, h, t_new, y, y_new, K, F, ytmp, fmid, y_stop,
               stats, watch, ws, si, sing_index, ev_t, ev_i, ev_y, n_ev, first):
    """Singularity indicators and user events in the accepted step from (t, y) to
    (t_new, y_new) that ``_events.watch_end`` found needing more than their values at the
    ends (``si``: the index of an indicator violated at the end, or -1; ``first``: the
    step is the run's first, ``_events.crossed``): the search
    inside the step (``_events.sing_dip``) and the location of stops and events
    (``_events.locate``).  Returns ``(stop, t_stop, sing_index, have_dense, ev_t, ev_i,
    ev_y, n_ev)``: stop is 0 (go on), EVENT or SINGULAR, with the stop state in
    ``y_stop``; ``have_dense``: the rows F of the step's interpolant are filled.  The
    caller moves the end's values to the next step's start (``_events.watch_next``)."""
    n_sing, sing_tol, ev_dir, ev_max = watch
    gs, gs_old, gref, sig, eps, gu_old, gu_new, gtmp, counts, roots, which = ws[:11]
    ns = tab[6][0]
    have_dense = False
    stop = 0
    t_stop = t_new
    theta_hi = 1.0
    if n_sing > 0 and si < 0 and sing_watch(n_sing, gs_old, gs, sig, gref):
        if fixed:
            rhs(t_new, y_new, p, K[ns])
            stats[2] += 1
        stats[2] += _dense_rows(tab, rhs, t, h, y, y_new, K, F, ytmp, p)
        have_dense = True
        theta_hi = sing_dip(sing, n_sing, t, h, y, F, p, gs_old, gs, sig, eps, gref,
                            ytmp)
        if theta_hi > 0.0:
            si = 0
        elif fixed:
            stats[2] += 1
            if hermite_defect(rhs, t, h, y, F, p, ytmp, fmid) > KINK:
                # the step straddles a kink next to a watched indicator: stop at its
                # start (theta_hi below the resolution of t)
                si = most_watched(n_sing, gs, sig, gref)
                theta_hi = 1e-300
            else:
                theta_hi = 1.0
        else:
            theta_hi = 1.0
    if si >= 0 or any_user_active(gu_old, gu_new, ev_dir, first):
        if not have_dense:
            if fixed:
                rhs(t_new, y_new, p, K[ns])
                stats[2] += 1
            stats[2] += _dense_rows(tab, rhs, t, h, y, y_new, K, F, ytmp, p)
            have_dense = True
        stop, t_stop, sing_index, ev_t, ev_i, ev_y, n_ev = locate(
            sing, uev, n_sing, si, theta_hi, t, h, y, F, p, gs, sig, eps, gu_old,
            gu_new, ev_dir, ev_max, counts, ytmp, gtmp, roots, which, ev_t, ev_i, ev_y,
            n_ev, y_stop, first)
    return stop, t_stop, sing_index, have_dense, ev_t, ev_i, ev_y, n_ev


@inline
def near_zero(n_sing, g_old, g_new, sig, h_abs, h_prev, rate):
    """The time in which the singularity indicators would reach zero from the end of a
    step of length ``h_abs`` (values g_old, g_new; inf: none does): how far the step's
    end is from the singular set, in time.  Each indicator moves toward zero at the mean
    rate over the step (kept in ``rate`` for the next), accelerating as from the mean
    rate of the step before (of length ``h_prev``; 0: none): a quadratic in time, right
    also where an indicator just turned toward zero (sin theta at its top).  In a run
    that changes chart (``Control.edge``) the next adaptive step is no longer than
    ``edge`` times it: near its singular set a chart's right-hand side has a pole
    (phi^alpha = A_alpha^-1 (...)), and a step whose length is comparable to its
    distance from the pole has a local error that the embedded estimate, an expansion
    in h, misses (dop853 accepts it at 100 times its usual error)."""
    out = np.inf
    for i in range(n_sing):
        b = sig[i] * g_new[i]
        r = (sig[i] * g_old[i] - b) / h_abs
        a = 0.0
        if h_prev > 0.0:
            a = max(0.0, (r - rate[i]) * 2.0 / (h_abs + h_prev))
        rate[i] = r
        v = r + 0.5 * a * h_abs             # the rate at the end
        if b > 0.0:
            if v > 0.0:
                out = min(out, 2.0 * b / (v + math.sqrt(v * v + 2.0 * a * b)))
            elif a > 0.0:
                out = min(out, (math.sqrt(v * v + 2.0 * a * b) - v) / a)
    return out


@inline
def past_edge(uev, n_user, C, A, ns, t, h, y, K, p, ytmp, g):
    """Whether a stage state y + h sum_r A[s, r] K[r] of a fixed step (s = 1 .. ns - 1)
    is past the chart's edge, the last of the ``n_user`` events (negative there, or not
    finite): a stage that ran into the band around the chart's singular set, where the
    step's end, even where it is regular, is not to be trusted (``Control.edge``)."""
    for s in range(1, ns):
        for i in range(y.shape[0]):
            acc = 0.0
            for r in range(s):
                acc += A[s, r] * K[r, i]
            ytmp[i] = y[i] + h * acc
        uev(t + C[s] * h, ytmp, p, g)
        if not g[n_user - 1] > 0.0:
            return True
    return False


@jit
def output(tab, fixed, rhs, p, t, h, t_new, y, y_new, K, F, ytmp, y_stop, stop, t_stop,
           have_dense, stats, mode, t_eval, j_eval, direction, ts, ys, n_out):
    """The output rows of an accepted step (``mode``); returns ``(ts, ys, n_out,
    j_eval)``."""
    if mode == AT_T_EVAL:
        while j_eval < t_eval.shape[0] and direction * (t_eval[j_eval] - t_stop) <= 0.0:
            if not have_dense:
                stats[2] += _dense_rows(tab, rhs, t, h, y, y_new, K, F, ytmp, p)
                have_dense = True
            dense_eval((t_eval[j_eval] - t) / h, y, F, ytmp)
            ts, ys, n_out = store(ts, ys, n_out, t_eval[j_eval], ytmp)
            j_eval += 1
    elif mode == EVERY_STEP:
        if stop == 0:
            ts, ys, n_out = store(ts, ys, n_out, t_new, y_new)
        elif not fixed or t_stop != ts[n_out - 1]:   # a fixed step's stop at its start
            ts, ys, n_out = store(ts, ys, n_out, t_stop, y_stop)  # is stored already
    return ts, ys, n_out, j_eval


def _solve(rhs_at, sing_at, uev_at, hol_at, t0, t_end, y0, p, ctl, t_eval, mode, watch,
           halt):
    """Integrate y' = rhs(t, y, p) from t0 to t_end with the method ``TAB``
    (``ExplicitRK.arrays``; it, ``ADAPTIVE`` and the parts ``WATCH``, ``PROJECT``,
    ``DENSE``, ``STEPS`` are compile-time constants, so the path of the other step kind and the
    parts the run does not need are not compiled: ``_specialised``) under the step control
    ``ctl`` (``Control``), watching ``watch`` (``Watch``: ``sing`` computes the ``n_sing``
    singularity indicators, ``uev`` the user event functions; see ``_events``); ``hol``
    the holonomic constraints an accepted step is projected onto when ``ctl.n_hol`` > 0
    (``projection``; the step's last stage is then evaluated again at the projected
    state); the four are the addresses of their C callbacks (``_common.function_at``).
    ``mode``:
    EVERY_STEP, AT_T_EVAL or ENDPOINTS.  The loop stops with status STOPPED before a step
    when ``halt[0]`` is nonzero.

    Returns the fields of a ``Result`` as a plain tuple (numba boxes a namedtuple by
    unpickling its class on every call; ``numeric.loops.call`` makes it a ``Result``):
    the status (never a success with a NaN or an infinity in the rows or the last state:
    ``finite_status``), the output rows ``ts[:n_out]``, ``ys[:n_out]``, ``stats =
    (accepted, rejected, rhs evaluations)`` (``counts``), the last time and state, the
    event records (time, index, state; the loop's entry returns None for them where the
    run recorded none, and None for the last state where such a run finished, its last
    time and state then in row ``n_out``: ``watch_result``), their count and the index of the
    indicator that stopped the run (-1 if none); a run that stopped in a step (EVENT,
    SINGULAR) has that step's start in row ``n_out`` of ``ts``, ``ys`` (``atlas``).  A
    loop that watches nothing (``WATCH`` false) records no events
    and returns ``(status, ts, ys, n_out, stats, sing_index)`` with the last time and
    state in row ``n_out`` of ``ts``, ``ys``: every array a compiled call returns is boxed
    at ~0.4 us, more than a short run's arithmetic.

    Fixed steps (``ctl.n_steps > 0``, methods without an error estimate): equal steps
    ``(t_end - t0) / n_steps``; events and indicators are located on the cubic Hermite
    interpolant (one extra evaluation in a step that needs it).  A fixed step can jump
    over a zero that an indicator only touches (the Appell-Hamel speed at a velocity
    reversal) and settle on a spurious state; so where an indicator is watched (below
    1 % of its initial size) and the interpolant's defect at the middle of the step
    exceeds ``KINK``, the run stops at the start of that step as a singular stop.
    """
    rhs, sing, uev, hol = (function_at(rhs_at), function_at(sing_at), function_at(uev_at),
                           function_at(hol_at))
    tab = TAB
    A, D = tab[1], tab[5]
    ns, _, _, error_order = SHAPE
    rtol, atol, max_steps, n_steps = ctl.rtol, ctl.atol, ctl.max_steps, ctl.n_steps
    max_step = ctl.max_step
    n = y0.shape[0]
    direction = 1.0 if t_end >= t0 else -1.0
    # the stages K, the interpolant's rows F and six states: rows of one allocation
    n_k = max(A.shape[0], ns + 1)
    n_f = 3 + D.shape[0]
    rows = np.empty((n_k + n_f + 6, n))
    K = rows[:n_k]
    F = rows[n_k:n_k + n_f]
    y, y_new, ytmp, fmid, y_stop, scale = (rows[n_k + n_f], rows[n_k + n_f + 1],
                                           rows[n_k + n_f + 2], rows[n_k + n_f + 3],
                                           rows[n_k + n_f + 4], rows[n_k + n_f + 5])
    copy_into(y, y0)
    stats = np.zeros(3, dtype=np.int64)
    ts, ys, n_out, j_eval = outputs(n, mode, t_eval, 64 if ADAPTIVE else n_steps + 1)
    t = t0
    if PROJECT:
        hw = projection.workspace(ctl.n_hol, ctl.n_coord, ctl.n_sens)
    if not ADAPTIVE:
        ts, ys, n_out = store(ts, ys, n_out, t, y)
    sing_index = -1
    if WATCH:
        n_sing, ev_dir = watch.n_sing, watch.ev_dir
        n_user = ev_dir.shape[0]
        ev_t, ev_i, ev_y, n_ev = no_events(F, ev_dir)
        ws, sing_index = watch_start(sing, uev, watch, t, y, p)
        gs, gs_old, gref, sig, eps, gu_old, gu_new, gtmp = ws[:8]
        rate = ws[11]
        if EDGE and ctl.edge < 0.0 and n_user > 0:
            # (the edge, the last event, at the start: negative, not NaN, is past it)
            if sing_index >= 0:
                uev(t, y, p, gu_old)
            if gu_old[n_user - 1] < 0.0:
                return (SINGULAR, ts, ys, n_out, counts(stats), t, y, ev_t, ev_i, ev_y,
                        n_ev, PAST_EDGE)
        if sing_index >= 0:
            if ADAPTIVE:
                ts, ys, n_out = store(ts, ys, n_out, t, y)
            return (SINGULAR, ts, ys, n_out, counts(stats), t, y, ev_t, ev_i, ev_y,
                    n_ev, sing_index)
    h_abs = 0.0
    g_edge = np.nan         # the edge's value at the last step's start (``Control.edge``)
    g_end = np.nan          # ... and at a fixed step's end before its projection
    h_prev = 0.0            # the length of the step before (``near_zero``)
    h_fixed = (t_end - t0) / max(n_steps, 1)
    exponent = -1.0 / (error_order + 1)
    if ADAPTIVE:
        go, h_abs, ts, ys, n_out = start(rhs, t, y, p, K[0], K[1], ytmp, scale, ctl,
                                         error_order, t_end, stats, mode, t_eval, ts, ys, n_out)
        if go >= 0:
            go = finite_status(go, ys, n_out, y, ctl.n_sens)
            if WATCH:
                return (go, ts, ys, n_out, counts(stats), t, y, ev_t, ev_i, ev_y, n_ev,
                        sing_index)
            ts, ys, _ = store(ts, ys, n_out, t, y)
            return go, ts, ys, n_out, counts(stats), sing_index
    status = FINISHED
    t_start = t
    step = 0
    stiff_run = 0           # positive stiffness tests in a row (Hairer's IASTI) ...
    calm_run = 0            # ... and negative ones since the last positive (NONSTI)
    stiff = False
    crawl_run = 0           # crawling steps in a row (``_events.sing_crawl``) ...
    h_watch = 0.0           # ... and the longest step since an indicator is watched
    while (direction * (t_end - t) > 0.0) if ADAPTIVE else (step < n_steps):
        if ADAPTIVE and stats[0] >= max_steps:
            status = MAX_STEPS
            break
        if halt[0] != 0:
            status = STOPPED
            break
        finite = True
        if ADAPTIVE:
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
                step_stages(rhs, t, h, y, K, ytmp, p)
                new_state(h, y, K, y_new)
                rhs(t_new, y_new, p, K[ns])
                stats[2] += ns
                err = step_error(h, y, y_new, K, rtol, atol)
                if not math.isfinite(err) or not all_finite(K[ns]):
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
            if STIFF_BOUND > 0.0 and (stiff_run > 0 or (stats[0] + 1) % STIFF_EVERY == 0):
                # ytmp holds the last stage's state (``sums``), K[ns - 1] its slope
                if stiff_ratio(h, y_new, ytmp, K[ns], K[ns - 1]) > STIFF_BOUND:
                    calm_run = 0
                    stiff_run += 1
                    stiff = stiff_run >= STIFF_RUN
                else:
                    calm_run += 1
                    if calm_run == STIFF_RESET:
                        stiff_run = 0
        else:
            rhs(t, y, p, K[0])
            step_stages(rhs, t, h_fixed, y, K, ytmp, p)
            new_state(h_fixed, y, K, y_new)
            stats[2] += ns
            finite = all_finite(y_new)
            if not finite and not (EDGE and ctl.edge > 0.0):
                status = NONFINITE
                break
            t_new = t0 + (step + 1) * h_fixed
            h = t_new - t
            if EDGE and PROJECT and ctl.edge > 0.0 and ctl.n_hol > 0 and n_user > 0:
                # the edge at the end as the stages left it: the projection would pull
                # a garbage end (a stage past the edge) back onto g = 0, where it may
                # look calm (``past_edge`` below)
                uev(t_new, y_new, p, gtmp)
                g_end = gtmp[n_user - 1]
        if PROJECT:
            if ctl.n_hol > 0:
                projection.project(hol, ctl, t_new, y_new, p, hw)
                if ADAPTIVE:
                    rhs(t_new, y_new, p, K[ns])
                    stats[2] += 1
        step += 1
        stats[0] += 1
        stop = 0
        t_stop = t_new
        have_dense = False
        if WATCH:
            # (written out here: a helper's array arguments cost a reference-count pair
            # each a step, more than the indicators themselves: ``_events.watch_end``)
            si = np.int64(-1)   # (not the literal -1: after_step is compiled once)
            more = False
            if n_sing > 0:
                sing(t_new, y_new, p, gs)
                for i in range(n_sing):
                    if si < 0 and not (sig[i] * gs[i] > eps[i]):      # also NaN
                        si = i
                    if near(sig[i], gs_old[i], gs[i], gref[i]):
                        more = True
                more = more or si >= 0
            if n_user > 0:
                uev(t_new, y_new, p, gu_new)
                for i in range(n_user):
                    if crossed(gu_old[i], gu_new[i], ev_dir[i], step == 1):
                        more = True
            if EDGE and not ADAPTIVE and ctl.edge > 0.0:
                # a fixed step that starts within two steps of the edge at the rate of
                # the step before, or whose edge value moved by half of it, or whose end
                # is not finite, may have had a stage past the edge (its end may look
                # regular all the same): then it stops at its start (a moment after it:
                # the start is the last state kept, ``atlas``)
                e = n_user - 1
                if n_sing > 0 and e >= 0:
                    g0 = gu_old[e]
                    calm = (finite and abs(gu_new[e] - g0) <= 0.5 * abs(g0)
                            and g0 >= 2.0 * (g_edge - g0))
                    if PROJECT and ctl.n_hol > 0:       # (and before the projection)
                        calm = calm and abs(g_end - g0) <= 0.5 * abs(g0)
                    g_edge = g0
                    if not calm and past_edge(uev, n_user, tab[0], A, ns, t, h, y, K, p,
                                              ytmp, gtmp):
                        more = False
                        stop = SINGULAR
                        t_stop = np.nextafter(t, t + direction)
                        sing_index = most_watched(n_sing, gs_old, sig, gref)
                        copy_into(y_stop, y)
                if stop == 0 and not finite:
                    status = NONFINITE
                    break
            watched = False
            crawling = -1
            if more:
                if ADAPTIVE and n_sing > 0:
                    watched, crawling = sing_crawl(n_sing, gs_old, gs, sig, gref)
                stop, t_stop, sing_index, have_dense, ev_t, ev_i, ev_y, n_ev = after_step(
                    tab, not ADAPTIVE, rhs, sing, uev, p, t, h, t_new, y, y_new, K, F, ytmp,
                    fmid, y_stop, stats, watch, ws, si, sing_index, ev_t, ev_i, ev_y, n_ev,
                    step == 1)
            if EDGE and ADAPTIVE and ctl.edge > 0.0 and stop == 0:
                h_abs = min(h_abs, ctl.edge * near_zero(n_sing, gs_old, gs, sig, abs(h),
                                                        h_prev, rate))
                h_prev = abs(h)
            for i in range(n_sing):
                gs_old[i] = gs[i]
            for i in range(n_user):
                gu_old[i] = gu_new[i]
            if ADAPTIVE and stop == 0 and n_sing > 0:
                if watched:
                    h_watch = max(h_watch, abs(h))
                    if crawling >= 0 and abs(h) < CRAWL * h_watch:
                        crawl_run += 1
                        if crawl_run >= STIFF_RUN:      # stop at the step's end
                            stop = SINGULAR
                            sing_index = crawling
                            copy_into(y_stop, y_new)
                    else:
                        crawl_run = 0
                else:
                    h_watch = 0.0
                    crawl_run = 0
        if WATCH or DENSE:
            if mode != ENDPOINTS:
                ts, ys, n_out, j_eval = output(tab, not ADAPTIVE, rhs, p, t, h, t_new, y,
                                               y_new, K, F, ytmp, y_stop, stop, t_stop,
                                               have_dense, stats, mode, t_eval, j_eval,
                                               direction, ts, ys, n_out)
        elif STEPS:
            if mode == EVERY_STEP:
                ts, ys, n_out = store(ts, ys, n_out, t_new, y_new)
        if stop != 0:
            t_start = t             # the step's start: row n_out at the end (``_solve``)
            copy_into(y_new, y)
            t = t_stop
            copy_into(y, y_stop)
            status = stop
            break
        t = t_new
        if ADAPTIVE:
            copy_into(y, y_new)
            copy_into(K[0], K[ns])
            if stiff:
                status = STIFF
                break
        else:           # (swapped: cheaper on rk4; on dop853 it costs more than the copy)
            y, y_new = y_new, y
    if mode == ENDPOINTS:
        ts, ys, n_out = store(ts, ys, n_out, t, y)
    status = finite_status(status, ys, n_out, y, ctl.n_sens)
    if WATCH:
        if status == EVENT or status == SINGULAR:
            ts, ys, _ = store(ts, ys, n_out, t_start, y_new)
        return (status, ts, ys, n_out, counts(stats), t, y, ev_t, ev_i, ev_y, n_ev,
                sing_index)
    ts, ys, _ = store(ts, ys, n_out, t, y)       # the last time and state: row n_out
    return status, ts, ys, n_out, counts(stats), sing_index


def _watching(rhs_at, sing_at, uev_at, hol_at, t0, t_end, y0, p, ctl, t_eval, mode, watch,
              halt):
    """The entry of a loop that watches: ``_solve`` (``body``, compiled apart) with its
    tuple made ``watch_result``'s.  (Returned from ``_solve`` itself, the optional
    records made numba's code for its steps slower: ~10 % a step.)"""
    return watch_result(body(rhs_at, sing_at, uev_at, hol_at, t0, t_end, y0, p, ctl, t_eval,
                             mode, watch, halt), watch.ev_dir.shape[0])


#: the method a specialised loop runs, its sums and that loop (``_specialised``; unbound
#: here), and a watching loop's body
TAB = SHAPE = ADAPTIVE = STIFF_BOUND = WATCH = PROJECT = DENSE = STEPS = EDGE = None
run = body = step_stages = new_state = step_error = None
_SPECIALISED = {}
CONTROL = numba.typeof(Control(1.0, np.zeros(1), 0.0, 1.0, 1, 0, 0, 0, 0))
WATCHED = numba.typeof(Watch(0, 0.0, np.zeros(1, dtype=np.int64),
                             np.zeros(1, dtype=np.int64)))
ARGS = (i8, i8, i8, i8, f8, f8, f8[::1], f8[::1], CONTROL, f8[::1], i8, WATCHED,
        i8[::1])
#: every part of the loop compiled (``features``)
ALL = (True, True, True, True)


def features(ctl, mode, watch) -> tuple[bool, bool, bool, bool]:
    """What a run needs of the loop: ``(watch, project, dense, steps)`` -- singularity
    indicators or user events, the projection onto holonomic constraints, output at
    ``t_eval`` (the step's interpolant), output of every step.  A loop compiled without a
    part serves only the runs that do not need it (``_specialised``): a run that keeps
    only its end or the points of ``t_eval`` runs a loop without the per-step store in
    its body (on rk4 that store costs ~5 % of a step even where it never runs)."""
    return (watch.n_sing > 0 or watch.ev_dir.shape[0] > 0, ctl.n_hol > 0,
            mode == AT_T_EVAL, mode == EVERY_STEP)


def _specialised(method, parts=ALL, edge=True):
    """The globals of this module with ``TAB`` bound to ``method.arrays``, the step's sums
    to the method's (``sums.functions``: its nonzero coefficients as literals), the parts
    of the loop a run needs (``WATCH, PROJECT, DENSE, STEPS = parts``: ``features``),
    ``EDGE`` (a watching loop's code for the runs with ``Control.edge`` > 0; ``edge``
    false: a loop for runs that never have it, as most ensembles: ``ensemble_solver``) and
    ``run`` to ``_solve`` compiled over them: each method's loop is compiled with its
    tableau (stage counts, coefficients) known, as the hand-written loops were, at the
    per-evaluation cost of theirs, and without the parts the run does not use (numba
    prunes the branches on these constants before typing them: a run without events,
    indicators, projection and ``t_eval`` compiles none of ``_events``, one that keeps
    only its end no per-step store).  Each loop has a name of its own (``compiled``:
    ``_solve_<method>_<parts>_<sources hash>``, the parts as the letters ``wpds``, and
    ``_noedge`` after them without ``EDGE``): numba links compiled functions by their
    mangled names, so two loops of one name could resolve to one another's machine code."""
    parts = tuple(bool(f) for f in parts)
    edge = bool(edge) and parts[0]          # (the edge is watched: nothing without WATCH)
    key = (method.name, parts, edge)
    if key not in _SPECIALISED:
        namespace = dict(globals())
        namespace["TAB"] = method.arrays
        namespace["SHAPE"] = tuple(int(k) for k in method.arrays[6])
        namespace["ADAPTIVE"] = method.adaptive
        namespace["STIFF_BOUND"] = float(method.stiff_bound)
        (namespace["WATCH"], namespace["PROJECT"], namespace["DENSE"],
         namespace["STEPS"]) = parts
        namespace["EDGE"] = edge
        helpers = sums(method)
        namespace["step_stages"] = helpers["stages"]
        namespace["new_state"] = helpers["new_state"]
        namespace["step_error"] = helpers["error"]
        tag = (method.name + ("" if parts == ALL else
                              "_" + "".join(c for c, f in zip("wpds", parts) if f))
               + ("_noedge" if parts[0] and not edge else ""))
        if parts[0]:
            namespace["body"] = apart(_solve, namespace, tag)
            namespace["run"] = compiled(_watching, ARGS, namespace=namespace, tag=tag)
        else:
            namespace["run"] = compiled(_solve, ARGS, namespace=namespace, tag=tag)
        _SPECIALISED[key] = namespace
    return _SPECIALISED[key]


def solver(method, parts=ALL):
    """The compiled ``solve(rhs_at, sing_at, uev_at, hol_at, t0, t_end, y0, p, ctl, t_eval,
    mode, watch, halt)`` (the callbacks' addresses) of the explicit method ``method``
    (``_solve`` over its tableau) with the ``parts`` of ``features`` (default: all; a run
    that needs a part the loop lacks is not to be given to it)."""
    return _specialised(method, parts)["run"]


# ---------------------------------------------------------------------- ensembles
# Two copies of one driver (numba's cache cannot hold a function compiled both with and
# without ``parallel``): run r of the ensemble is the loop on Y0[r], P[r].  In the parallel
# one, an iteration of ``prange`` takes the next run (``take_next``) until none is left:
# each thread's first iteration shares out the runs with the others, its later ones find
# none.  Runs differ in cost (their steps, early stops), and prange alone hands each
# thread a fixed block of them.  (No ``numba.get_num_threads()`` here: it would make the
# driver uncacheable.)
def _ensemble_parallel(rhs_at, sing_at, uev_at, hol_at, t0, t_end, Y0, P, ctl, t_eval, mode,
                       watch, halt, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T):
    n_runs = Y0.shape[0]
    taken = np.zeros(1, dtype=np.int64)
    for _ in numba.prange(n_runs):
        r = take_next(taken)
        while r < n_runs:
            res = run(rhs_at, sing_at, uev_at, hol_at, t0, t_end, Y0[r], P[r], ctl, t_eval,
                      mode, watch, halt)
            collect(r, res, mode, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T)
            r = take_next(taken)


def _ensemble_serial(rhs_at, sing_at, uev_at, hol_at, t0, t_end, Y0, P, ctl, t_eval, mode,
                     watch, halt, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T):
    for r in range(Y0.shape[0]):
        res = run(rhs_at, sing_at, uev_at, hol_at, t0, t_end, Y0[r], P[r], ctl, t_eval, mode,
                  watch, halt)
        collect(r, res, mode, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T)


ENSEMBLE_ARGS = ARGS[:6] + (f8[:, ::1], f8[:, ::1]) + ARGS[8:] + ENSEMBLE_OUT


def ensemble_solver(method, parallel=True, edge=False):
    """The compiled ensemble driver ``drive(rhs_at, sing_at, uev_at, hol_at, t0, t_end, Y0, P,
    ctl, t_eval, mode, watch, halt, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T)`` (the
    callbacks' addresses first) of the method ``method``: numba threads taking the runs
    one by one (``parallel``) or one loop (for a Python thread pool).  ``edge``: for runs
    with ``Control.edge`` > 0 (fixed steps that watch their chart's edge); the others'
    driver is without that code (``_specialised``), which they never run."""
    namespace = _specialised(method, ALL, edge)
    tag = method.name + ("" if edge else "_noedge")
    return compiled(_ensemble_parallel if parallel else _ensemble_serial, ENSEMBLE_ARGS,
                    parallel=parallel, namespace=namespace, tag=tag)


def watch_of(kern, compiled_events, singular: bool, singular_tol: float) -> Watch:
    """What a run of the kernels ``kern`` watches: their singularity indicators (if
    ``singular``) and the user events (``events.CompiledEvents`` or None)."""
    ce = compiled_events
    none = np.zeros(0, dtype=np.int64)
    return Watch(len(kern.layout.indicators) if singular else 0, float(singular_tol),
                 ce.direction if ce is not None else none,
                 ce.max_events if ce is not None else none)
