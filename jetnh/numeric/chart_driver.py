"""A run that changes chart, every piece of it in one compiled call.

``numeric.atlas.follow`` runs a switching run piece by piece from Python: the loop of a
chart to its edge, the start of the step that reached it (the loop leaves it in row
``n_out``), the result cut there, the change of chart (``chart_change``), the next
piece.  Each of those is a few microseconds of Python, as much as the pieces' own
arithmetic on a short run.  ``drive`` does the same in one compiled call for the runs
that need nothing else: an explicit method's loop (``loop.body`` of the plan's parts:
every chart's kernels are callbacks at addresses, so one loop serves them all), the
edge as the only event, no time budget, sensitivities or holonomic constraints, and
multipliers that keep their values across a change.  It takes the same decisions with
the same numbers (``follow``'s: the step start, ``_cut``, the hysteresis of the change,
the approach to the edge in eighth steps, ``_at_end``, the budget of steps across the
pieces, the halt flag before every step) and returns a record of the pieces, from which
``atlas`` makes the pieces ``follow`` would have made.  Where it meets what it does not
do -- a chart without kernels or events yet, a step start that needs the loop run again,
a piece that would watch nothing -- it hands the run back (``HANDED_BACK``) and the run
is made by ``follow`` from its start.

The record (``drive``'s return, ``_record``): ``(code, pieces, switches, rows, status,
steps, rejected, evaluations, partial, once, I, B)`` -- the last piece's status, the
counts summed over the pieces, whether the first piece's last step was partial and
whether the run was one piece that never reached the edge (what the run's Trajectory
needs at once), the integers ``I`` and one float array ``B`` holding ``F``, ``TS`` and
``YS`` one after the other (``F`` with a row per piece or switch, whichever are more;
every array a compiled call returns costs ~0.4 us to box); piece ``k``
has ``I[k] = (split, status, rows, steps, rejected, evaluations, events, singular index,
first row in TS/YS, max_steps, n_steps, partial last step, watched the edge, last event,
the plan's own control, cut at its last step's start)`` and ``F[k] = (t start, t end asked, t reached, event time,
max_step, switch time, y start, y reached, event state)``; switch ``j`` is
``(F[j, SW_T], I[j, SW_FROM], I[j, SW_TO])``.
"""

from __future__ import annotations

import functools
import math  # noqa: F401 (the compiled driver's globals)

import numba
import numpy as np

from . import chart_change
from .arguments import MIN_TIME_RESOLUTION
from .kernels import calls, loop_cache
from .methods import _common, loop
from .methods._common import (AT_T_EVAL, ENDPOINTS, EVENT, EVERY_STEP, FINISHED,  # noqa: F401
                              SINGULAR, f8, i8)
from .methods.loop import Control, Watch  # noqa: F401

#: ``drive``'s codes: the run is in the record, or handed back to ``follow``
DONE, HANDED_BACK = 0, 1
#: the columns of a piece's integers (``I``)
(C_SPLIT, C_STATUS, C_ROWS, C_STEPS, C_REJECTED, C_NFEV, C_NEV, C_SING, C_ROW0, C_MAXSTEPS,
 C_NSTEPS, C_PARTIAL, C_EDGE, C_EVI, C_FIRST, C_CUT, SW_FROM, SW_TO) = range(18)
#: the columns of a piece's floats (``F``), its three states after them
(C_T, C_TTO, C_TEND, C_EVT, C_MAXSTEP, SW_T) = range(6)
N_I, N_F = 18, 6
#: as ``atlas``: cuts of a step that crossed the edge, parts of an approach, the step
#: bound of a piece after the first (``atlas.NEAR``)
DEPTH, PARTS, NEAR = 4, 8, 0.25

_change = numba.njit(error_model="numpy", nogil=True)(chart_change._change)


@numba.njit(error_model="numpy", nogil=True)
def _room(I, F, k):
    """``I``, ``F`` with room for row ``k``."""
    if k < I.shape[0]:
        return I, F
    I2 = np.zeros((2 * I.shape[0], I.shape[1]), dtype=np.int64)
    F2 = np.zeros((2 * F.shape[0], F.shape[1]))
    I2[:I.shape[0]] = I
    F2[:F.shape[0]] = F
    return I2, F2


@numba.njit(error_model="numpy", nogil=True)
def _rows(TS, YS, m, n_new):
    """``TS``, ``YS`` with room for ``n_new`` rows after the first ``m``."""
    if m + n_new <= TS.shape[0]:
        return TS, YS
    cap = max(2 * TS.shape[0], m + n_new)
    TS2 = np.empty(cap)
    YS2 = np.empty((cap, YS.shape[1]))
    TS2[:m] = TS[:m]
    YS2[:m] = YS[:m]
    return TS2, YS2


