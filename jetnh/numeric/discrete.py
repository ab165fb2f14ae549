"""The drivers of the discrete integrators dla and dvi (``methods.dla``,
``methods.dvi``): their kernels (``codegen.generate_dla``), the run, the trajectory of
the nodes, and the explanation of a failed step (a singular configuration, a Lagrangian
degenerate on the constraints).  Functions of the scene (``Scene.run`` calls them).
"""

from __future__ import annotations

import functools
import time

import numpy as np

from ..mechanics import principles
from ..errors import IntegrationError, PrincipleError
from . import codegen, diagnosis, drift, interrupt
from .kernels import load as load_kernels
from .methods import STATUS_TEXT
from .events import split_records
from .methods._common import ENDPOINTS, EVENT, EVERY_STEP, NONFINITE, NOT_CONVERGED, SINGULAR, STOPPED
from .trajectory import Trajectory


def kernels(scene, principle):
    """The kernels of the discrete step of ``principle`` (chetaev: dla, vakonomic: dvi)."""
    spec = scene.spec.but(principle=principle, form=None, convention="paper",
                          variant="discrete")
    return load_kernels(spec.key, lambda: codegen.generate_dla(spec), persistent=scene.cache)


def run_dla(scene, method, t0, t1, y_init, default_y0, p, n_steps, save, tol, max_iter,
            projection, singular_tol, timeout, ce=None):
    """A dla run (``methods.dla``, ``method`` its ``Method``); ``ce``: compiled user
    events (``node_events``)."""
    from .methods import dla

    if principles.get(scene.principle).integrator(scene.convention) != method.name:
        raise PrincipleError(
            "the discrete Lagrange-d'Alembert integrator discretizes Chetaev "
            f"(Lagrange-d'Alembert) dynamics, not {scene.principle}; use dop853"
            + (", or dvi (the discrete vakonomic integrator)"
               if scene.principle in ("vakonomic", "holder") else ""))
    n = scene.system.J.n
    q0 = np.ascontiguousarray(y_init[:n])
    v0 = full_velocities(scene, t0, y_init, p, default_y0)
    kern = scene.dla_kernels
    mode = EVERY_STEP if save == "steps" or ce is not None else ENDPOINTS
    n_sing = len(kern.layout.indicators) if singular_tol is not None else 0
    v0 = np.ascontiguousarray(v0, dtype=float)
    solve = dla.solver()
    constrained = degenerate_off_constraints(scene, kern, t0, q0, v0, p)
    uev, cols, ev_dir, ev_max = watched_events(scene, ce, 0)
    n_hol = len(scene.system.holonomic) if projection else 0
    hol = scene.kernels.hol_c if n_hol else _no_events()     # (never called without)
    hol_state = np.zeros(len(scene.state_names))
    halt = interrupt.flag()
    tic = time.perf_counter()
    out = interrupt.call(lambda: solve(
        kern.step_residual, kern.momentum, kern.legendre, kern.nodal, kern.constraint_jac,
        kern.sing, uev, hol, t0, t1, q0, v0, p, n_steps, scene.system.k, tol, max_iter,
        mode, projection, n_hol, hol_state, n_sing, float(singular_tol or 0.0),
        len(kern.layout.integrals), constrained, cols, ev_dir, ev_max, halt), halt,
        timeout)
    return _reported(trajectory(scene, method.name + ("+projection" if projection else ""),
                                kern, out, time.perf_counter() - tic, p, t0, t1, n_steps,
                                singular_tol, timeout, ce, save))


