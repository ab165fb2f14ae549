"""scipy's ``solve_ivp`` on a scene's compiled right-hand side (``method="scipy-<M>"``):
user events and the singularity indicators become scipy events, a root on a step's end
counted once and an event not finite at the start said, as the compiled methods do.  A
right-hand side that becomes NaN or infinite stops the run as theirs: a singular stop
where an indicator explains it, else an ``IntegrationError`` (also where Radau's or
BDF's Jacobian of finite differences met it).

With holonomic constraints g(t, q) = 0 the one-step methods (RK23, RK45, DOP853, Radau)
move every accepted step onto g = 0 as jetnh's own loops do (``methods.projection``: the
same compiled iteration, through a subclass of scipy's solver whose step ends with it;
the derivative at the step's end is evaluated again at the projected state, one more
right-hand side per step), and the rows their dense output gives (``t_eval``, events, a
terminal event's last row) are projected the same way: |g| stays at rounding level.
BDF and LSODA are multistep methods whose history (BDF's differences, LSODA's Nordsieck
array inside its Fortran state) a projected value would contradict: their steps are not
projected, their rows drift off g = 0 by the global error, and the run says so
(``drift.report``: a ``JetnhWarning`` with the figure; the diagnostics'
``holonomic_residual_max``).

``save="final"`` (no ``t_eval``) keeps t0 and the last state alone, as the compiled
methods do: ``solve_ivp`` runs with an empty ``t_eval`` (no row stored, no dense output
made but for events) through a subclass of its solver that keeps the state where it is
(``_final``); the rows are those of the run that keeps every step, its first and its
last, bit for bit (a terminal event's state is the one ``solve_ivp`` records for it).
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..errors import JetnhError
from . import diagnosis, drift
from .events import warn_not_finite
from .methods import SCIPY_METHODS, projection
from .methods._common import EVENT, SINGULAR
from .trajectory import Trajectory

#: scipy's methods whose steps are projected onto g = 0 (one-step methods)
PROJECTED = ("RK23", "RK45", "DOP853", "Radau")
#: what a user's event that is exactly 0 after t0 gives scipy: a positive value, so that
#: a root on a step's end is a crossing of that step or of the next, never of both
#: (scipy takes g_old <= 0 <= g_new, which a 0 at the node meets twice): one root, as
#: the compiled methods count it (``methods._events``)
_POSITIVE_ZERO = np.finfo(float).tiny


def run(scene, method, rtol, atol, t_eval, t0, t1, y_init, p, first_step, max_step,
        events=None, singular="stop", singular_tol=1e-10, sensitivities=None,
        save="steps") -> Trajectory:
    """scipy's ``solve_ivp`` on the compiled right-hand side; user events and the
    singularity indicators become scipy events (the indicators terminal, direction -1,
    on ``s_i g_i - singular_tol |g_i(t0)|``).  ``sensitivities``: the kernels of the
    state augmented by its sensitivities (``kernels.sensitivity_kernels``; ``y_init``
    and the tolerances augmented too).  ``save``: "steps" or "final" (without
    ``t_eval``: t0 and the end alone, module docstring)."""
    from scipy.integrate import solve_ivp

    if method not in SCIPY_METHODS:
        raise JetnhError(f"unknown scipy method {method!r}; choose one of {SCIPY_METHODS}")
    final = save == "final" and t_eval is None
    saved = "t_eval" if t_eval is not None else save
    kern = scene.kernels
    rhs = kern.rhs if sensitivities is None else sensitivities.rhs
    n = y_init.shape[0]
    n_state = kern.layout.n_state

    failed = []         # the last (t, y) where the right-hand side was not finite

    calls = [0]         # right-hand-side evaluations (for a failed run's stop counts)

    def fun(t, y):
        calls[0] += 1
        out = np.empty(n)
        y = np.ascontiguousarray(y, dtype=float)
        rhs(float(t), y, p, out)
        if not math.isfinite(out.sum()):
            failed[:] = [(float(t), y.copy())]
        return out

    ce = scene.compile_events(events)
    scipy_events = []
    if ce is not None:
        warn_not_finite(ce, t0, y_init[:n_state], p)
        for f, ev in zip(ce.python_funcs, ce.events):
            def g(t, y, f=f):
                v = f(t, y, p)
                return _POSITIVE_ZERO if v == 0.0 and t != t0 else v
            g.terminal = ev.max_events if ev.max_events > 0 else False
            g.direction = ev.direction
            scipy_events.append(g)
    n_user = len(scipy_events)
    m = len(kern.layout.indicators) if singular == "stop" else 0
    if m:
        g0 = np.empty(m)
        kern.sing(t0, y_init, p, g0)
        bad = ~np.isfinite(g0) | (g0 == 0.0)
        if bad.any():
            idx = int(np.argmax(bad))
            info = diagnosis.singularity(scene, kern, idx, t0, y_init, p, t0, y_init,
                                         singular_tol)
            return Trajectory(scene, [t0], [y_init[:n_state]], p, method=f"scipy-{method}",
                              status=SINGULAR, stop_reason=info["reason"], steps=0,
                              rejected=0, nfev=0, wall_time=0.0, kernels=kern,
                              projected=scene.projected, singularity=info,
                              saved=saved)
        sig, thr = np.sign(g0), singular_tol * np.abs(g0)
        work = np.empty(m)
        for i in range(m):
            def gs(t, y, i=i):
                kern.sing(float(t), np.ascontiguousarray(y, dtype=float), p, work)
                v = sig[i] * work[i] - thr[i]
                return v if np.isfinite(v) else -1.0
            gs.terminal = True
            gs.direction = -1
            scipy_events.append(gs)
    kw = {}
    if first_step:          # a first step beyond the span is the span (as dop853 takes it)
        kw["first_step"] = min(first_step, abs(t1 - t0))
    te_run, repeat = t_eval, None
    if t_eval is not None:  # scipy refuses repeated times: each is asked for once
        fresh = np.ones(t_eval.size, dtype=bool)
        fresh[1:] = np.diff(t_eval) != 0
        te_run, repeat = t_eval[fresh], np.cumsum(fresh) - 1
    if not np.all(np.isfinite(fun(t0, y_init))):
        diagnosis.raise_nonfinite(scene, f"scipy-{method}", t0, y_init, kern, p, t0, y_init,
                                  stop=dict(t=float(t0), steps=None, rejected=None,
                                            rhs_evaluations=1))
    onto = _onto(scene, sensitivities, p) if method in PROJECTED else None
    solver = method if onto is None else _projected(method, onto)
    if final:
        solver, made = _final(solver)
        te_run = np.zeros(0)
    tic = time.perf_counter()
    try:
        sol = solve_ivp(fun, (t0, t1), y_init, method=solver, t_eval=te_run, rtol=rtol,
                        atol=atol, max_step=max_step, events=scipy_events or None, **kw)
    except (ValueError, np.linalg.LinAlgError):
        if not failed:
            raise
        # (Radau, BDF: a Jacobian of finite differences taken across a NaN)
        diagnosis.raise_nonfinite(scene, f"scipy-{method}", *failed[0], kern, p, t0, y_init,
                                  stop=dict(t=failed[0][0], steps=None, rejected=None,
                                            rhs_evaluations=calls[0]))
    wall = time.perf_counter() - tic
    # no row (an empty t_eval, a stop before its first time): scipy leaves lists
    ts = np.asarray(sol.t, dtype=float).reshape(-1)
    ys = np.ascontiguousarray(np.asarray(sol.y, dtype=float).reshape(n, -1).T)
    if final:
        ts, ys = made[0].rows(t0, y_init, sol, t1 >= t0)
    if repeat is not None:  # a repeated time: its row repeated
        keep = repeat[repeat < ts.size]
        ts, ys = ts[keep], np.ascontiguousarray(ys[keep])
    if onto is not None:          # the dense output's rows (t_eval; a terminal event)
        inner = np.flatnonzero(ts != t0) if t_eval is not None else (
            [len(ts) - 1] if sol.status == 1 and ts[-1] != t0 else [])
        rows = ys[inner]
        onto(ts[inner], rows)
        ys[inner] = rows
    status, reason, singularity = (0 if sol.status == 0 else 2), sol.message, None
    nonfinite = bool(ys.size) and not np.all(np.isfinite(ys))
    if nonfinite:
        # as the compiled methods: a singular stop at the last finite row where an
        # indicator explains it, else an error
        first = int(np.argmax(~np.all(np.isfinite(ys), axis=1)))
        i = max(first - 1, 0)
        idx = (diagnosis.explain_nonfinite(scene, kern, ts[i], ys[i], p, t0, y_init,
                                           singular_tol) if m and first else -1)
        if idx < 0:
            diagnosis.raise_nonfinite(scene, f"scipy-{method}", ts[i], ys[i], kern, p, t0,
                                      y_init, stop=dict(t=float(ts[i]), steps=None,
                                                        rejected=None,
                                                        rhs_evaluations=int(sol.nfev)))
        ts, ys = ts[:first], np.ascontiguousarray(ys[:first])
        singularity = diagnosis.singularity(scene, kern, idx, ts[i], ys[i], p, t0, y_init,
                                            singular_tol, nonfinite=True)
        status, reason = SINGULAR, singularity["reason"]
    kw = {}
    if sol.status == 1 and not nonfinite:
        hit = [(sol.t_events[k][-1], k) for k in range(len(scipy_events))
               if len(sol.t_events[k]) and getattr(scipy_events[k], "terminal", False)]
        t_hit, k = min(hit, key=lambda x: x[0] * (1 if t1 >= t0 else -1))
        if k < n_user:
            status, reason = EVENT, f"terminal event {ce.names[k]!r} at t = {t_hit:.17g}"
        else:
            status = SINGULAR
            y_hit = sol.y_events[k][-1]
            singularity = diagnosis.singularity(scene, kern, k - n_user, t_hit, y_hit, p, t0,
                                                y_init, singular_tol)
            reason = singularity["reason"]
            if singularity["kind"] == "split":
                reason += (" scipy's methods do not change split (split='switch' is "
                           "dop853's, dopri5's, rk4's and radau's): this run stopped at "
                           "its chart's edge, as any method does with split='fixed'.")
    if ce is not None:
        y_ev = [np.array(sol.y_events[k], dtype=float).reshape(-1, n) for k in range(n_user)]
        if onto is not None:
            for k in range(n_user):
                onto(sol.t_events[k], y_ev[k])
        kw["events"] = (ce.names, [np.asarray(sol.t_events[k]) for k in range(n_user)],
                        [y[:, :n_state] for y in y_ev])
    if sensitivities is not None:
        kw["sensitivities"] = (scene._sensitivity_columns(), ys[:, n_state:].reshape(
            ys.shape[0], n_state, sensitivities.layout.sensitivity_columns))
        ys = np.ascontiguousarray(ys[:, :n_state])
    traj = Trajectory(scene, ts, ys, p, method=f"scipy-{method}", status=status,
                      stop_reason=reason, steps=None, rejected=None, nfev=int(sol.nfev),
                      wall_time=wall, kernels=kern, projected=scene.projected,
                      singularity=singularity, saved=saved, **kw)
    if sol.status == 1 and t_eval is not None and not nonfinite:
        # the stop of an event, after the last row: ``final``
        y_stop = np.array(sol.y_events[k][-1], dtype=float)[None, :]
        if onto is not None:
            onto(np.array([t_hit]), y_stop)
        traj._stopped(t_hit, y_stop[0, :n_state])
    if onto is None and scene.system.holonomic:
        drift.report(traj, f"scipy's {method} is a multistep method, whose steps are "
                         "not projected onto g = 0")
    return traj


def _onto(scene, sensitivities, p):
    """``onto(ts, ys)``: the rows ``ys`` (states at the times ``ts``, augmented by their
    sensitivities with ``sensitivities``; C-contiguous, writable) moved onto the
    holonomic constraints g = 0 in place, each as a step of jetnh's loops, in one call of
    ``projection.rows``; None without holonomic constraints."""
    m = len(scene.system.holonomic)
    if not m:
        return None
    kern = scene.kernels if sensitivities is None else sensitivities
    n_sens = 0 if sensitivities is None else sensitivities.layout.sensitivity_columns
    nq, p = scene.system.J.n, np.ascontiguousarray(p, dtype=float)

    def onto(ts, ys):
        projection.rows(kern.hol, m, nq, np.asarray(ts, dtype=float), ys, p, n_sens)
    return onto


def _projected(method, onto):
    """scipy's solver ``method`` (a one-step method) with every accepted step moved onto
    g = 0 by ``onto``, and the derivative there evaluated again (the next step starts
    from it)."""
    import scipy.integrate

    base = getattr(scipy.integrate, method)

    class Projected(base):
        def _step_impl(self):
            ok, message = super()._step_impl()
            if ok:
                y = np.array(self.y, dtype=float).reshape(1, -1)
                onto([self.t], y)
                self.y = y[0]
                self.f = self.fun(self.t, self.y)
            return ok, message

    Projected.__name__ = Projected.__qualname__ = f"Projected{method}"
    return Projected


def _final(solver):
    """``(class, made)``: scipy's solver ``solver`` (a name or a class) as a subclass that
    keeps where it is and the first accepted step whose end is not finite (with the
    state before it; scipy's solvers make ``self.y`` anew every step, LSODA a copy of its
    work array), and the list its instance is put in; ``rows`` makes from them the
    rows of a ``save="final"`` run: t0, then the last state (the state of a terminal
    event where the run ended in one), or the last finite state and the first state that
    is not (the run's singular stop or error is then that of every step's rows)."""
    import scipy.integrate

    base = getattr(scipy.integrate, solver) if isinstance(solver, str) else solver
    made = []

    class Final(base):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            self.not_finite = None
            made.append(self)

        def _step_impl(self):
            t, y = self.t, self.y       # (every step makes self.y anew: no copy)
            ok, message = super()._step_impl()
            if ok and self.not_finite is None and not math.isfinite(self.y.sum()):
                self.not_finite = (t, y, self.t, self.y)
            return ok, message

        def rows(self, t0, y0, sol, forward):
            if self.not_finite is not None:
                t, y, t_bad, y_bad = self.not_finite
                ts, ys = ([t0, t, t_bad], [y0, y, y_bad]) if t != t0 else (
                    [t0, t_bad], [y0, y_bad])
            elif sol.status == 1:       # the state solve_ivp records at the last root
                last = [(te[-1], k) for k, te in enumerate(sol.t_events) if len(te)]
                t, k = (max if forward else min)(last)
                ts, ys = [t0, t], [y0, sol.y_events[k][-1]]
            elif self.t != t0:
                ts, ys = [t0, self.t], [y0, self.y]
            else:
                ts, ys = [t0], [y0]
            return (np.array(ts, dtype=float),
                    np.ascontiguousarray(np.array(ys, dtype=float).reshape(len(ts), -1)))

    Final.__name__ = Final.__qualname__ = f"Final{base.__name__}"
    return Final, made