@numba.njit(error_model="numpy", nogil=True)
def _record(code, n_p, n_sw, n_rows, I, F, TS, YS):
    """``_drive``'s return (the module docstring): the summary of its pieces, ``I``, and
    ``F[:max(n_p, n_sw)]``, ``TS[:n_rows]``, ``YS[:n_rows]`` copied into one array."""
    m = max(n_p, n_sw)
    w, n = F.shape[1], YS.shape[1]
    B = np.empty(m * w + n_rows * (1 + n))
    k = 0
    for r in range(m):
        for c in range(w):
            B[k] = F[r, c]
            k += 1
    for r in range(n_rows):
        B[k] = TS[r]
        k += 1
    for r in range(n_rows):
        for c in range(n):
            B[k] = YS[r, c]
            k += 1
    status = steps = rejected = nfev = 0
    for r in range(n_p):
        steps += I[r, C_STEPS]
        rejected += I[r, C_REJECTED]
        nfev += I[r, C_NFEV]
    if n_p > 0:
        status = I[n_p - 1, C_STATUS]
    partial = n_p > 0 and I[0, C_PARTIAL] != 0
    once = n_p == 1 and n_sw == 0 and I[0, C_CUT] == 0
    return code, n_p, n_sw, n_rows, status, steps, rejected, nfev, partial, once, I, B


def unpacked(record, n):
    """``(F, TS, YS)`` of a record ``(pieces, switches, rows, I, B)`` of ``drive`` of
    ``n`` states: views of ``B``."""
    n_p, n_sw, n_rows, _, B = record
    m = max(n_p, n_sw)
    w = N_F + 3 * n
    a = m * w
    return (B[:a].reshape(m, w), B[a:a + n_rows], B[a + n_rows:a + n_rows * (1 + n)]
            .reshape(n_rows, n))


