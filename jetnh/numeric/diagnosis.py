"""Why a run stopped early: singularity indicators and non-finite values explained.

``singularity`` turns the index of the indicator that stopped a run into its kind, values
and a reason that names the way out (another split, ``singular='ignore'``, an adaptive
method); ``stiff_reason`` and ``small_step_reason`` explain a run that an explicit
method found stiff (status ``STIFF``) and one whose step fell to the spacing of the
floating-point numbers, naming the singular set the motion is near (``near_singular``);
``explain_nonfinite`` finds the indicator behind a NaN or infinity, and
``raise_nonfinite`` raises the ``IntegrationError`` when none explains it.  Functions of
the scene (``Scene.run``, ensembles and the discrete drivers call them).
"""

from __future__ import annotations

import numpy as np

from ..algebra import dag
from ..errors import IntegrationError
from .methods import STATUS_TEXT
from .methods._common import STOPPED
from .methods._events import WATCH


def timeout_reason(timeout, t) -> str:
    """The stop reason of a run that the wall-clock budget (or Ctrl-C) stopped."""
    if timeout is None:
        return STATUS_TEXT[STOPPED]
    return (f"stopped at t = {float(t):.17g} by the wall-clock budget timeout = {timeout:g} s; "
            "raise timeout (or max_steps) to go further")


#: how far (times 1 + max |y|) the Euler probe of ``explain_nonfinite`` moves the state
PROBE_REACH = 1e3
#: parameter values beyond this factor from 1 are named when the rhs overflows
FAR_SCALE = 1e30
#: states beyond this size overflow the squares in the step-size control's norms
HUGE_STATE = 1e145


def explain_nonfinite(scene, kern, t, y, p, t0, y_init, tol) -> int:
    """Index of an indicator that explains a NaN/inf in the step after (t, y): small
    there (below max(tol, 1e-3) of its initial size), or violated along an Euler
    probe of the step (moving the state by at most ``PROBE_REACH`` times its size),
    else -1 (an overflow or a domain error at a regular configuration)."""
    lay = kern.layout
    m = len(lay.indicators)
    if not m:
        return -1
    g0 = np.empty(m)
    g = np.empty(m)
    kern.sing(t0, y_init, p, g0)
    kern.sing(t, y, p, g)
    with np.errstate(all="ignore"):
        rel = np.abs(g) / np.abs(g0)
        bad = ~np.isfinite(g) | (np.sign(g) != np.sign(g0)) | (rel < max(tol, 1e-3))
    if bad.any():
        return int(np.argmax(bad))
    f = np.empty_like(y)
    kern.rhs(t, y, p, f)
    if not np.all(np.isfinite(f)):
        # no indicator is small here: blame the one nearest to vanishing only if it
        # is near its singular set (below WATCH of its initial size); with every
        # denominator regular, a NaN or infinity is an overflow or a domain error
        i = int(np.argmin(rel))
        return i if rel[i] < WATCH else -1
    span = abs(scene.t_span[1] - scene.t_span[0]) or 1.0
    reach = PROBE_REACH * (1.0 + np.max(np.abs(y)))
    for s in np.geomspace(1e-12, 1.0, 25):
        for hh in (s * span, -s * span):
            if not np.max(np.abs(hh * f)) <= reach:     # no step moves the state so far:
                return -1                               # the rhs overflows (``overflow``)
            kern.sing(t + hh, y + hh * f, p, g)
            with np.errstate(all="ignore"):
                viol = ~np.isfinite(g) | (np.sign(g) != np.sign(g0))
            if viol.any():
                return int(np.argmax(viol))
    return -1


def _adaptive(method) -> bool:
    from .methods import method as lookup

    try:
        return lookup(method).adaptive
    except Exception:           # a name of a method this table does not hold
        return False