def run_dvi(scene, method, t0, t1, y_init, default_y0, p, n_steps, save, tol, max_iter,
            singular_tol, timeout, ce=None):
    """A dvi run (``methods.dvi``, ``method`` its ``Method``); ``ce``: compiled user
    events (``node_events``)."""
    from .methods import dvi

    if principles.get(scene.principle).integrator(scene.convention) != method.name:
        raise PrincipleError(
            "the discrete vakonomic integrator discretizes vakonomic dynamics (and "
            "Hoelder's in the paper's convention, which has the same equations), not "
            f"{scene.principle}" + ("; use dla for Chetaev" if scene.principle == "chetaev"
                                   else "; use dop853"))
    if scene.form not in (None, "multiplier"):
        raise PrincipleError(
            f"dvi uses the multipliers of the constraints as written (the 'multiplier' "
            f"form); the scene's form {scene.form!r} scales them differently: omit form=")
    J = scene.system.J
    n, k = J.n, scene.system.k
    q0 = np.ascontiguousarray(y_init[:n])
    lam0 = np.ascontiguousarray(y_init[n + n - k:])
    v0 = full_velocities(scene, t0, y_init, p, default_y0)
    kern = scene.dvi_kernels
    mode = EVERY_STEP if save == "steps" or ce is not None else ENDPOINTS
    n_sing = len(kern.layout.indicators) if singular_tol is not None else 0
    solve = dvi.solver()
    uev, cols, ev_dir, ev_max = watched_events(scene, ce, k)
    halt = interrupt.flag()
    tic = time.perf_counter()
    out = interrupt.call(lambda: solve(
        kern.step_residual, kern.momentum, kern.legendre, kern.nodal, kern.sing, uev, t0,
        t1, q0, v0, lam0, p, n_steps, tol, max_iter, mode, n_sing,
        float(singular_tol or 0.0), len(kern.layout.integrals), cols, ev_dir, ev_max, halt),
        halt, timeout)
    return _reported(trajectory(scene, method.name, kern, out, time.perf_counter() - tic,
                                p, t0, t1, n_steps, singular_tol, timeout, ce, save))


def _reported(traj):
    """``traj``, its drift off the holonomic constraints reported (``drift``: the nodes
    of dla and dvi are not projected onto g = 0, which would break their structure;
    dla's ``projection=True`` projects them, and reports only a projection that
    failed)."""
    if traj.scene.system.holonomic:
        drift.report(traj, f"{traj.method.split('+')[0]} keeps g = 0 through D g at each "
                     "step's midpoint only (a projection of the nodes would break its "
                     "structure: symmetry, symplecticity); a smaller h shrinks the drift "
                     "as h^2")
    return traj


def watched_events(scene, ce, k_lam):
    """What a discrete loop watches of the user events ``ce`` (or None): ``(uev, cols,
    direction, max_events)``, ``cols`` the columns of a node row that make the scene's
    state (coordinates, independent velocities, ``k_lam`` multipliers)."""
    J = scene.system.J
    n = J.n
    ind = [J.q.index(s) for s in scene.system.independent]
    cols = np.array([*range(n), *(n + i for i in ind), *range(2 * n, 2 * n + k_lam)],
                    dtype=np.int64)
    if ce is None:
        none = np.zeros(0, dtype=np.int64)
        return _no_events(), cols, none, none
    return ce.uev.cfunc, cols, ce.direction, ce.max_events


@functools.cache
def _no_events():
    """The event function of a run without events (never called): a compiled no-op, kept
    in jetnh's signed store (``kernels.loop_cache``; never numba's own cache)."""
    from .kernels.loop_cache import file_stamp, signed_cfunc
    from .methods._common import RHS_SIGNATURE

    return signed_cfunc(_nothing, RHS_SIGNATURE, file_stamp(__file__))


def _nothing(t, y, p, out):
    pass