def _drive(addr, n_sing, t0, t1, y0, p, ctl, t_eval, mode, sing_tol, edge_dir, edge_max,
           no_events, halt, table, caddr, eps, cur):
    n = y0.shape[0]
    N = addr.shape[0]
    if (addr.shape[1] < 4 or n_sing.shape[0] < N or table.shape[0] < N + 1
            or caddr.shape[1] < N or not 0 <= cur < N or table[0, 2] != n
            or table[0, 4] != N or edge_dir.shape[0] != 1 or edge_max.shape[0] != 1
            or p.shape[0] < table[0, 3]):
        raise ValueError("the arrays of a switching run do not fit its charts")
    I = np.zeros((4, N_I), dtype=np.int64)
    F = np.zeros((4, N_F + 3 * n))
    TS = np.empty(8)
    YS = np.empty((8, n))
    # the edge of the chart the run starts in, at its start (``atlas.own_edge``)
    if addr[cur, 0] == 0 or addr[cur, 2] == 0:
        return _record(HANDED_BACK, 0, 0, 0, I, F, TS, YS)
    g = np.empty(1)
    _common.function_at(addr[cur, 2])(t0, y0, p, g)
    if g[0] < 0.0:
        return _record(HANDED_BACK, 0, 0, 0, I, F, TS, YS)
    direction = 1.0 if t1 >= t0 else -1.0
    h_fixed = (t1 - t0) / ctl.n_steps if ctl.n_steps > 0 else 0.0
    y = y0.copy()
    yk = np.empty(n)
    new = np.empty(n)
    chart = cur
    t = t0
    steps_left = ctl.max_steps
    near = False
    near_span = 0.0
    near_depth = 0
    edge = True
    first = True
    n_p = 0
    n_sw = 0
    n_rows = 0
    while True:
        t_to = t1
        seg_ctl = ctl
        seg_te = t_eval
        if not first:
            n_steps = 0
            if ctl.n_steps > 0:
                n_steps = max(1, math.ceil(abs(t1 - t) / abs(h_fixed) * (1.0 - 1e-12)))
            seg_ctl = Control(ctl.rtol, ctl.atol, 0.0, ctl.max_step, max(steps_left, 0),
                              n_steps, ctl.n_hol, ctl.n_coord, ctl.n_sens, NEAR)
            if near:                    # (``atlas._approach``)
                span = near_span
                if ctl.n_steps > 0:
                    span = math.copysign(abs(h_fixed), t1 - t)
                t_to = t + (span if ctl.n_steps > 0 else 2.0 * span)
                if abs(t_to - t) >= abs(t1 - t):
                    t_to = t1
                if ctl.n_steps > 0:
                    seg_ctl = Control(ctl.rtol, ctl.atol, 0.0, ctl.max_step,
                                      seg_ctl.max_steps, PARTS, ctl.n_hol, ctl.n_coord,
                                      ctl.n_sens, NEAR)
                else:
                    seg_ctl = Control(ctl.rtol, ctl.atol, 0.0,
                                      min(ctl.max_step, abs(span) / PARTS),
                                      seg_ctl.max_steps, seg_ctl.n_steps, ctl.n_hol,
                                      ctl.n_coord, ctl.n_sens, NEAR)
            if mode == AT_T_EVAL:
                j = 0
                while j < t_eval.shape[0] and not direction * (t_eval[j] - t) > 0.0:
                    j += 1
                seg_te = t_eval[j:]
        if addr[chart, 0] == 0 or addr[chart, 2] == 0 or (not edge and n_sing[chart] == 0):
            return _record(HANDED_BACK, n_p, n_sw, n_rows, I, F, TS, YS)
        if edge:
            watch = Watch(n_sing[chart], sing_tol, edge_dir, edge_max)
            uev = addr[chart, 2]
        else:
            watch = Watch(n_sing[chart], sing_tol, no_events, no_events)
            uev = addr[chart, 1]
        (status, ts, ys, n_out, stats, t_end, y_end, ev_t, ev_i, ev_y, n_ev,
         sing_index) = body(addr[chart, 0], addr[chart, 1], uev, addr[chart, 3], t, t_to,
                            y, p, seg_ctl, seg_te, mode, watch, halt)
        hit = edge and status == EVENT and n_ev > 0 and ev_i[n_ev - 1] == 0
        depth = near_depth + 1 if near else 0
        partial = status == EVENT or status == SINGULAR
        back = False
        t_k = t
        span = 0.0
        if ((hit and not near) or (edge and status == SINGULAR)) and depth <= DEPTH:
            # the start of the step that stopped (``atlas._step_start``)
            back = True
            t_stop = t_end
            if stats[0] == 0:
                src = -1
            else:
                t_s = ts[n_out]
                if direction * (t_stop - t_s) > 0.0:
                    src = -1 if t_s == t else n_out
                elif mode == EVERY_STEP:
                    src = n_out - 1
                    while src >= 0 and not direction * (t_stop - ts[src]) > 0.0:
                        src -= 1
                    if src <= 0:
                        src = -1
                else:                   # (the loop run again: ``follow``)
                    return _record(HANDED_BACK, n_p, n_sw, n_rows, I, F, TS, YS)
            if src < 0:
                t_k = t
                for i in range(n):
                    yk[i] = y[i]
            else:
                t_k = ts[src]
                for i in range(n):
                    yk[i] = ys[src, i]
            span = t_stop - t_k
        keep = n_out
        add = False
        if back:                        # cut at the step's start (``atlas._cut``)
            while keep > 0 and direction * (ts[keep - 1] - t_k) > 0.0:
                keep -= 1
            if mode == ENDPOINTS:
                keep = min(keep, 1)
            add = mode != AT_T_EVAL and not (keep > 0 and ts[keep - 1] == t_k)
            partial = False
        if not back or t_k != t or n_p == 0:        # (not a piece of no steps)
            I, F = _room(I, F, n_p)
            rows = keep + (1 if add else 0)
            TS, YS = _rows(TS, YS, n_rows, rows)
            for r in range(keep):
                TS[n_rows + r] = ts[r]
                for i in range(n):
                    YS[n_rows + r, i] = ys[r, i]
            if add:
                TS[n_rows + keep] = t_k
                for i in range(n):
                    YS[n_rows + keep, i] = yk[i]
            row = I[n_p]
            row[C_SPLIT], row[C_ROWS], row[C_ROW0] = chart, rows, n_rows
            row[C_STEPS], row[C_REJECTED], row[C_NFEV] = stats[0], stats[1], stats[2]
            row[C_MAXSTEPS], row[C_NSTEPS] = seg_ctl.max_steps, seg_ctl.n_steps
            row[C_PARTIAL], row[C_EDGE], row[C_FIRST], row[C_CUT] = partial, edge, first, back
            f = F[n_p]
            f[C_T], f[C_TTO], f[C_MAXSTEP] = t, t_to, seg_ctl.max_step
            for i in range(n):
                f[N_F + i] = y[i]
            if back:
                row[C_STATUS], row[C_NEV], row[C_SING], row[C_EVI] = FINISHED, 0, -1, 0
                f[C_TEND] = t_k
                for i in range(n):
                    f[N_F + n + i] = yk[i]
            else:
                row[C_STATUS], row[C_NEV], row[C_SING] = status, n_ev, sing_index
                f[C_TEND] = t_end
                for i in range(n):
                    f[N_F + n + i] = y_end[i]
                if n_ev > 0:
                    row[C_EVI] = ev_i[n_ev - 1]
                    f[C_EVT] = ev_t[n_ev - 1]
                    for i in range(n):
                        f[N_F + 2 * n + i] = ev_y[n_ev - 1, i]
            n_p += 1
            n_rows += rows
        first = False
        steps_left -= stats[0]
        near = False
        if not hit and not back:
            if t_to != t1 and status == FINISHED:       # an approach's end
                t = t_end
                for i in range(n):
                    y[i] = y_end[i]
                continue
            break
        if back:
            t = t_k
            for i in range(n):
                y[i] = yk[i]
        else:
            t = ev_t[n_ev - 1]
            for i in range(n):
                y[i] = ev_y[n_ev - 1, i]
        # the change of chart (``atlas.switch``, ``_at_end``: none within the time
        # resolution of the run's end)
        if abs(t1 - t) < MIN_TIME_RESOLUTION * (np.nextafter(max(abs(t), abs(t1)), np.inf)
                                - max(abs(t), abs(t1))):
            target = -1
        else:
            target = _change(t, y, p, table, caddr, eps, chart, new)
            if target <= -2:
                return _record(HANDED_BACK, n_p, n_sw, n_rows, I, F, TS, YS)
        if target < 0:
            if back:                    # approach the edge (``atlas._approach``)
                near, near_span, near_depth = True, span, depth
            else:                       # no better split here: on without the edge
                edge = False
            continue
        if addr[target, 0] == 0:
            return _record(HANDED_BACK, n_p, n_sw, n_rows, I, F, TS, YS)
        I, F = _room(I, F, n_sw)
        F[n_sw, SW_T] = t
        I[n_sw, SW_FROM], I[n_sw, SW_TO] = chart, target
        n_sw += 1
        chart = target
        for i in range(n):
            y[i] = new[i]
    return _record(DONE, n_p, n_sw, n_rows, I, F, TS, YS)