def singularity(scene, kern, idx, t, y, p, t0, y_init, tol, nonfinite=False,
                method=None) -> dict:
    """What the stop at a singular configuration was: indicator, kind, time, value,
    and a reason with the way out (``method``: the run's; an adaptive method that stops
    before the indicator reaches its threshold could not step closer).  An indicator
    that is NaN or infinite at the start while the others are finite and nonzero is no
    vanishing denominator: kind ``"nonfinite"``, an overflow (or a domain error)."""
    lay = kern.layout
    g0 = np.empty(len(lay.indicators))
    g = np.empty(len(lay.indicators))
    kern.sing(t0, y_init, p, g0)
    kern.sing(float(t), np.ascontiguousarray(y), p, g)
    with np.errstate(all="ignore"):
        rel = g / g0
    short = (np.isfinite(rel[idx]) and rel[idx] > 4 * tol and rel[idx] > 1e-12
             and not nonfinite)             # the indicator has not reached its threshold
    crawled = short and _adaptive(method)
    if crawled:         # name the singular set the motion approaches: the smallest one
        near = np.flatnonzero(np.isfinite(rel) & (rel > 0) & (rel < WATCH))
        if near.size:
            idx = int(near[np.argmin(rel[near])])
    expr, kind = lay.indicators[idx], lay.indicator_kinds[idx]
    value, initial = float(g[idx]), float(g0[idx])
    if not np.isfinite(initial) and regular_elsewhere(g0, idx):
        reason = (f"the initial state (t = {t:.17g}): {expr} = {initial:.6g}, a NaN or "
                  "infinity, not a zero; every other singularity indicator is finite and "
                  "nonzero there, so no denominator is shown to vanish: an intermediate "
                  "value overflowed (inf - inf, inf/inf) or left its domain. "
                  + overflow_hint(far_parameters(scene, p)) + ".")
        return {"indicator": expr, "kind": "nonfinite", "index": idx, "t": float(t),
                "value": value, "initial": initial, "reason": reason}
    if not np.isfinite(initial) or initial == 0.0:
        where = (f"the initial state (t = {t:.17g}) is singular: {expr} = {initial:.6g}")
    elif crawled:
        where = (f"at t = {t:.17g} the motion approaches the singular set {expr} = 0 "
                 f"({expr} = {value:.6g} is {value / initial:.3g} of its initial value, "
                 f"above the threshold singular_tol = {tol:g}), but {method} cannot step "
                 "closer: its steps shrank faster than the distance to that set (or its "
                 "dense output left the finite numbers), as where the equations in this "
                 "form are a 0/0 that floating point cannot resolve; the run stops at the "
                 "last regular point (a looser rtol stops it in fewer steps)")
    elif short:
        where = (f"the fixed step after t = {t:.17g} jumps over a kink of the right-hand "
                 f"side next to a zero of {expr} = {value:.6g} (initially {initial:.6g}); "
                 "the run stops at the last regular point (an adaptive method such as "
                 "dop853 locates the singular time)")
    elif nonfinite:
        where = (f"the right-hand side became NaN or infinite in the step after "
                 f"t = {t:.17g}, where {expr} = {value:.6g} (initially {initial:.6g}) "
                 "is about to vanish or change sign")
    else:
        where = (f"at t = {t:.17g}, {expr} fell to {value:.6g} (initially "
                 f"{initial:.6g}; the threshold is singular_tol = {tol:g} of that)")
    kind, hint = _kind_and_hint(scene, expr, kind, t, y, p, t0, y_init)
    reason = (f"singular configuration: {where}. {hint}. (If the singularity is removable "
              "-- a 0/0 that cancels -- run with singular='ignore'.)")
    return {"indicator": expr, "kind": kind, "index": idx, "t": float(t),
            "value": value, "initial": initial, "reason": reason}