def trajectory(scene, method, kern, out, wall, p, t0, t1, n_steps, singular_tol,
               timeout=None, ce=None, save="steps"):
    """A Trajectory from the result of a dla/dvi solve; a failed Newton step next to a
    singular configuration becomes a singular stop, any other failure an error; user
    events ``ce`` located between the nodes (``node_events``; the run itself ended at
    the node after a terminal one), the trajectory ending at a terminal one."""
    status, ts, rows, n_out, stats, t_last, y_last, sing_index, t_prev, y_prev = out
    status = int(status)
    J = scene.system.J
    n, k = J.n, scene.system.k
    k_lam = len(scene.state_names) - (2 * n - k)          # dvi: the multipliers
    name = method.split("+")[0]
    singularity = None
    if status == SINGULAR:
        singularity = node_singularity(scene, kern, int(sing_index), t_last, y_last, p,
                                       rows[0], t0, singular_tol)
    elif status in (NONFINITE, NOT_CONVERGED):
        singularity = explain_failure(scene, kern, t_last, y_last, t_prev, y_prev, p,
                                      rows[0], t0, singular_tol, n_out)
        if singularity is None:
            what = ("the state became NaN or infinite" if status == NONFINITE else
                    "Newton's method did not converge")
            raise IntegrationError(
                f"{name}: {what} in the step from t = {t_last:.17g} "
                f"(h = {(t1 - t0) / n_steps:.3g}); take a smaller step, or the discrete "
                "constraint has no nearby solution there",
                stop=dict(t=float(t_last), steps=int(stats[0]), rejected=0,
                          rhs_evaluations=int(stats[1])))
        status = SINGULAR
    rows = rows[:n_out]
    ind = [J.q.index(s) for s in scene.system.independent]
    ys = np.ascontiguousarray(np.hstack([rows[:, :n], rows[:, [n + i for i in ind]],
                                         rows[:, 2 * n:2 * n + k_lam]]))
    ts = ts[:n_out]
    kw = {}
    reason = (singularity["reason"] if singularity else diagnosis.timeout_reason(timeout, t_last)
              if status == STOPPED else STATUS_TEXT[status])
    if ce is not None:
        records, stop = node_events(ce, ts, ys, p)
        if stop is not None:         # a terminal event: the rows end there
            i, theta, which = stop
            rows = np.vstack([rows[:i + 1], rows[i] + theta * (rows[i + 1] - rows[i])])
            ys = np.vstack([ys[:i + 1], ys[i] + theta * (ys[i + 1] - ys[i])])
            ts = np.append(ts[:i + 1], records[-1][0])
            status, singularity = EVENT, None
            reason = f"terminal event {ce.names[which]!r} at t = {float(ts[-1]):.17g}"
        if save != "steps":
            keep = [0, len(ts) - 1] if len(ts) > 1 else [0]
            rows, ys, ts = rows[keep], ys[keep], ts[keep]
        kw["events"] = (ce.names, *split_records(
            len(ce), np.array([r[0] for r in records]),
            np.array([r[1] for r in records], dtype=np.int64),
            np.array([r[2] for r in records]).reshape(len(records), ys.shape[1])))
    c = 2 * n + k_lam
    own = {"velocities": {v.name: rows[:, n + i] for i, v in enumerate(J.qd)},
           "residual": rows[:, c:c + k], "energy": rows[:, c + k],
           "integrals": {nm: rows[:, c + k + 1 + i]
                         for i, nm in enumerate(kern.layout.integrals)}}
    return Trajectory(scene, ts, np.ascontiguousarray(ys), p, method=method, status=status,
                      stop_reason=reason, steps=int(stats[0]), rejected=0,
                      nfev=int(stats[1]), wall_time=wall, kernels=kern,
                      projected=scene.projected, own=own, singularity=singularity,
                      saved="steps" if save == "steps" else "final", **kw)


def _active(g_old, g_new, direction, first) -> bool:
    """The rule of ``_events.crossed``: a crossing in the event's direction; an exact zero
    at the start of a step other than the ``first`` is the root the previous step ended
    on, not a new crossing."""
    if g_old == 0.0 and not first:
        return False
    up = g_old <= 0.0 <= g_new
    down = g_old >= 0.0 >= g_new
    return up if direction > 0 else down if direction < 0 else (up or down)


