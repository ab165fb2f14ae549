"""The one driver of every run: ``Scene.run``, ensembles (``run_ensemble``), sweeps and
``Trajectory.at`` plan here and dispatch here.

- ``plan`` checks the options of a run once, each with one message (``numeric.options``,
  ``numeric.arguments``), and makes them a frozen ``Plan``: the method (a
  ``methods.Method``, asked every question about the method), the step control
  (``Control``), what the loop watches (``Watch``), the compiled events, the output mode
  and times, the budgets, the kernels and the machine-code entry of the loop with its
  arguments.  Plans are kept on the scene (``planned``: a repeated run with the same
  options plans nothing; ``Scene.replace`` hands them on when the kernels stay).
- ``run`` is one trajectory of a plan from one initial state and parameter vector,
  ``batch`` the runs of an ensemble (rows of arrays), ``trajectory`` the ``Trajectory``
  of the result of a compiled loop (``loops.call``: one call, which the atlas of splits
  and dense output make too).
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
from concurrent import futures
from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError, JetnhError
from . import (arguments, atlas, diagnosis, discrete, initial, interrupt, loops, methods,
               scipy_backend)
from .methods import STATUS_TEXT, Solver
from .methods._common import (AT_T_EVAL, ENDPOINTS, EVENT, EVERY_STEP, FINISHED, NONFINITE,
                              SINGULAR, STIFF, STOPPED, TOO_SMALL_STEP,
                              entry_point)
from .events import check_varying, split_records, warn_not_finite
from .kernels import sensitivity_kernels
from .methods.loop import Control, Result, Watch
from .options import fields_of, options
from .trajectory import Trajectory

#: plans kept per scene and store (beyond: the oldest dropped, ``keep``)
MAX_PLANS = 64
_NONE = np.zeros(0, dtype=np.int64)


@dataclass(frozen=True, eq=False)
class Plan:
    """A run's checked options and what its compiled loop is called with (``plan``).

    ``entry(*prefix, t0, t1, y0, p, *suffix, halt)`` is the call of the loop of the
    compiled methods (``loop.solver`` or radau's); ``ctl``, ``te``, ``mode``, ``watch``,
    ``newton`` are among its arguments.  ``dense``: what re-taking a step (radau:
    re-solving its collocation equations) needs (``numeric.dense``; None: no dense
    output), ``dense_ends`` it completed for a run whose last step is whole and for one
    stopped inside its last step (made once).  ``sens``: the kernels of the state
    augmented by its sensitivities, ``sens_tol`` their tolerances.  ``switch``: the run
    goes on across its chart's edge (``numeric.atlas``); its loop then watches the
    edge as its last event (``ce``: it stops there).  The discrete methods read
    ``steps``, ``newton_tol``, ``max_newton``, ``projection``; scipy's ``first`` and
    ``max_step``.  ``spans``: nothing but ``t0``, ``t1`` and ``head`` depends on the
    time span (an adaptive method without ``t_eval``: ``on_span``)."""

    method: methods.Method
    t0: float
    t1: float
    save: str
    rtol: float
    atol: np.ndarray
    events: object
    ce: object
    watch: Watch
    checked: bool
    singular_tol: float
    limit: float | None
    kern: object = None
    ctl: Control | None = None
    te: np.ndarray | None = None
    mode: int = EVERY_STEP
    newton: object = None
    switch: bool = False
    dense: dict | None = None
    dense_ends: tuple | None = None
    sens: object = None
    sens_error: bool = True
    steps: int = 0
    newton_tol: float = 0.0
    max_newton: int = 0
    projection: bool = False
    first: float = 0.0
    max_step: float = np.inf
    entry: object = None
    prefix: tuple = ()
    suffix: tuple = ()
    callbacks: tuple = ()           # what the addresses in prefix point into, kept alive
    direct: bool = False            # a run is one call of ``entry`` (``run``)
    head: tuple = ()                # ``(*prefix, t0, t1)`` of a direct plan
    spans: bool = False
    made: dict | None = None        # a direct plan's finished runs' ``Trajectory._made``


def _unused(method, **given):
    """Refuse options that ``method`` does not use (rather than ignore them)."""
    named = [k for k, v in given.items() if v is not None]
    if not named:
        return
    one = len(named) == 1
    hint = ""
    if {"newton_tol", "max_newton"} & set(named):
        hint = " (newton_tol and max_newton are options of radau, dla and dvi)"
    elif {"n_steps", "h"} & set(named):
        hint = " (n_steps and h are options of the fixed-step methods rk4, dla and dvi)"
    raise JetnhError(f"{', '.join(named)} {'is' if one else 'are'} not an option of the "
                     f"{method} method{hint}; remove {'it' if one else 'them'}")


def plan(scene, method="dop853", *, opts=None, t_span=None, t_eval=None, save="steps",
         events=None, timeout=None, projection=False, backend=None, sensitivities=False,
         sensitivity_error=True, batch=False) -> Plan:
    """The ``Plan`` of a run of ``scene`` (``batch``: of the runs of an ensemble, which
    store ``t_eval`` points or the final state), every option checked.  ``opts``: the
    ``numeric.options.Options`` of the run."""
    opts = options() if opts is None else opts
    rtol, atol, first_step, max_step, max_steps, n_steps, h = fields_of(opts.step)
    singular, singular_tol, split = fields_of(opts.singular)
    newton_tol, max_newton = fields_of(opts.newton)
    t0, t1 = scene.t_span if t_span is None else arguments.time_span(t_span)
    singular_tol = arguments.real(singular_tol, "singular_tol")
    if not 0.0 <= singular_tol < 1.0:
        raise JetnhError(f"singular_tol must be in [0, 1) (a fraction of each "
                         f"indicator's initial size), not {singular_tol}")
    if save not in ("steps", "final"):
        raise JetnhError(f"save must be 'steps' or 'final', not {save!r}")
    budget = arguments.count(max_steps, "max_steps")
    limit = arguments.timeout(timeout)
    n = len(scene.state_names)
    rtol, atol_v = arguments.tolerances(rtol, atol, n)
    m = methods.method(method, backend)
    checked = singular == "stop"
    if batch:
        if not m.ensemble:
            runnable = [x.name for x in methods.METHODS.values() if x.ensemble]
            raise JetnhError(f"ensembles run the Runge-Kutta methods {', '.join(runnable)}, "
                             f"not {m.name!r}")
        if t_eval is not None and not m.dense:
            dense = [x.name for x in methods.METHODS.values() if x.ensemble and x.dense]
            raise JetnhError(f"t_eval needs dense output: use {', '.join(dense)} ({m.name} "
                             "gives save='final')")
        if t_eval is None and save != "final":
            raise JetnhError("an ensemble stores t_eval points or save='final' (every step "
                             "differs per run); pass t_eval=... or save='final'")
    sens = None
    if events is not None:
        check_varying(scene, events)
    common = dict(method=m, t0=t0, t1=t1, save=save, events=events, checked=checked,
                  singular_tol=singular_tol, limit=limit)
    for flag, value in (("sensitivities", sensitivities),
                        ("sensitivity_error", sensitivity_error)):
        if not isinstance(value, (bool, np.bool_)):
            raise ArgumentError(f"{flag} must be True or False, not {value!r}")
    if sensitivities:
        if m.solver is Solver.DISCRETE:
            raise JetnhError(f"sensitivities=True is an option of the continuous methods "
                             f"(dop853, dopri5, rk4, radau, scipy-*), not of {m.name}")
        sens = sensitivity_kernels(scene)
        rtol, atol_v = _augmented_tolerances(sens.layout, rtol, atol_v,
                                             bool(sensitivity_error))
        common.update(sens=sens, sens_error=bool(sensitivity_error))
    elif sensitivity_error is not True:
        raise JetnhError("sensitivity_error= is an option of runs with sensitivities=True")
    none_watch = Watch(0, singular_tol, _NONE, _NONE)
    if m.solver is Solver.SCIPY:
        _unused(m.name, n_steps=n_steps, h=h, newton_tol=newton_tol, max_newton=max_newton,
                timeout=timeout, projection=projection or None)
        first, mx = arguments.step_limits(first_step, np.inf if max_step is None
                                          else max_step)
        te = None if t_eval is None else arguments.times(t_eval, t0, t1)
        return Plan(**common, rtol=rtol, atol=atol_v, ce=None, watch=none_watch, te=te,
                    first=first, max_step=mx, spans=te is None)
    if m.solver is Solver.DISCRETE:
        _unused(m.name, t_eval=t_eval, first_step=first_step, max_step=max_step)
        steps = arguments.fixed_steps(n_steps, h, t0, t1, m.name, budget)
        arguments.output_rows(steps, 3 * scene.system.J.n + 2 * scene.system.k, save)
        tol = 1e-13 if newton_tol is None else arguments.positive(newton_tol, "newton_tol")
        iters = 50 if max_newton is None else arguments.count(max_newton, "max_newton",
                                                              limit=10_000)
        if projection and not m.projection:
            raise JetnhError("projection= is an option of the dla integrator")
        return Plan(**common, rtol=rtol, atol=atol_v, ce=scene.compile_events(events),
                    watch=none_watch, steps=steps, newton_tol=tol, max_newton=iters,
                    projection=bool(projection))
    if projection:
        raise JetnhError("projection= is an option of the dla integrator; the "
                         "Runge-Kutta methods follow the constraints to their tolerance")
    if not m.newton:
        _unused(m.name, newton_tol=newton_tol, max_newton=max_newton)
    n_hol, n_coord = len(scene.system.holonomic), scene.system.J.n
    if m.adaptive:
        _unused(m.name, n_steps=n_steps, h=h)
        first, mx = arguments.step_limits(first_step, np.inf if max_step is None
                                          else max_step)
        mode = EVERY_STEP if save == "steps" else ENDPOINTS
        te = np.zeros(0)
        if t_eval is not None:
            te = arguments.times(t_eval, t0, t1)
            mode = AT_T_EVAL
        ctl = Control(rtol, atol_v, first, mx, budget, 0, n_hol, n_coord)
    else:
        if t_eval is not None and not batch:
            raise JetnhError(f"{m.name} is a fixed-step method and takes no t_eval: its "
                             "compiled loop writes a row at every step (or the ends), not at "
                             "given times, in single runs and ensembles alike. Run it with "
                             "n_steps or h and read traj.at(times) (its cubic Hermite "
                             "interpolant, error O(h^4)), choose n_steps so that the times "
                             "are steps (t0 + k (t1 - t0) / n_steps), or use dop853, dopri5 "
                             "or radau with t_eval")
        _unused(m.name, first_step=first_step, max_step=max_step)
        steps = arguments.fixed_steps(n_steps, h, t0, t1, m.name, budget)
        if not batch:
            arguments.output_rows(steps, n, save)
        mode = EVERY_STEP if save == "steps" else ENDPOINTS
        te = np.zeros(0)
        ctl = Control(rtol, atol_v, 0.0, np.inf, budget, steps, n_hol, n_coord)
    if sens is not None:     # the projection moves the sensitivities with the state
        ctl = ctl._replace(n_sens=sens.layout.sensitivity_columns)
    if batch:
        mode = AT_T_EVAL if t_eval is not None else ENDPOINTS
    switch = split == "switch" and atlas.applies(scene, events)
    if switch and not m.adaptive:       # (a stage past the edge: ``atlas.NEAR``)
        ctl = ctl._replace(edge=atlas.NEAR)
    dense = ends = None
    if not batch:
        dense = {"rtol": rtol, "atol": atol_v, "mode": mode, "ctl": ctl}
        if sens is not None:
            dense["rhs"] = sens
        ends = tuple({**dense, "partial_last": cut} for cut in (False, True))
    newton = None
    if m.solver is Solver.IMPLICIT:
        from .methods import radau

        newton = radau.newton_options(newton_tol, max_newton)
    kern = scene.kernels
    if switch:
        # the run goes on across its chart's edge (numeric.atlas): its loop, in the
        # scene's own chart, watches the edge as its last event (it stops there)
        from .events import as_events

        at = atlas.atlas(scene)
        ce = at.events(at.own, as_events(events), True)
    else:
        ce = scene.compile_events(events)
    watch = _watch(scene, kern, ce, checked, singular_tol)
    entry, prefix, suffix, callbacks = loops.entry(scene, m, kern, ce, sens, ctl, te, mode,
                                                    watch, newton)
    direct = sens is None and not switch and not batch
    made = None if not direct else Trajectory._made(
        kern, m.name, _FINISHED_TEXT, None if ends is None else ends[0],
        () if ce is None else ce.names)
    return Plan(**common, rtol=rtol, atol=atol_v, ce=ce, watch=watch, kern=kern, ctl=ctl,
                te=te, mode=mode, newton=newton, switch=switch, dense=dense,
                dense_ends=ends, entry=entry,
                prefix=prefix, suffix=suffix, callbacks=callbacks,
                direct=direct, head=(*prefix, t0, t1),
                spans=m.adaptive and t_eval is None and not batch, made=made)


def planned(scene, key, make, span=None) -> Plan:
    """The plan of ``key`` kept on ``scene`` (``make()`` when there is none; an
    unhashable key plans afresh).  The key holds every input of the plan but the
    kernels, and the time span, or it is ``span``: scenes with the same kernels share
    their plans (``Scene.replace``).  With ``span``, a plan of ``key`` on another span
    whose options do not depend on it (``Plan.spans``; kept apart, per key) is taken
    over on ``span`` (``on_span``): a loop over time spans (a shooting loop over the
    final time) plans once."""
    memo = scene._memo
    store = memo.get("plans")
    if store is None:
        store = memo["plans"] = {}
    full = key if span is None else (key, span)
    try:
        found = store.get(full)
    except TypeError:           # an array among the options
        return make()
    if found is None:
        spans = None if span is None else memo.setdefault("spans", {})
        other = None if spans is None else spans.get(key)
        if other is not None:
            found = on_span(other, *span)
        else:
            found = make()
            if spans is not None and found.spans:
                keep(spans, key, found)
        keep(store, full, found)
    return found


def keep(store: dict, key, plan):
    """``store[key] = plan``, the oldest entry dropped where ``store`` holds
    ``MAX_PLANS``: a loop of ever new options (spans, times) keeps a bounded store and
    leaves room for the options planned after it."""
    if len(store) >= MAX_PLANS:
        try:
            del store[next(iter(store))]
        except (KeyError, RuntimeError, StopIteration):   # (another thread's run took it)
            pass
    store[key] = plan


def on_span(plan, t0, t1) -> Plan:
    """``plan`` (whose options do not depend on its span: ``Plan.spans``) on the time
    span ``(t0, t1)`` (checked: ``arguments.time_span``)."""
    new = object.__new__(Plan)
    d = plan.__dict__.copy()            # (a copy of the dict: sooner than filling one)
    d["t0"], d["t1"], d["head"] = t0, t1, (*plan.prefix, t0, t1)
    object.__setattr__(new, "__dict__", d)
    return new


def hashable(value):
    """``value`` as a part of a plan's key: a list or a tuple as a tuple of its entries
    and their types (``True == 1``, but a run may refuse a bool where it takes 1), an
    array as its bytes (with dtype and shape; of objects, as a list), anything else as
    it is."""
    if type(value) is list or type(value) is tuple:
        return tuple(map(hashable, value)), tuple(map(type, value))
    if isinstance(value, np.ndarray):
        if value.dtype.hasobject:       # (its bytes are addresses, which are reused)
            return "objects", value.shape, hashable(value.ravel().tolist())
        return ("array", value.dtype.str, value.shape, value.tobytes())
    return value


def _watch(scene, kern, ce, checked, singular_tol) -> Watch:
    """What the loop watches: the singularity indicators (``checked``) and the user
    events ``ce``."""
    return Watch(len(kern.layout.indicators) if checked else 0, float(singular_tol),
                 ce.direction if ce is not None else _NONE,
                 ce.max_events if ce is not None else _NONE)


def _augmented_tolerances(layout, rtol, atol, controlled):
    """The tolerances of a run with sensitivities: with ``controlled``, entry (i, k) of
    S has the tolerance of state i; else S has none (atol = inf) and the state's
    tolerances are scaled by sqrt(n / N), so that the RMS error norm over all N entries
    equals the norm over the n states of a run without sensitivities (the same steps)."""
    n, m = layout.n_state, layout.sensitivity_columns
    if controlled:
        return rtol, np.ascontiguousarray(np.concatenate([atol, np.repeat(atol, m)]))
    r = np.sqrt(n / (n + n * m))
    return rtol * r, np.ascontiguousarray(np.concatenate([atol * r, np.full(n * m, np.inf)]))


def augmented(scene, plan, y0, p) -> np.ndarray:
    """The initial state of a run of ``plan`` with sensitivities: ``(y0, S0)`` flattened
    (``y0`` one state or rows of states, ``p`` one row of parameters or one per row);
    S0 = (I | 0), along the holonomic constraints in the split's chart
    (``initial.sensitivities``)."""
    y0 = np.asarray(y0, dtype=float)
    S0 = initial.sensitivities(plan.sens, scene.system, plan.t0, y0, p)
    return np.ascontiguousarray(np.concatenate([y0, S0], axis=-1))


# ---------------------------------------------------------------------- one run
def run(scene, plan, y, p, own=False, span=None) -> Trajectory:
    """The trajectory of ``plan`` from the state ``y`` (checked, its own array) with the
    run-time parameters ``p``; ``own``: these are the scene's own initial values;
    ``span``: the time span ``(t0, t1)`` (checked) to run a direct plan on
    (``Plan.spans``) instead of its own, as ``on_span(plan, *span)`` would."""
    if span is not None and not plan.direct:
        plan = on_span(plan, *span)
    if plan.ce is not None:
        warn_not_finite(plan.ce, plan.t0 if span is None else span[0], y, p)
    if plan.direct:             # one call of the compiled loop, first: most runs are
        halt = _HALT.copy()
        head = plan.head if span is None else (*plan.prefix, *span)
        tic = _clock()
        out = interrupt.call(plan.entry, halt, plan.limit, (*head, y, p, *plan.suffix, halt))
        wall = _clock() - tic
        if plan.ctl.n_hol:          # rows of the dense output onto g = 0
            loops.on_constraints(plan.kern, plan.ctl, plan.mode, None, out, p, head[-2])
        status = out[0]
        if status == FINISHED and (len(out) == 6 or out[7] is None):   # most runs: at once
            return Trajectory._of_made(plan.made, scene, out, p, wall)
        dense = plan.dense_ends
        if dense is not None:    # stopped inside a step or not
            dense = dense[status == EVENT or status == SINGULAR]
        return trajectory(scene, plan.method.name, out, wall, plan.kern, plan.ce, p,
                          head[-2], y, plan.singular_tol, plan.checked, plan.limit, dense)
    m = plan.method
    if plan.sens is not None:
        y = augmented(scene, plan, y, p)
    if m.solver is Solver.SCIPY:
        return scipy_backend.run(scene, m.scipy, plan.rtol, plan.atol, plan.te, plan.t0,
                                 plan.t1, y, p, plan.first or None, plan.max_step,
                                 plan.events, "stop" if plan.checked else "ignore",
                                 plan.singular_tol, sensitivities=plan.sens,
                                 save=plan.save)
    if m.solver is Solver.DISCRETE:
        sing = plan.singular_tol if plan.checked else None
        if not m.projection:
            return discrete.run_dvi(scene, m, plan.t0, plan.t1, y, own, p, plan.steps,
                                    plan.save, plan.newton_tol, plan.max_newton, sing,
                                    plan.limit, plan.ce)
        return discrete.run_dla(scene, m, plan.t0, plan.t1, y, own, p, plan.steps, plan.save,
                                plan.newton_tol, plan.max_newton, plan.projection, sing,
                                plan.limit, plan.ce)
    dense = plan.dense
    if plan.switch:
        return atlas.run(scene, plan, y, p, trajectory)
    halt = _HALT.copy()
    t0 = plan.t0
    tic = _clock()
    out = interrupt.call(plan.entry, halt, plan.limit,
                         (*plan.prefix, t0, plan.t1, y, p, *plan.suffix, halt))
    wall = _clock() - tic
    loops.on_constraints(plan.kern, plan.ctl, plan.mode, plan.sens, out, p, t0)
    if dense is not None:    # stopped inside a step or not
        dense = plan.dense_ends[out[0] in (EVENT, SINGULAR)]
        if plan.sens is not None:           # the run's own (``trajectory`` adds its rows)
            dense = dict(dense)
    return trajectory(scene, m.name, out, wall, plan.kern, plan.ce, p, t0, y,
                      plan.singular_tol, plan.checked, plan.limit, dense, sens=plan.sens)


_clock = time.perf_counter
_FINISHED_TEXT = STATUS_TEXT[FINISHED]
#: what a run's halt flag is made from (a copy: sooner than ``np.zeros``; never written)
_HALT = np.zeros(1, dtype=np.int64)


def trajectory(scene, method, out, wall, kern, ce, p, t0, y_init, singular_tol, checked,
               timeout=None, dense=None, n_events=None, sens=None) -> Trajectory:
    """A Trajectory from the ``Result`` of a compiled loop, or the tuple it returned
    (``loop._solve``), or an error; with ``n_events``, only the first ``n_events`` events
    of ``ce`` are reported; with ``sens`` (the kernels of a run with sensitivities) the
    state's columns, and the sensitivities apart."""
    if (out[0] == FINISHED and sens is None and (len(out) == 6 or out[7] is None)
            and not isinstance(out, Result)):       # most runs: at once
        names = () if ce is None else ce.names[:n_events]
        return Trajectory._of_loop(scene, out, p, method, _FINISHED_TEXT, wall, kern, dense,
                                   names)
    if len(out) == 6:      # a loop that watched nothing: no events
        status, ts, ys, n_out, stats, sing_index = out
        if status != FINISHED:      # its last time and state (row n_out), for diagnosis
            t_last, y_last = float(ts[n_out]), ys[n_out]
    else:
        (status, ts, ys, n_out, stats, t_last, y_last, ev_t, ev_i, ev_y, n_ev,
         sing_index) = out
    # a loop's status is never a success with a NaN or an infinity in the states
    # (``loop.finite_status``); a ``Result`` (``loops.call``) is checked again: the
    # atlas moves its last state onto the constraints
    finite = not isinstance(out, Result)
    status = int(status)
    sensitivities = events = singularity = None
    if sens is not None:
        n = kern.layout.n_state
        ys = ys[:n_out]
        if dense is not None:
            dense["y"] = ys
        sensitivities = (scene._sensitivity_columns(), ys[:, n:].reshape(
            n_out, n, sens.layout.sensitivity_columns))
        ys, n_out = np.ascontiguousarray(ys[:, :n]), ys.shape[0]
        y_init = y_init[:n]
        if (len(out) != 6 or status != FINISHED) and y_last is not None:
            y_last = y_last[:n]
        if ce is not None and ev_y is not None:
            ev_y = ev_y[:, :n]
    if n_out != ts.shape[0]:
        ts, ys = ts[:n_out], ys[:n_out]
    if not finite and status in (FINISHED, EVENT) and not arguments.all_finite(ys, y_last):
        status = NONFINITE
    if status == FINISHED:
        reason = STATUS_TEXT[FINISHED]
    elif status == NONFINITE:
        sing_index = (diagnosis.explain_nonfinite(scene, kern, t_last, y_last, p, t0, y_init,
                                                  singular_tol) if checked else -1)
        if sing_index < 0:
            diagnosis.raise_nonfinite(scene, method, t_last, y_last, kern, p, t0, y_init,
                                      checked=checked)
        status = SINGULAR
        singularity = diagnosis.singularity(scene, kern, int(sing_index), t_last, y_last, p,
                                            t0, y_init, singular_tol, nonfinite=True)
        reason = singularity["reason"]
    elif status == SINGULAR:
        singularity = diagnosis.singularity(scene, kern, int(sing_index), t_last, y_last, p,
                                            t0, y_init, singular_tol, method=method)
        reason = singularity["reason"]
    elif status == STIFF:
        reason = diagnosis.stiff_reason(scene, kern, method, t_last, y_last, p, t0, y_init)
    elif status == TOO_SMALL_STEP:
        reason = diagnosis.small_step_reason(scene, kern, method, t_last, y_last, p, t0,
                                             y_init)
    elif status == EVENT:
        k = int(ev_i[n_ev - 1])
        reason = f"terminal event {ce.names[k]!r} at t = {float(ev_t[n_ev - 1]):.17g}"
    elif status == STOPPED:
        reason = diagnosis.timeout_reason(timeout, t_last)
    else:       # where it stopped: with t_eval, after the last row
        reason = f"{STATUS_TEXT[status]}, at t = {t_last:.10g}"
    if ce is not None:
        k = len(ce) if n_events is None else n_events
        if ev_t is None:        # (none recorded: the loop returned no records)
            t_events = [np.empty(0) for _ in range(k)]
            y_events = [np.empty((0, ys.shape[1])) for _ in range(k)]
        else:
            t_events, y_events = split_records(k, ev_t[:n_ev], ev_i[:n_ev], ev_y[:n_ev])
        events = (ce.names[:k], t_events, y_events)
    # the loop's own float64, C-contiguous rows: taken as they are
    traj = Trajectory._of_run(scene, (ts, ys, n_out), p, method, status, reason,
                              (stats, wall, scene.projected), kern, events, singularity,
                              dense, sensitivities)
    if status != FINISHED:      # where it stopped, for ``final`` (after its last row)
        traj._stopped(t_last, y_last)
    return traj


# ---------------------------------------------------------------------- many runs
def _driver(method, prange, edge=False):
    """The entry of the compiled ensemble driver of ``method`` (numba threads over the
    runs with ``prange``, else one loop; ``edge``: for runs with ``Control.edge`` > 0,
    ``loop.ensemble_solver``), kept."""
    edge = edge and method.solver is not Solver.IMPLICIT        # (radau has no edge code)
    found = _DRIVERS.get((method.name, prange, edge))
    if found is None:
        if method.solver is Solver.IMPLICIT:
            from .methods import radau

            found = entry_point(radau.ensemble_solver(parallel=prange))
        else:
            from .methods import loop

            found = entry_point(loop.ensemble_solver(method.tableau, prange, edge))
        _DRIVERS[method.name, prange, edge] = found
    return found


_DRIVERS: dict = {}


#: idle thread pools of the ensembles (``_pool``): worker count -> pools, at most
#: ``MAX_IDLE_POOLS`` in all (beyond, those of the count first kept are ended)
_IDLE: dict = {}
MAX_IDLE_POOLS = 4
_POOL_LOCK = threading.Lock()


@contextlib.contextmanager
def _pool(workers):
    """A pool of ``workers`` threads for one ``batch`` call alone: an idle one kept from
    an earlier call (making one, with its threads, costs more than a small ensemble), or
    a new one; back to the idle ones after a call that returned, ended (its threads
    joined, as a pool of the call's own) after one that raised.  A child process
    (``os.fork``) starts with none: the threads stay in the parent."""
    with _POOL_LOCK:
        idle = _IDLE.get(workers)
        pool = idle.pop() if idle else None
    if pool is None:
        pool = futures.ThreadPoolExecutor(workers, thread_name_prefix="jetnh-ensemble")
    try:
        yield pool
    except BaseException:
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    with _POOL_LOCK:
        _IDLE.setdefault(workers, []).append(pool)
        spare = []
        while sum(map(len, _IDLE.values())) > MAX_IDLE_POOLS:
            oldest = next(k for k, v in _IDLE.items() if v)
            spare.append(_IDLE[oldest].pop(0))
            if not _IDLE[oldest]:
                del _IDLE[oldest]
    for extra in spare:
        extra.shutdown(wait=False)


def _forget_pools():
    """In a forked child: no pools (their threads stayed in the parent), a new lock."""
    _IDLE.clear()
    global _POOL_LOCK
    _POOL_LOCK = threading.Lock()


os.register_at_fork(after_in_child=_forget_pools)


def batch(scene, plan, Y0, P, parallel="threads", workers=1):
    """The runs of ``plan`` from the rows of ``Y0`` with the rows of ``P`` (checked,
    C-contiguous) through the compiled ensemble driver of its method: ``parallel``
    "threads" (``workers`` threads, this one and those of a pool kept between calls
    (``_pool``), each running the serial driver on the next chunk of rows with the GIL
    released), "prange" (numba threads) or "serial".  Returns the arrays ``(OUT_T,
    OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T)`` (``_common.collect``) and the wall-clock
    time."""
    import numba

    n_runs, n = Y0.shape
    n_times = plan.te.shape[0] if plan.mode == AT_T_EVAL else 1
    n_ev = len(plan.watch.ev_dir)
    out = (np.empty((n_runs, n_times)), np.empty((n_runs, n_times, n)),
           np.zeros((n_runs, 6), dtype=np.int64), np.empty(n_runs), np.empty((n_runs, n)),
           np.zeros((n_runs, max(n_ev, 1)), dtype=np.int64),
           np.full((n_runs, max(n_ev, 1)), np.nan))
    halt = np.zeros(1, dtype=np.int64)
    prange = parallel == "prange"
    drive = _driver(plan.method, prange, plan.ctl.edge > 0.0)
    head, tail = plan.prefix + (plan.t0, plan.t1), plan.suffix + (halt,)

    def block(a, b):
        if a == 0 and b == n_runs:      # all of them (no slices: each costs)
            drive(*head, Y0, P, *tail, *out)
        else:
            drive(*head, Y0[a:b], P[a:b], *tail, *(x[a:b] for x in out))

    def compute():
        if prange:
            old = numba.get_num_threads()
            numba.set_num_threads(min(workers, numba.config.NUMBA_NUM_THREADS))
            try:        # (each thread takes the next run: the driver balances the load)
                block(0, n_runs)
            finally:
                numba.set_num_threads(old)
        else:       # this thread and workers - 1 of a pool, each taking the next chunk
            chunk = max(1, -(-n_runs // (4 * workers)))
            bounds = [(a, min(a + chunk, n_runs)) for a in range(0, n_runs, chunk)]
            chunks, failed = iter(bounds), []

            def work():
                for a, b in chunks:     # (next() of a list's iterator: one at a time)
                    if failed:          # (as a pool's map cancels what has not begun)
                        return
                    try:
                        block(a, b)
                    except BaseException:
                        failed.append(True)
                        raise

            with _pool(workers - 1) as pool:
                helpers = [pool.submit(work) for _ in range(min(workers, len(bounds)) - 1)]
                try:
                    work()
                finally:        # (a helper that has not begun: no chunk left, none due)
                    futures.wait([f for f in helpers if not f.cancel()])
                for f in helpers:
                    if not f.cancelled():
                        f.result()

    tic = time.perf_counter()
    if not prange and (parallel == "serial" or workers == 1 or n_runs == 1):
        # one block: the driver itself is the call (no closures)
        interrupt.call(drive, halt, plan.limit, (*head, Y0, P, *tail, *out))
    else:
        interrupt.call(compute, halt, plan.limit)
    return out, time.perf_counter() - tic
