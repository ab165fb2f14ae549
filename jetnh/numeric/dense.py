"""Values of a trajectory at any time of its span (``Trajectory.at``).

- dop853, dopri5: the step of the run that covers each time is taken again, from its
  stored start (t_k, y_k) with the step h_k = t_{k+1} - t_k and the times as ``t_eval``.
  An accepted step is a function of (t_k, y_k, h_k) alone (its first stage is
  f(t_k, y_k), which the run reused from the step before), so its dense output is the
  one the original run gives with those times as ``t_eval``: the same bits.
- rk4: the cubic Hermite interpolant of each step through y and f(t, y) at its ends,
  the one rk4 locates events on; its error is O(h^4), the order of the method.
- On a system with holonomic constraints g = 0 the values inside a step are moved onto
  g = 0 as the steps are (``methods.projection.rows``; the re-taken steps of dop853 and
  dopri5 do so in their loop, ``loops.on_constraints``), with their sensitivities.
- radau: the collocation polynomial of each step, the one its ``t_eval`` and events
  use, from the step's start (t_k, y_k) and size h_k (``radau.collocation``: the stage
  equations solved to rounding level, where the run stopped Newton at its
  ``newton_tol``; the run's own polynomial agrees to that tolerance, not to the bit);
  each step's end is checked against the run's next row.
- dla, dvi and scipy's methods: no interpolant (the discrete integrators have none that
  matches their nodes and multipliers) and an error that says what to do.

``resampled`` gives the run at the rows and evenly between them (the smooth curves of
``Trajectory.plot``), or the rows alone where there is no dense output.

Only a trajectory that holds every step (``save="steps"``, no ``t_eval``) can be
evaluated; the last interval of a run stopped inside a step (a terminal event or a
singular stop) is not a whole step, and only its end is available.
"""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError, IntegrationError, JetnhError
from . import arguments
from .loops import onto_constraints, retake
from .methods import method
from .methods._common import EVERY_STEP


def _times(times, lo, hi) -> np.ndarray:
    """Times to evaluate at, checked as every array for compiled code is: real, finite
    numbers (in any order), inside [lo, hi]."""
    a = arguments.real_array(np.atleast_1d(times), "times")
    if a.size and (a.min() < lo or a.max() > hi):
        raise ArgumentError(f"times must lie within the trajectory's span [{lo!r}, {hi!r}]; "
                            f"got [{a.min()!r}, {a.max()!r}]")
    return a


def _refusal(traj) -> str | None:
    """Why ``traj`` cannot be evaluated between its rows, or None."""
    d = traj._dense
    if d is None:
        return (f"{traj.method} trajectories have no dense output to evaluate between rows; "
                "run with method='dop853' or 'dopri5' (steps re-taken exactly), 'radau' "
                "(its collocation polynomials) or 'rk4' (cubic Hermite), or pass the "
                "times as t_eval= to the run")
    if d["mode"] != EVERY_STEP:
        return ("evaluation re-takes the steps of the run, so the trajectory must hold every "
                "step: run with save='steps' and without t_eval (or pass these times as "
                "t_eval= to the run)")
    return None


def evaluate(traj, times, full=False) -> np.ndarray:
    """The states at ``times`` (any order, inside the span): ``[len(times), n_states]``;
    with ``full``, a run with sensitivities gives its whole integrated state (the
    state, then S row-major: ``Layout.n_rhs`` columns).  A run made of pieces (a change
    of split, multiple shooting's segments) is evaluated by its pieces."""
    if traj._segments is not None:
        return traj._segments.evaluate(traj, times, full)
    why = _refusal(traj)
    if why:
        raise JetnhError(why)
    t = traj.t
    if not len(t):
        raise JetnhError("the trajectory is empty; there is nothing to evaluate")
    tau = _times(times, float(t.min()), float(t.max()))
    rows = traj._dense.get("y", traj.y) if full else traj.y
    n = rows.shape[1]
    out = np.empty((tau.shape[0], n))
    if len(t) == 1 or not tau.size:
        out[:] = rows[0]
        return out
    sgn = 1.0 if t[-1] >= t[0] else -1.0
    # time tau belongs to the first step whose end is not before it (as t_eval does)
    k = np.minimum(np.searchsorted(sgn * t[1:], sgn * tau, side="left"), len(t) - 2)
    last = len(t) - 2
    if traj._dense["partial_last"]:
        bad = (k == last) & (tau != t[-1])
        if bad.any():
            raise JetnhError(
                f"the run stopped inside its last step ({traj.stop_reason[:120]}), so "
                f"[{t[-2]!r}, {t[-1]!r}] is not a whole step and cannot be re-taken or "
                f"re-solved; times there (e.g. {tau[bad][0]!r}) are not available, only its "
                f"end t = {t[-1]!r}")
        ends = (k == last)
        out[ends] = rows[-1]
        keep = ~ends
    else:
        keep = np.ones(tau.shape[0], dtype=bool)
    step = (_hermite_steps if method(traj.method).fixed_step else
            _collocation_steps if traj.method == "radau" else _retaken_steps)
    idx = np.nonzero(keep)[0]
    if idx.size:
        order = idx[np.lexsort((sgn * tau[idx], k[idx]))]
        out[order] = step(traj, k[order], tau[order])[:, :n]
    return out