def _kind_and_hint(scene, expr, kind, t, y, p, t0, y_init):
    """The kind of the singularity of the indicator ``expr`` at (t, y) and what it means
    (``singularity``)."""
    dep = [s.name for s in scene.system.dependent]
    ratio = (split_det_ratio(scene, t, y, p, t0, y_init)
             if kind != "split" and scene.system.k > 3 else None)
    if ratio is not None and ratio < 1e-6:
        kind = "split"      # for k > 3 the split's determinant is no indicator of its own
    if kind == "split":
        alt = regular_split(scene, t, y, p)
        hint = (f"The determinant of df/dqdot^alpha vanishes: the constraints cannot be "
                f"solved for the velocities of the dependent coordinates {dep} here. "
                + (f"The split is singular, not necessarily the motion: use another split "
                   f"(here dependent={alt} is regular{_switching(scene)})" if alt else
                   "df/dqdot could not be evaluated at this state, so no other split was "
                   "tried" if jacobian_at(scene, t, y, p) is None else
                   "No other split was found regular here (df/dqdot may lose rank): the "
                   "constraints themselves are singular"))
    elif kind == "constraint":
        hint = ("The explicit form of the constraints qdot^alpha = phi^alpha(t, q, "
                "qdot^mu) is singular or not differentiable here, so the dynamics "
                "have no unique continuation (e.g. the Appell-Hamel constraint at "
                "zero horizontal speed)")
    else:
        hint = ("A denominator (or a square-root argument) of the accelerations "
                "vanishes: the reduced mass matrix or the multiplier equations are "
                "singular here, so the accelerations are not determined")
    if ratio is not None and ratio > 1e-3 and kind == "constraint":
        hint = (f"The split is regular here (det df/dqdot^alpha is {ratio:.3g} of its "
                "initial value), but with more than 3 constraints phi^alpha comes from a "
                f"symbolic LU solve, and {expr} is a denominator of it -- likely a pivot "
                "that vanishes where the matrix does not: a singularity of the "
                "expressions, not of the motion. Order the constraints so that the solve "
                "can pivot on constants, or pass it")
    return kind, hint


def stiff_reason(scene, kern, method, t, y, p, t0, y_init) -> str:
    """The stop reason of a run that an explicit method found stiff (status ``STIFF``,
    ``methods.loop``): where, why, the way out, and the singular set the motion is near
    (``near_singular``)."""
    reason = (f"the problem became stiff for {method} at t = {float(t):.17g}: its estimate "
              "of h |lambda| (Hairer's test) stayed beyond its stability bound, so its "
              "steps are limited by stability, not by the tolerance (an explicit method "
              "needs ~|lambda| steps per unit of time here, whatever rtol). Run it with "
              "method='radau' (implicit: its steps follow the solution's own time scale)")
    near = near_singular(scene, kern, t, y, p, t0, y_init)
    if near is None:
        return reason + "."
    return reason + f"; {near[0]}, which may be what makes it stiff. {near[1]}."


def small_step_reason(scene, kern, method, t, y, p, t0, y_init) -> str:
    """The stop reason of a run whose step fell below the spacing of the floating-point
    numbers (status ``TOO_SMALL_STEP``), with the singular set the motion is near."""
    reason = (f"{method}: the step size fell below the spacing of floating-point numbers "
              f"at t = {float(t):.17g}")
    near = near_singular(scene, kern, t, y, p, t0, y_init)
    if near is None and huge_state(y):
        return reason + ". " + huge_state(y)
    if near is None:
        return (reason + ": the solution may blow up there, or the problem is too stiff "
                "for this tolerance; try a looser rtol, or method='radau'")
    return (reason + f"; {near[0]}, which {method} cannot approach at this tolerance (a "
            f"looser rtol stops it sooner). {near[1]}.")