def node_events(ce, ts, ys, p):
    """User events of a discrete run, with the semantics the compiled loops have
    (``_events.locate``: scipy's, a root on a node counted once): each event function at
    every node; in a step where one crosses zero its root by Brent's method (xtol = rtol
    = 4 eps) on the linear interpolant of the state between the nodes (second order, the
    order of dla and dvi); every active event counted, then the first terminal one
    (``max_events``-th occurrence) ends the run. Returns ``(records, stop)``: records
    ``(t, index, state)`` in order, stop ``(node, theta, index)`` of the terminal event
    or None."""
    from scipy.optimize import brentq

    funcs = ce.python_funcs
    G = np.array([[f(float(t), y, p) for f in funcs] for t, y in zip(ts, ys)])
    counts = np.zeros(len(funcs), dtype=np.int64)
    records = []
    eps = 4 * np.finfo(float).eps
    for i in range(len(ts) - 1):
        active = [k for k in range(len(funcs)) if _active(G[i, k], G[i + 1, k],
                                                          ce.direction[k], i == 0)]
        if not active:
            continue
        t0, h, y0, dy = ts[i], ts[i + 1] - ts[i], ys[i], ys[i + 1] - ys[i]
        roots = []
        for k in active:
            if G[i, k] == 0.0 or G[i + 1, k] == 0.0:
                theta = 0.0 if G[i, k] == 0.0 else 1.0
            else:
                theta = brentq(lambda th, k=k: funcs[k](t0 + th * h, y0 + th * dy, p),
                               0.0, 1.0, xtol=eps, rtol=eps)
            roots.append((theta, k))
            counts[k] += 1
        roots.sort(key=lambda r: r[0])
        for theta, k in roots:
            records.append((t0 + theta * h, k, y0 + theta * dy))
            if 0 < ce.max_events[k] <= counts[k]:
                return records, (i, theta, k)
    return records, None


def node(scene, y):
    """(q for the node kernels, v) from a discrete state (q, v[, lambda])."""
    n = scene.system.J.n
    return (np.ascontiguousarray(np.concatenate([y[:n], y[2 * n:]])),
            np.ascontiguousarray(y[n:2 * n]))


def node_indicators(scene, kern, t, y, p):
    g = np.empty(len(kern.layout.indicators))
    kern.sing(float(t), *node(scene, y), p, g)
    return g


def saddle(scene, kern, t, q, v, p):
    """M = d^2F/dqdot^2 and S = [[M, A^T], [A, 0]], A = df/dqdot, at a node: S is the
    matrix the discrete step inverts as h -> 0."""
    n, k = scene.system.J.n, scene.system.k
    M, mom = np.empty((n, n)), np.empty(n)
    A, f = np.empty((k, n)), np.empty(k)
    kern.legendre(float(t), q, v, p, mom, M)
    kern.constraint_jac(float(t), q, v, p, f, A)
    return M, np.block([[M, A.T], [A, np.zeros((k, k))]])


def saddle_condition(scene, kern, t, y, p) -> float:
    """Condition number of S (``saddle``) at a node (infinite where S is singular)."""
    _, S = saddle(scene, kern, t, *node(scene, y), p)
    with np.errstate(all="ignore"):
        c = np.linalg.cond(S) if np.all(np.isfinite(S)) else np.inf
    return float(c) if np.isfinite(c) else np.inf


def degenerate_off_constraints(scene, kern, t, q, v, p) -> bool:
    """Whether dla should take node velocities from the constrained Legendre transform:
    ||M^-1|| > 100 ||S^-1|| at the initial node (see ``methods.dla``)."""
    M, S = saddle(scene, kern, t, q, v, p)
    if not (np.all(np.isfinite(M)) and np.all(np.isfinite(S))):
        return False
    smin = lambda X: np.linalg.svd(X, compute_uv=False)[-1]  # noqa: E731
    return bool(smin(S) > 100 * smin(M))


