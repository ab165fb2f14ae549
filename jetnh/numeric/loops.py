"""One call of a compiled loop: the loop of a method (``methods``) with its arguments,
stoppable by Ctrl-C and a wall-clock budget (``numeric.interrupt``).

``entry`` is the machine-code entry of the loop of a method with the arguments before
and after ``(t0, t1, y0, p)`` (what ``solve.plan`` keeps in a plan); ``call`` one call
(the atlas of splits runs its pieces so); ``retake`` one step of a run taken again for
its dense output (``numeric.dense``).  Nothing here builds a Trajectory
(``solve.trajectory`` does), so every module that runs a loop can import this one.
"""

from __future__ import annotations

import time

import numpy as np

from . import interrupt, methods
from .methods import Solver, projection
from .methods._common import AT_T_EVAL, EVENT, SINGULAR
from .methods.loop import Result, Watch, features

NO_EVENTS = np.zeros(0, dtype=np.int64)


def entry(scene, method, kern, ce, sens, ctl, te, mode, watch, newton):
    """The entry of the compiled loop of ``method`` on the kernels ``kern`` (events
    ``ce``; with ``sens``, the right-hand side and radau's Jacobian of the state
    augmented by its sensitivities) and its arguments before and after ``(t0, t1, y0,
    p)`` (``halt`` last, per call), and the callbacks whose addresses the loop takes
    (``methods._common.function_at``): whoever calls the loop keeps them alive."""
    uev = ce.uev if ce is not None else kern.sing_fp
    rhs = kern.rhs_fp if sens is None else sens.rhs_fp
    hol = kern.hol_or_none if sens is None else sens.hol_or_none   # (with dg/dp)
    if method.solver is Solver.IMPLICIT:
        jac = scene.jacobian.address if sens is None else sens.jac_fp
        callbacks = (rhs, jac, kern.sing_fp, uev, hol)
        return (methods.implicit_solver(features(ctl, mode, watch)),
                tuple(f.address for f in callbacks),
                (ctl, newton, te, mode, watch), callbacks)
    callbacks = (rhs, kern.sing_fp, uev, hol)
    return (methods.explicit_solver(method, features(ctl, mode, watch)),
            tuple(f.address for f in callbacks), (ctl, te, mode, watch), callbacks)


def result(out) -> Result:
    """The ``Result`` of the tuple a loop returned (a loop that watched nothing returns
    no event records and its last time and state as row ``n_out`` of its output:
    ``loop._solve``)."""
    if len(out) == len(Result._fields):
        if out[6] is not None:
            return Result._make(out)
        # a loop that watched and finished: its last time and state in row n_out
        return Result._make(out)._replace(y=out[2][out[3]])
    status, ts, ys, n_out, stats, sing_index = out
    return Result(status, ts, ys, n_out, stats, float(ts[n_out]), ys[n_out], np.empty(0),
                  np.empty(0, dtype=np.int64), np.empty((0, ys.shape[1])), 0, sing_index)


def call(scene, method, kern, ce, watch, t0, t1, y, p, ctl, te, mode, newton, limit,
         sens=None):
    """One call of the compiled loop of ``method`` (a ``Method`` or its name; ``entry``),
    stoppable by Ctrl-C and ``limit`` seconds; returns its ``Result`` (the loops return
    its fields as a tuple) and the wall-clock time."""
    method = methods.method(method)
    # the callbacks: a local, alive until the loop has returned
    loop, prefix, suffix, _callbacks = entry(scene, method, kern, ce, sens, ctl, te, mode,
                                             watch, newton)
    halt = np.zeros(1, dtype=np.int64)
    tic = time.perf_counter()
    out = interrupt.call(lambda: loop(*prefix, t0, t1, y, p, *suffix, halt), halt, limit)
    wall = time.perf_counter() - tic
    on_constraints(kern, ctl, mode, sens, out, p, t0)
    return result(out), wall


def on_constraints(kern, ctl, mode, sens, out, p, t0=None):
    """The rows of a loop's tuple ``out`` that the dense output gave (off the holonomic
    constraints g = 0 by its error: the rows at ``t_eval``, the events' states, the state
    of a stop inside a step) moved onto g = 0 in place, as every step is
    (``methods.projection``), the sensitivities of a run with ``sens`` with them; rows at
    the call's start ``t0`` (its initial state as given, S the identity) are left."""
    if not ctl.n_hol:
        return
    k, n_sens = (kern, 0) if sens is None else (sens, ctl.n_sens)
    status, ts, ys, n = int(out[0]), out[1], out[2], int(out[3])
    if mode == AT_T_EVAL and n:
        if n_sens and t0 is not None:
            inner = np.flatnonzero(ts[:n] != t0)
            rows = ys[inner]
            onto_constraints(k, ts[inner], rows, p, n_sens)
            ys[inner] = rows
        else:
            onto_constraints(k, ts[:n], ys[:n], p, n_sens)
    if len(out) == len(Result._fields):     # a loop that watched: events, stops
        t_last, y_last, ev_t, ev_y, n_ev = out[5], out[6], out[7], out[9], int(out[10])
        if n_ev:
            onto_constraints(k, ev_t[:n_ev], ev_y[:n_ev], p, n_sens)
        if status in (EVENT, SINGULAR) and t_last != t0:
            onto_constraints(k, np.array([t_last]), y_last[None, :], p, n_sens)
            if mode != AT_T_EVAL and n and ts[n - 1] == t_last:
                ys[n - 1] = y_last


def onto_constraints(kern, ts, ys, p, n_sens=0):
    """The rows ``ys`` (at the times ``ts``) moved onto the holonomic constraints of the
    kernels ``kern`` in place (``methods.projection.rows``: ``p`` one row of parameters
    or one per row; with ``n_sens`` sensitivity columns, ``kern`` the kernels of the
    augmented state, whose hol gives dg/dp too)."""
    lay = kern.layout
    projection.rows(kern.hol, lay.holonomic, len(lay.coordinates), ts, ys, p, n_sens)


def retake(traj, t0, t1, y, tau):
    """The step of ``traj`` (a dop853 or dopri5 run) from (t0, y) to t1 taken again,
    its dense output at the times ``tau``: the ``Result``.  The step control is the
    run's (``traj._dense["ctl"]``) with one step of exactly t1 - t0."""
    d = traj._dense
    # |h| one ulp up: t0 + first reaches (or passes, and is cut back to) t1, so the
    # step is h = t1 - t0, the original run's h to the bit
    first = float(np.nextafter(abs(t1 - t0), np.inf))
    ctl = d["ctl"]._replace(first_step=first, max_step=np.inf, max_steps=1, n_steps=0)
    out, _ = call(traj.scene, traj.method, traj._kernels, None,
                  Watch(0, 0.0, NO_EVENTS, NO_EVENTS), t0, t1, y,
                  np.ascontiguousarray(traj._p, dtype=float), ctl, tau, AT_T_EVAL, None,
                  None, d.get("rhs"))
    return out