def near_singular(scene, kern, t, y, p, t0, y_init):
    """``(where, hint)``: the singularity indicator smallest relative to its initial
    size at (t, y) if it is below ``WATCH`` of it (the singular set the motion is near,
    and what it means: ``_kind_and_hint``), else None."""
    m = len(kern.layout.indicators)
    if not m:
        return None
    g0 = np.empty(m)
    g = np.empty(m)
    kern.sing(float(t0), np.ascontiguousarray(y_init), p, g0)
    kern.sing(float(t), np.ascontiguousarray(y), p, g)
    with np.errstate(all="ignore"):
        rel = g / g0
    near = np.flatnonzero(np.isfinite(rel) & (rel < WATCH))
    if not near.size:
        return None
    i = int(near[np.argmin(rel[near])])
    expr = kern.layout.indicators[i]
    _, hint = _kind_and_hint(scene, expr, kern.layout.indicator_kinds[i], t, y, p, t0,
                             y_init)
    return (f"the motion is near the singular set {expr} = 0 (here {expr} is {rel[i]:.3g} "
            "of its initial value), where the equations are singular"), hint


def _switching(scene) -> str:
    """What a run with ``split='switch'`` does at the edge of this scene's split."""
    from .atlas import split_invariant

    if split_invariant(scene.principle, scene.convention):
        return ("; dop853, dopri5, rk4 and radau runs with split='switch' (the default) go "
                "on in it")
    return ("; but these equations depend on the split (Suslov's in the paper's "
            "convention), so a run cannot change split: start one in the other split")


def jacobian_at(scene, t, y, p):
    """df/dqdot (k x n) at the state (t, y), numerically, or None."""
    sys_ = scene.system
    J = sys_.J
    try:
        aux = np.empty(scene.kernels.layout.n_aux)
        scene.kernels.aux(float(t), np.ascontiguousarray(y, dtype=float), p, aux)
        vals = {J.t: t}
        vals.update(zip(J.q, y[:J.n]))
        vals.update(zip(sys_.independent_velocities, y[J.n:J.n + J.n - sys_.k]))
        vals.update(zip(sys_.dependent_velocities, aux[:sys_.k]))
        vals.update({s: scene.params[s.name] for s in sys_.parameters})
        for i, nm in enumerate(scene.runtime_params):
            vals.update({s: p[i] for s in sys_.parameters if s.name == nm})
        jac = sys_.jacobian
        A = np.array([float(v) for v in dag.evaluate_numpy(list(jac), vals)],
                     dtype=float).reshape(jac.shape)
    except (TypeError, ValueError):
        return None
    return A if np.all(np.isfinite(A)) else None


def split_det_ratio(scene, t, y, p, t0, y0):
    """|det df/dqdot^alpha| at (t, y) over its value at (t0, y0), or None."""
    cols = [scene.system.J.q.index(s) for s in scene.system.dependent]
    A, A0 = jacobian_at(scene, t, y, p), jacobian_at(scene, t0, y0, p)
    if A is None or A0 is None:
        return None
    d0 = abs(np.linalg.det(A0[:, cols]))
    return float(abs(np.linalg.det(A[:, cols])) / d0) if d0 else None


def regular_split(scene, t, y, p):
    """A choice of dependent coordinates for which df/dqdot is invertible at (t, y)."""
    from itertools import combinations

    sys_ = scene.system
    J = sys_.J
    A = jacobian_at(scene, t, y, p)
    if A is None:
        return None
    best, choice = 0.0, None
    for cols in combinations(range(J.n), sys_.k):
        d = abs(np.linalg.det(A[:, list(cols)]))
        if d > best:
            best, choice = d, [J.q[c].name for c in cols]
    norm = max(np.prod(np.linalg.norm(A, axis=1)), 1e-300)
    if choice is None or best < 1e-3 * norm or set(choice) == {s.name for s in sys_.dependent}:
        return None
    return choice


def regular_elsewhere(g0, idx) -> bool:
    """Whether every indicator but ``idx`` is finite and nonzero (``g0``: their values)."""
    rest = np.delete(np.asarray(g0, dtype=float), idx)
    return bool(np.all(np.isfinite(rest) & (rest != 0.0)))