def explain_failure(scene, kern, t, y, t_prev, y_prev, p, row0, t0, tol, n_out):
    """The singularity next to which a dla/dvi step failed (Newton did not converge or
    the state became NaN), or None: an indicator below 1 % of its initial size at the
    last regular node, or one whose linear trend over the last two nodes reaches its
    threshold within two steps; else a singular matrix [[F_vv, A^T], [A, 0]]."""
    y0 = row0[:y.shape[0]]
    if kern.layout.indicators:
        g0 = node_indicators(scene, kern, t0, y0, p)
        with np.errstate(all="ignore"):
            sg = np.sign(g0) / np.abs(g0)
            rel = sg * node_indicators(scene, kern, t, y, p)
            rel_prev = sg * node_indicators(scene, kern, t_prev, y_prev, p)
            bad = (~np.isfinite(rel) | (rel <= max(tol or 0.0, 1e-2))
                   | (rel + 2 * (rel - rel_prev) <= (tol or 0.0)))
        if bad.any():
            return node_singularity(scene, kern, int(np.argmax(bad)), t, y, p, row0,
                                    t0, tol, failed=True)
    cond = saddle_condition(scene, kern, t, y, p)
    if cond > 1e12:
        return node_singularity(scene, kern, -1, t, y, p, row0, t0, tol, failed=True,
                                cond=(cond, saddle_condition(scene, kern, t0, y0, p)))
    return None


def node_singularity(scene, kern, idx, t, y, p, row0, t0, tol, failed=False,
                     cond=None) -> dict:
    """The stop of a dla/dvi run at a singular configuration, as ``diagnosis.singularity``."""
    lay = kern.layout
    y0 = row0[:y.shape[0]]
    if cond is not None:
        expr, kind = "cond([[d2F/dqdot2, (df/dqdot)^T], [df/dqdot, 0]])", "degenerate"
        value, initial = cond
    else:
        expr, kind = lay.indicators[idx], lay.indicator_kinds[idx]
        initial = float(node_indicators(scene, kern, t0, y0, p)[idx])
        value = float(node_indicators(scene, kern, t, y, p)[idx])
    if cond is None and (not np.isfinite(initial) or initial == 0.0):
        where = f"the initial state (t = {t:.17g}) is singular: {expr} = {initial:.6g}"
    elif failed:
        where = (f"the step after the node t = {t:.17g} failed (Newton's method did not "
                 f"converge) where {expr} = {value:.6g} (initially {initial:.6g})"
                 + (" is singular" if cond is not None else
                    " is about to vanish or change sign"))
    else:
        where = (f"after the node t = {t:.17g}, {expr} (there {value:.6g}, initially "
                 f"{initial:.6g}) crosses zero or falls below singular_tol = {tol:g} of "
                 "its initial size; the run stops at that last regular node")
    hint = {
        "constraint": "The constraints f^a as written are singular or not differentiable "
                      "here (e.g. the Appell-Hamel constraint at zero horizontal speed), "
                      "so the motion has no unique continuation",
        "lagrangian": "The Lagrangian is singular or not differentiable here",
        "degenerate": "The Lagrangian is degenerate on the constraints here, or the "
                      "constraints lose rank: the discrete step (like the accelerations) "
                      "is not determined"}[kind]
    reason = f"singular configuration: {where}. {hint}."
    return {"indicator": expr, "kind": kind, "index": idx, "t": float(t),
            "value": value, "initial": initial, "reason": reason}


def full_velocities(scene, t0, y_init, p, default_y0) -> np.ndarray:
    """Every velocity at the initial state (the dependent ones from the constraints)."""
    J = scene.system.J
    n = J.n
    if default_y0:
        v0 = [scene.initial[v.name] for v in J.qd]
    else:
        vals = dict(zip(scene.coordinates + scene.velocities, y_init[:2 * n - scene.system.k]))
        vals.update(scene._dependent_velocity_values(
            vals, t0, dict(zip(scene.runtime_params, p))))
        v0 = [vals[v.name] for v in J.qd]
    return np.ascontiguousarray(v0, dtype=float)