_C1, _C2 = f8[::1], numba.types.Array(i8, 2, "C")
ARGS = (_C2, i8[::1], f8, f8, f8[::1], f8[::1], loop.CONTROL, f8[::1], i8, f8, i8[::1],
        i8[::1], i8[::1], i8[::1], _C2, _C2, f8, i8)


@functools.cache
def compiled(method_name: str, parts: tuple, load_only: bool = False):
    """``_drive`` over the loop of ``method_name`` with ``parts`` (``loop.features``;
    watching) compiled for ``ARGS`` (or loaded from the signed store), stamped with the
    loop's sources, this file, ``chart_change`` and ``kernels.calls``; with
    ``load_only``, None where the store does not hold it (compiling it takes CPU
    seconds: ``jetnh cache warm``, ``precompile``, does it ahead)."""
    from .methods import METHODS

    method = METHODS[method_name].tableau
    namespace = dict(globals())
    namespace["body"] = loop._specialised(method, parts)["body"]
    tag = method.name + "_" + "".join(c for c, f in zip("wpds", parts) if f)
    stamp = (_common.sources_hash() + loop_cache.file_stamp(__file__)[:8]
             + loop_cache.file_stamp(chart_change.__file__)[:8]
             + loop_cache.file_stamp(calls.__file__)[:8])
    func = _common.rebound(_drive, namespace)
    func.__qualname__ = f"_drive_{tag}_{stamp}"
    func.__module__ = _drive.__module__
    dispatcher = numba.njit(error_model="numpy", nogil=True)(func)
    dispatcher._cache = loop_cache.cache_for(func, stamp)
    if load_only and dispatcher._cache.load_overload(ARGS, dispatcher.targetctx) is None:
        return None
    dispatcher.compile(ARGS)
    dispatcher.disable_compile()
    _MADE[method_name, parts] = dispatcher
    return dispatcher


def drive(method_name: str, parts: tuple):
    """The machine-code entry of ``compiled(method_name, parts)``
    (``_common.entry_point``), or None where it is not compiled yet (in this process or
    the store: a run goes on piece by piece then, ``atlas.follow``); the caller passes
    exactly ``ARGS``' types, checked (``atlas``)."""
    d = _MADE.get((method_name, parts)) or compiled(method_name, parts, True)
    return None if d is None else _common.entry_point(d)


#: the drivers compiled or loaded in this process
_MADE: dict = {}