def far_parameters(scene, p) -> list[str]:
    """``name = value`` of the parameters (compiled, and at run time ``p``) whose size is
    beyond ``FAR_SCALE`` from 1."""
    values = dict(scene.params)
    if p is not None:
        values.update(zip(scene.runtime_params, np.asarray(p, dtype=float).tolist()))
    far = []
    for name, v in sorted(values.items()):
        try:
            a = abs(float(v))
        except (TypeError, ValueError):
            continue
        if a > FAR_SCALE or 0.0 < a < 1.0 / FAR_SCALE:
            far.append(f"{name} = {float(v):.6g}")
    return far


def huge_state(y) -> str:
    """What a state beyond ``HUGE_STATE`` does to a run (the squares of its components
    overflow in the error norms, the motion need not blow up), or ''."""
    with np.errstate(all="ignore"):
        big = float(np.max(np.abs(y))) if np.size(y) else 0.0
    if not (np.isfinite(big) and big > HUGE_STATE):
        return ""
    return (f"The state is {big:.3g} in size: beyond ~{HUGE_STATE:.0e} the squares in the "
            "step-size control's norms overflow (the largest double is 1.8e308), whether "
            "or not the motion blows up; rescale the states (choose units in which they "
            "are of moderate size)")


def overflow_hint(far) -> str:
    """What to do when values overflow at a regular configuration (``far``: the
    parameters far from unit scale, ``far_parameters``)."""
    units = ("nondimensionalise the model (choose units in which its parameters and "
             "states are of moderate size)")
    if far:
        return (f"Likely cause: parameter values far from unit scale ({', '.join(far)}), "
                f"whose products leave the floating-point range; {units}")
    return f"If the model's values are far from unit scale, {units}"


def raise_nonfinite(scene, method, t, y, kern=None, p=None, t0=None, y_init=None,
                    checked=True, stop=None):
    state = ", ".join(f"{n} = {v:.17g}" for n, v in zip(scene.state_names, y))
    extra = ""
    regular = False
    if kern is not None and kern.layout.indicators:
        g = np.empty(len(kern.layout.indicators))
        kern.sing(float(t), np.ascontiguousarray(y, dtype=float), p, g)
        extra = ("; singularity indicators there: "
                 + ", ".join(f"{e} = {v:.6g}" for e, v in zip(kern.layout.indicators, g)))
        regular = bool(np.all(np.isfinite(g) & (g != 0.0)))
    size = ""
    if kern is not None and checked and p is not None and np.all(np.isfinite(y)):
        f = np.empty(len(y))
        with np.errstate(all="ignore"):
            kern.rhs(float(t), np.ascontiguousarray(y, dtype=float), p, f)
        big = float(np.max(np.abs(f))) if f.size else 0.0
        regular = regular or not kern.layout.indicators
        far = far_parameters(scene, p)
        if regular and (big > FAR_SCALE or (not np.isfinite(big) and far)):
            size = (". The right-hand side there is "
                    + (f"{big:.3g} in size" if np.isfinite(big) else "not finite")
                    + " at a configuration where every singularity indicator is regular: "
                    "it overflowed (or produced inf - inf = NaN), no singular "
                    "configuration. " + overflow_hint(far))
    why = (huge_state(y) if huge_state(y) and kern is not None and checked else
           "No singularity indicator explains it: the solution blows up, or an "
           "expression leaves its domain; check the model and the initial values, or "
           "integrate a shorter span" + size if kern is not None and checked else
           "The singularity checks were off (singular='ignore'); run with "
           "singular='stop' to stop at singular configurations" if kern is not None else
           "The equations are singular there (a vanishing denominator of the dependent "
           "velocities or of the reduced mass matrix), or the solution blows up")
    if method == "rk4":
        why += (". A fixed step beyond rk4's stability bound (h |lambda| > 2.8 for an "
                "eigenvalue lambda of the Jacobian: a stiff problem) blows up too: take a "
                "smaller h (more n_steps) or method='radau'")
    raise IntegrationError(
        f"{method}: the right-hand side or the state became NaN or infinite in the step "
        f"from t = {t:.17g}; state there: {state}{extra}. {why}", stop=stop)