#: a resampled run has at least this many points (the rows, and points between them)
SMOOTH_POINTS = 400


def resampled(traj, points=SMOOTH_POINTS):
    """``traj`` at its rows and, where the method has dense output, at evenly spaced
    times inside its steps: at least ``points`` values in all (a run with as many steps
    already is its rows).  A Trajectory of the same run, scene and kernels; without
    dense output (dla, dvi, scipy's methods, ``t_eval`` or ``save="final"`` runs) or with
    a change of split ``traj`` itself."""
    t = traj.t
    n_steps = len(t) - 1
    if (traj._segments is not None or _refusal(traj) or n_steps < 1
            or n_steps >= points):         # (a run that changed split: its rows)
        return traj
    per = -(-points // n_steps)                          # values per step, its start included
    last = n_steps - 1 if traj._dense["partial_last"] else n_steps
    frac = np.arange(1, per) / per
    inner = (t[:last, None] + frac[None, :] * np.diff(t)[:last, None]).ravel()
    inner_y = evaluate(traj, inner).reshape(last, per - 1, -1)
    ys = np.concatenate([traj.y[:last, None, :], inner_y], axis=1).reshape(-1, traj.y.shape[1])
    ts = np.concatenate([t[:last, None], inner.reshape(last, per - 1)], axis=1).ravel()
    ts = np.concatenate([ts, t[last:]])
    return sampled(traj, ts, np.concatenate([ys, traj.y[last:]]))


def sampled(traj, t, y):
    """A Trajectory of the run of ``traj`` with the states ``y`` at the times ``t`` (its
    derived columns from the same kernels); no steps, no events, no dense output."""
    return type(traj)(traj.scene, t, y, traj._p, method=traj.method, status=traj.status,
                      stop_reason=traj.stop_reason, steps=None, rejected=None, nfev=0,
                      wall_time=0.0, kernels=traj._kernels, saved="t_eval")


def _groups(k):
    """(step, start, stop) of the runs of equal values in the sorted array ``k``."""
    cut = np.nonzero(np.diff(k))[0] + 1
    starts = np.concatenate([[0], cut])
    stops = np.concatenate([cut, [k.shape[0]]])
    return [(int(k[a]), a, b) for a, b in zip(starts, stops)]


def _retaken_steps(traj, k, tau) -> np.ndarray:
    """dop853/dopri5: re-take step k[i] with the times tau (sorted by step, then time)
    through the run's own loop (``loops.retake``)."""
    t, y = traj.t, traj._dense.get("y", traj.y)
    out = np.empty((tau.shape[0], y.shape[1]))
    for j, a, b in _groups(k):
        t0, t1 = float(t[j]), float(t[j + 1])
        res = retake(traj, t0, t1, np.array(y[j]), np.ascontiguousarray(tau[a:b]))
        status, _, ys, n_out, stats = res[:5]
        if int(status) != 0 or int(stats[1]) != 0 or int(n_out) != b - a:
            raise IntegrationError(
                f"re-taking the step from t = {t0!r} to {t1!r} did not reproduce it (status "
                f"{int(status)}, {int(stats[1])} rejected); the trajectory's arrays were "
                "changed after the run?")
        out[a:b] = ys[:b - a]
    return out


#: how far (in the run's tolerances, RMS) a re-solved radau step may end from the run's
#: next row: the run stops Newton at newton_tol, which can leave a few tolerances on a
#: stiff step; a changed array is off by far more
_REPRODUCED = 10.0


def _collocation_steps(traj, k, tau) -> np.ndarray:
    """radau: the collocation polynomial of step k[i] at tau (sorted by step, then time;
    ``radau.collocation``), its end checked against the run's next row (within
    ``_REPRODUCED`` times the run's tolerance, after the move onto g = 0 that the run
    made), the values inside a step moved onto g = 0 as the run's ``t_eval`` rows are; at
    a step's ends its rows."""
    from .methods._events import dense_eval
    from .methods.radau import collocation

    d = traj._dense
    sens = d.get("rhs")
    kern = traj._kernels if sens is None else sens
    jac = traj.scene.jacobian if sens is None else sens.jac
    t, y, p = traj.t, d.get("y", traj.y), np.ascontiguousarray(traj._p, dtype=float)
    n = y.shape[1]
    hol = traj._kernels.layout.holonomic
    n_sens = n // traj._kernels.layout.n_state - 1
    out = np.empty((tau.shape[0], n))
    for j, a, b in _groups(k):
        t0, t1 = float(t[j]), float(t[j + 1])
        h = t1 - t0
        y0 = np.array(y[j])
        F = collocation(kern.rhs, jac, t0, h, y0, p)
        end = np.empty((1, n))
        if F is not None:
            dense_eval(1.0, y0, F, end[0])
            if hol:
                onto_constraints(kern, np.array([t1]), end, p, n_sens)
            scale = d["atol"] + d["rtol"] * np.maximum(np.abs(y0), np.abs(y[j + 1]))
        off = np.sqrt(np.mean(((end[0] - y[j + 1]) / scale) ** 2)) if F is not None else None
        if off is None or not off <= _REPRODUCED:
            found = ("no convergence" if off is None else
                     f"an end off the run's next row by {off:.3g} times its tolerance")
            raise IntegrationError(
                f"solving the collocation equations of the step from t = {t0!r} to {t1!r} "
                f"again did not reproduce it ({found}): the run stopped its Newton "
                "iterations at newton_tol, which on a stiff step can leave a few "
                "tolerances (run again with a smaller newton_tol, e.g. 1e-10), or the "
                "trajectory's arrays were changed after the run")
        rows = out[a:b]
        for i, theta in enumerate((tau[a:b] - t0) / h):
            dense_eval(float(theta), y0, F, rows[i])
        start, stop = tau[a:b] == t0, tau[a:b] == t1
        rows[start], rows[stop] = y[j], y[j + 1]
        inner = np.flatnonzero(~start & ~stop)
        if hol and inner.size:
            moved = np.ascontiguousarray(rows[inner])
            onto_constraints(kern, tau[a:b][inner], moved, p, n_sens)
            rows[inner] = moved
    return out


def _hermite_steps(traj, k, tau) -> np.ndarray:
    """rk4: the cubic Hermite interpolant of step k[i] at tau (the form of rk4's own)."""
    kern, d = traj._kernels, traj._dense
    kern = d.get("rhs", kern)                   # with sensitivities: the augmented rhs
    t, y, p = traj.t, d.get("y", traj.y), np.ascontiguousarray(traj._p, dtype=float)
    n = y.shape[1]
    nodes = np.unique(np.concatenate([k, k + 1]))
    f = {}
    for j in nodes:
        f[j] = np.empty(n)
        kern.rhs(float(t[j]), np.array(y[j]), p, f[j])
    h = (t[k + 1] - t[k])[:, None]
    th = ((tau - t[k]) / (t[k + 1] - t[k]))[:, None]
    f0 = np.array([f[j] for j in k])
    f1 = np.array([f[j + 1] for j in k])
    d = y[k + 1] - y[k]
    F1 = h * f0 - d
    F2 = d - h * f1 - F1
    out = y[k] + th * (d + (1.0 - th) * (F1 + th * F2))
    if traj._kernels.layout.holonomic:
        # inside a step: off g = 0 by the interpolant's error, moved onto it as the
        # steps are; at a step's ends the step's own (projected) row
        start, end = tau == t[k], tau == t[k + 1]
        out[start], out[end] = y[k[start]], y[k[end] + 1]
        inner = np.flatnonzero(~start & ~end)
        rows = out[inner]
        onto_constraints(kern, tau[inner], rows, p, n // traj._kernels.layout.n_state - 1)
        out[inner] = rows
    return out
