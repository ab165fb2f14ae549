"""Work-precision: error at the final time against wall time, jetnh's compiled integrators
against scipy's ``solve_ivp`` on the same equations, for six catalogue systems under
Chetaev and vakonomic dynamics.

    .venv/bin/python benchmarks/workprecision.py [--quick] [--out PATH] [--panels LABEL ...]

(default output: benchmarks/results/workprecision.json and, next to it,
workprecision_chetaev.png, workprecision_vakonomic.png, workprecision_tolerance.png).

Methodology (SciML's DiffEqDevTools ``WorkPrecision``): for rtol = 1e-3 ... 1e-12 with
atol = 1e-3 rtol, the error at the final time T is

    err = max_i |y_i(T) - y_ref,i(T)| / max(|y_ref,i(T)|, 1)

over every state (coordinates, independent velocities, multipliers), against the exact
solution where the catalogue gives one (evaluated with mpmath at 30 digits) and otherwise
against a tight jetnh DOP853 run (rtol 2.5e-14) whose uncertainty is bounded by its
distance to a jetnh run at 1e-13 and to scipy's DOP853 at 2.5e-14 on the lambdified
right-hand side (an independent integrator and evaluation); on the exact cases the same
procedure is checked against the closed form.  Errors below that bound are not resolved.

Systems (catalogue defaults, multipliers starting at +-0.1): rolling_disk (T = 100),
nonholonomic_particle (T = 50), knife_edge (T = 0.8), chaplygin_sleigh (T = 2),
isokinetic_particle (T = 2, a constraint nonlinear in the velocities), n_trailer:N=3
(T = 2; vakonomic T = 0.5, multipliers +-0.01); the short spans end before the split's
singular configuration (cos(heading) = 0).  Appell-Hamel is left out: its motion is
quadratic in t, so every method is exact to round-off at any tolerance.

Methods: jetnh ``dop853`` and ``dopri5`` (adaptive, compiled); ``rk4`` and the discrete
``dla`` (Chetaev) / ``dvi`` (vakonomic) at fixed step counts; scipy ``solve_ivp`` with
RK45, DOP853, LSODA and Radau on the researcher's route -- the same equations (jetnh's
derivation) through ``sympy.lambdify(cse=True, modules="math")``; and scipy's DOP853 on
jetnh's compiled right-hand side (``Scene.run(method="scipy-DOP853")``), which separates
the cost of the integrator loop from that of the right-hand side.  Every call is timed
from Python (``scene.run(save="final")`` against ``solve_ivp(t_eval=[T])``): each
method's figure is the best of several rounds, each round calling every method three
times in a row (``_common.best_of_blocks``), so the figure is a warm call, as in a loop of
runs and as DiffEqDevTools times each method, while the rounds stay interleaved against
changes of the machine's load; the best first call of a round (right after the other
methods' calls, with cold caches) is kept too, and its ratio is reported beside.  Summaries: the time each method needs to reach an
error (the cheapest run at or below it), the ratios to jetnh's fastest adaptive method
at equal error, and achieved error / requested rtol.

The floor: what any implementation that makes jetnh's right-hand-side evaluations must
pay, measured on each panel in the same run.  floor = n x e + c, where n is the fewest
evaluations of a jetnh adaptive run that reaches the error, e the cost of one evaluation
of the panel's compiled rhs in a bare compiled loop (``_common.rhs_driver``; best of
several batches) and c the fixed cost of a call of the compiled dop853 loop (called
directly on a one-step span, as ``overhead.py --fixed`` calls it: 5th percentile of
single calls, less that call's own evaluations at e).  The fastest scipy method's time
over the floor is the largest ratio such an implementation could reach; the step
control, the stage sums and the checks of each step come on top.  The run floor adds what
a run from Python cannot skip while Ctrl-C stops it within a step (``numeric.interrupt``):
a halt flag, one ``set_wakeup_fd`` where the tree's runs confirm the wakeup fd each time,
and the Trajectory of the result (``python_floor``).  Between the floor and
jetnh's time: its compiled loop called directly with the run's arguments (best of several
calls in a row),
i.e. the run without its Python side and, where the split can change, without the chart
bookkeeping (``numeric.atlas``).
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field

import mpmath as mp
import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

from _common import best, best_of_blocks, parser, rhs_driver, write

import jetnh.models as models
from jetnh.errors import JetnhError
from jetnh.numeric import Scene
from jetnh.numeric.codegen import multiplier_names

SCIPY = ("RK45", "DOP853", "LSODA", "Radau")
JETNH_ADAPTIVE = ("dop853", "dopri5")
TARGETS = (1e-4, 1e-6, 1e-8, 1e-10)
GOAL = 50.0             # the ratio to the fastest scipy method aimed at on every panel


# ---------------------------------------------------------------------- exact solutions
# Chetaev closed forms from the models' docstrings, in mpmath (30 digits); each takes the
# parameters and initial state by name and T, returns the state at T by name.
def disk_exact(p, s, T):
    phi, psi = s["phi"] + s["phi_t"] * T, s["psi"] + s["psi_t"] * T
    c = p["R"] * s["phi_t"] / s["psi_t"]
    return dict(s, phi=phi, psi=psi, x=s["x"] + c * (mp.sin(psi) - mp.sin(s["psi"])),
                y=s["y"] - c * (mp.cos(psi) - mp.cos(s["psi"])))


def particle_exact(p, s, T):
    y0, u = s["y"], s["y_t"]
    y = y0 + u * T
    c = s["x_t"] * mp.sqrt(1 + y0**2)
    return dict(s, y=y, x_t=c / mp.sqrt(1 + y**2),
                x=s["x"] + c / u * (mp.asinh(y) - mp.asinh(y0)),
                z=s["z"] + c / u * (mp.sqrt(1 + y**2) - mp.sqrt(1 + y0**2)))


def knife_exact(p, s, T):
    w, phi0 = s["phi_t"], s["phi"]
    c = p["g"] * mp.sin(p["alpha"]) / w
    A = s["x_t"] / mp.cos(phi0) - c * mp.sin(phi0)
    phi = phi0 + w * T

    def X(f):
        return A * mp.sin(f) + c * mp.sin(f) ** 2 / 2

    def Y(f):
        return -A * mp.cos(f) + c * (f - mp.sin(f) * mp.cos(f)) / 2
    return dict(s, phi=phi, x=s["x"] + (X(phi) - X(phi0)) / w,
                y=s["y"] + (Y(phi) - Y(phi0)) / w, x_t=(A + c * mp.sin(phi)) * mp.cos(phi))


def sleigh_exact(p, s, T):
    m, a = p["m"], p["a"]
    K = p["I"] + m * a**2
    v0, w0 = s["x_t"] / mp.cos(s["theta"]), s["theta_t"]
    V = mp.sqrt(v0**2 + K * w0**2 / m)
    c = mp.atanh(v0 / V)
    k = m * a * V / K

    def theta(t):
        return s["theta"] + w0 * mp.cosh(c) / k * (mp.atan(mp.sinh(k * t + c))
                                                   - mp.atan(mp.sinh(c)))

    def v(t):
        return V * mp.tanh(k * t + c)
    th = theta(T)
    return dict(s, theta=th, theta_t=w0 * mp.cosh(c) / mp.cosh(k * T + c),
                x_t=v(T) * mp.cos(th),
                x=s["x"] + mp.quad(lambda t: v(t) * mp.cos(theta(t)), [0, T]),
                y=s["y"] + mp.quad(lambda t: v(t) * mp.sin(theta(t)), [0, T]))


def isokinetic_exact(p, s, T):
    v, g = p["v"], p["g"]
    s0 = mp.atanh(s["y_t"] / v)
    S = s0 - g * T / v

    def gd(u):
        return mp.atan(mp.sinh(u))
    return dict(s, y_t=v * mp.tanh(S), x=s["x"] - v**2 / g * (gd(S) - gd(s0)),
                y=s["y"] - v**2 / g * (mp.log(mp.cosh(S)) - mp.log(mp.cosh(s0))))


def trailer_exact(p, s, T):
    """The steady turn of ``n_trailer_turning``: every heading turns at theta0_t."""
    W = s["theta0_t"]
    R0 = -s["y"]
    out = {k: (val + W * T if k.startswith("theta") and not k.endswith("_t") else val)
           for k, val in s.items()}
    out.update(x=R0 * mp.sin(W * T), y=-R0 * mp.cos(W * T), x_t=R0 * W * mp.cos(W * T))
    return out


# ---------------------------------------------------------------------- the cases
@dataclass
class Case:
    model: str
    principle: str
    t_end: float
    exact: object = None                          # Chetaev closed form, or None
    options: dict = field(default_factory=dict)
    multipliers: float = 0.1                      # initial |lambda|, alternating signs

    @property
    def label(self) -> str:
        opts = "".join(f":{k}={v}" for k, v in self.options.items())
        return f"{self.model}{opts} / {self.principle}"


def cases(quick: bool):
    out = []
    for model, T, exact, opts in (
            ("rolling_disk", 100.0, disk_exact, {}),
            ("nonholonomic_particle", 50.0, particle_exact, {}),
            ("knife_edge", 0.8, knife_exact, {}),
            ("chaplygin_sleigh", 2.0, sleigh_exact, {}),
            ("isokinetic_particle", 2.0, isokinetic_exact, {}),
            ("n_trailer", 2.0, trailer_exact, {"N": 3})):
        out.append(Case(model, "chetaev", T, exact, opts))
        out.append(Case(model, "vakonomic", T if model != "n_trailer" else 0.5, None, opts,
                        0.1 if model != "n_trailer" else 0.01))
    return out[:2] if quick else out


def scene_of(case: Case) -> Scene:
    system = models.get(case.model, **case.options)
    ini = models.initial(case.model, **case.options)
    lam = {name: case.multipliers * (-1) ** i
           for i, name in enumerate(multiplier_names(system, case.principle))}
    return Scene(system, case.principle, initial={**ini, **lam}, t_span=(0.0, case.t_end))


def researcher_rhs(scene: Scene):
    """What a researcher would otherwise integrate: the same equations (jetnh's
    accelerations and multiplier rates, the dependent velocities phi and the parameter
    values substituted) through ``sympy.lambdify(cse=True, modules="math")``, as a
    Python ``f(t, y)`` for ``solve_ivp`` over the scene's state."""
    system = scene.system
    J = system.J
    eom = system.equations(scene.principle, form=scene.form, convention=scene.convention)
    acc = eom.accelerations()
    num = {s: scene.params[s.name] for s in system.parameters}
    phi = {v: e.xreplace(num) for v, e in system.phi.items()}
    states = list(J.q) + list(system.independent_velocities) + list(eom.multipliers)
    assert [s.name for s in states] == list(scene.state_names)
    exprs = [phi.get(v, v) for v in J.qd]
    exprs += [acc[J.jet(J.split(v)[0], 2)] for v in system.independent_velocities]
    exprs += [acc[r] for r in eom.multiplier_rates]
    exprs = [sp.sympify(e).xreplace(phi).xreplace(num) for e in exprs]
    f = sp.lambdify((J.t, states), exprs, modules="math", cse=True)
    return lambda t, y: np.array(f(t, y))


# ---------------------------------------------------------------------- one panel
def error(y, ref) -> float:
    return float(np.max(np.abs(y - ref) / np.maximum(np.abs(ref), 1.0)))


def reference(case: Case, scene: Scene, f):
    """(y_ref(T), description) -- see the module docstring."""
    T = case.t_end
    tight = scene.run(rtol=2.5e-14, atol=1e-17, save="final").y[-1]
    check = scene.run(rtol=1e-13, atol=1e-16, save="final").y[-1]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        other = solve_ivp(f, (0.0, T), scene.y0, method="DOP853", rtol=2.5e-14,
                          atol=1e-17, t_eval=[T]).y[:, -1]
    bound = max(error(check, tight), error(other, tight))
    info = {"kind": "tight run", "uncertainty": bound,
            "how": "jetnh dop853 rtol 2.5e-14; uncertainty: max distance to jetnh dop853 "
                   "rtol 1e-13 and scipy DOP853 (lambdified rhs) rtol 2.5e-14"}
    if case.exact is None:
        return tight, info
    with mp.workdps(30):
        p = {k: mp.mpf(v) for k, v in scene.params.items()}
        s = {k: mp.mpf(v) for k, v in scene.initial.items() if k in scene.state_names}
        ex = case.exact(p, s, mp.mpf(T))
        y = np.array([float(ex[n]) for n in scene.state_names])
    return y, {"kind": "exact", "uncertainty": 2.0**-53,     # rounding to float64
               "how": "closed form (model docstring), mpmath 30 digits",
               "tight_run_error": error(tight, y), "tight_run_bound": bound}


def floor_costs(scene, drive, reps, calls) -> dict:
    """The floor's costs on ``scene`` (module docstring): ``per_evaluation_s`` (e),
    ``fixed_s`` (c) and the bare call it comes from (seconds, evaluations)."""
    y, p = scene.y0.copy(), scene.p
    n = 20_000
    rhs = scene.kernels.rhs_fp
    drive(rhs, y.copy(), p, 10)
    per = best(lambda: drive(rhs, y.copy(), p, n), reps)[0] / n
    t0 = scene.t_span[0]
    short = scene.replace(t_span=(t0, t0 + 1e-6))
    plan = short._quick_plan("dop853", "final", None, None)
    halt = np.zeros(1, dtype=np.int64)
    args = (*plan.prefix, plan.t0, plan.t1, short.y0.copy(), short.p, *plan.suffix, halt)
    nfev = int(plan.entry(*args)[4][2])
    times = []
    for _ in range(calls):
        tic = time.perf_counter()
        plan.entry(*args)
        times.append(time.perf_counter() - tic)
    call = float(np.percentile(times, 5))
    return dict(per_evaluation_s=per, fixed_s=call - nfev * per, bare_call_s=call,
                bare_call_nfev=nfev, python_s=python_floor(short, plan, args, calls))


def python_floor(short, plan, args, calls) -> float | None:
    """What a run from Python adds to its compiled call and cannot skip while Ctrl-C
    stops it within a step (``numeric.interrupt``): a fresh halt flag, the wakeup fd
    confirmed where this tree's runs confirm it each time (one ``set_wakeup_fd``; a tree
    that knows the fd is still the watchdog's skips it) and the Trajectory its runs make
    of the call's result (5th percentile of ``calls``; None where this tree lacks the
    parts)."""
    try:
        import _signal

        from jetnh.numeric import interrupt
        from jetnh.numeric.trajectory import Trajectory
        own = interrupt._WATCHDOG.own
        confirm = getattr(_signal.set_wakeup_fd, "__wrapped__", _signal.set_wakeup_fd)
        known = hasattr(interrupt, "_KNOWN")
        lean = getattr(Trajectory, "_of_loop", None)
        got = plan.entry(*args)

        def parts():
            np.zeros(1, np.int64)
            if not known:
                confirm(own, warn_on_full_buffer=False)
            if lean is not None:
                return lean(short, got, short.p, "dop853", "", 0.0, plan.kern, None)
            return Trajectory._finished(short, (got[1], got[2], got[3]), short.p, "dop853",
                                        "", (got[4], 0.0, {}), plan.kern, None)
        parts()
    except (AttributeError, ImportError, TypeError, ValueError):
        return None
    times = []
    for _ in range(calls):
        tic = time.perf_counter()
        parts()
        times.append(time.perf_counter() - tic)
    return float(np.percentile(times, 5))


def floors(scene, runs, costs, reference_uncertainty, reps) -> dict:
    """Per target error (those the reference resolves): the floor of jetnh's run
    (module docstring), the compiled loop of jetnh's fastest run at that error called
    directly (its entry, as ``floor_costs`` calls it: what the run costs without its
    Python side), jetnh's time and the fastest scipy method's, and the ratios."""
    out = {}
    for t in TARGETS:
        if reference_uncertainty > 0.1 * t:
            continue
        ours = [r for r in runs if r["method"] in (f"jetnh {m}" for m in JETNH_ADAPTIVE)
                and r["error"] is not None and r["error"] <= t and r.get("nfev")]
        theirs = [r for r in runs if r["method"] in (f"scipy {m}" for m in SCIPY)
                  and r["error"] is not None and r["error"] <= t]
        if not ours or not theirs:
            continue
        nfev = min(r["nfev"] for r in ours)
        run = min(ours, key=lambda r: r["seconds"])
        plan = scene._quick_plan(run["method"].split()[-1], "final", run["rtol"],
                                 1e-3 * run["rtol"])
        halt = np.zeros(1, dtype=np.int64)

        def loop():
            return plan.entry(*plan.prefix, plan.t0, plan.t1, scene.y0.copy(), scene.p,
                              *plan.suffix, halt)
        loop_s, res = best(loop, 3 * reps)  # as many calls as jetnh's run: reps blocks of 3
        fastest = min(theirs, key=lambda r: r["seconds"])
        floor = nfev * costs["per_evaluation_s"] + costs["fixed_s"]
        run_floor = floor + costs["python_s"] if costs.get("python_s") else None
        out[str(t)] = dict(nfev=nfev, floor_s=floor, loop_s=loop_s,
                           run_floor_s=run_floor,
                           scipy_over_run_floor=(fastest["seconds"] / run_floor
                                                 if run_floor else None),
                           loop_nfev=int(res[4][2]), jetnh_s=run["seconds"],
                           jetnh_nfev=run["nfev"], scipy_s=fastest["seconds"],
                           scipy_method=fastest["method"],
                           jetnh_over_floor=run["seconds"] / floor,
                           scipy_over_jetnh=fastest["seconds"] / run["seconds"],
                           scipy_over_loop=fastest["seconds"] / loop_s,
                           scipy_over_floor=fastest["seconds"] / floor)
    return out


def panel(case: Case, tolerances, steps, reps, budget, give_up, drive=None, calls=0):
    """Every method's runs on one system x principle; with ``drive`` (``rhs_driver``) and
    ``calls``, its floor too (``floor_costs``, ``floors``)."""
    scene = scene_of(case).compile()
    f = researcher_rhs(scene)
    T = case.t_end
    ref, ref_info = reference(case, scene, f)
    print(f"\n{case.label}  T = {T}  reference: {ref_info['kind']} "
          f"(uncertainty {ref_info['uncertainty']:.1e})", flush=True)
    runs = []

    def jetnh(method, **kw):
        return lambda: scene.run(method=method, save="final", **kw)

    def scipy_(method, rtol):
        def go():
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    return solve_ivp(f, (0.0, T), scene.y0, method=method, rtol=rtol,
                                     atol=1e-3 * rtol, t_eval=[T])
                except (ArithmeticError, ValueError) as exc:   # e.g. sqrt of a negative
                    return exc
        return go

    def outcome(res):
        """(final state or None, rhs evaluations, note)."""
        if isinstance(res, Exception):
            return None, None, f"the lambdified rhs raised {type(res).__name__}: {res}"
        if hasattr(res, "diagnostics"):
            ok = res.success and abs(res.t[-1] - T) <= 1e-12 * max(1.0, abs(T))
            return (res.y[-1] if ok else None), res.diagnostics.rhs_evaluations, \
                ("" if ok else res.stop_reason[:120])
        ok = res.status == 0
        return (res.y[:, -1] if ok else None), int(res.nfev), ("" if ok else res.message)

    fixed = ["rk4", "dla" if case.principle == "chetaev" else "dvi"]
    for m in JETNH_ADAPTIVE + ("scipy-DOP853",) + tuple(fixed):     # compile, load
        try:
            scene.run(method=m, save="final", n_steps=1000 if m in fixed else None)
        except JetnhError:
            pass
    slow = set()
    for rtol in tolerances:
        kw = dict(rtol=rtol, atol=1e-3 * rtol)
        named = {f"jetnh {m}": jetnh(m, **kw) for m in JETNH_ADAPTIVE}
        named["scipy DOP853 (jetnh rhs)"] = jetnh("scipy-DOP853", singular="ignore", **kw)
        named.update({f"scipy {m}": scipy_(m, rtol) for m in SCIPY})
        named = {k: v for k, v in named.items() if k not in slow}
        for (name, _), (t, cold, res) in zip(named.items(), best_of_blocks(
                list(named.values()), reps, budget)):
            y, nfev, note = outcome(res)
            e = error(y, ref) if y is not None else None
            runs.append(dict(method=name, rtol=rtol, seconds=t, seconds_cold=cold, error=e,
                             nfev=nfev,
                             achieved_over_requested=e / rtol if e is not None else None,
                             **({"failed": note} if note else {})))
            if t > give_up:
                slow.add(name)
        print(f"  rtol {rtol:.0e}: " + "  ".join(
            f"{r['method'].replace('scipy ', 's:').replace('jetnh ', 'j:')} "
            f"{r['seconds'] * 1e3:.3g}ms/{r['error'] or float('nan'):.0e}"
            for r in runs if r["rtol"] == rtol), flush=True)
    for method in fixed:
        last = math.inf
        for n in steps:
            try:
                t, cold, res = best_of_blocks([jetnh(method, n_steps=n)], reps, budget)[0]
            except JetnhError as exc:                  # e.g. Newton does not converge
                runs.append(dict(method=f"jetnh {method}", n_steps=n, seconds=None,
                                 error=None, failed=str(exc)[:120]))
                continue
            y, nfev, note = outcome(res)
            e = error(y, ref) if y is not None else None
            runs.append(dict(method=f"jetnh {method}", n_steps=n, seconds=t, seconds_cold=cold,
                             error=e, nfev=nfev, **({"failed": note} if note else {})))
            converged = e is not None and n > steps[2] and (e < 1e-13 or e > 0.5 * last)
            if converged or t > give_up:               # at round-off, or too slow
                break
            last = e if e is not None else math.inf
        print(f"  {method}: " + "  ".join(f"n={r['n_steps']} {r['error'] or float('nan'):.0e}"
                                          for r in runs if r.get("n_steps")
                                          and r["method"] == f"jetnh {method}"), flush=True)
    floor = {}
    if drive is not None:
        costs = floor_costs(scene, drive, reps, calls)
        costs["by_target"] = floors(scene, runs, costs, ref_info["uncertainty"], reps)
        print(f"  floor: {costs['per_evaluation_s'] * 1e9:.3g} ns an evaluation + "
              f"{costs['fixed_s'] * 1e6:.3g} us; scipy / floor " + "  ".join(
                  f"{t}: {f['scipy_over_floor']:.3g}x" for t, f in costs["by_target"].items()),
              flush=True)
        floor = dict(floor=costs)
    return dict(model=case.model, options=case.options, principle=case.principle,
                label=case.label, t_end=T, states=list(scene.state_names),
                initial=[float(v) for v in scene.y0], reference=ref_info, runs=runs,
                time_to_error=time_to_error(runs),
                time_to_error_cold=time_to_error(runs, "seconds_cold"),
                orders={f"jetnh {m}": observed_order(runs, f"jetnh {m}",
                                                     ref_info["uncertainty"]) for m in fixed},
                **floor)


# ---------------------------------------------------------------------- summaries
def time_to_error(runs, key="seconds") -> dict:
    """method -> {target: seconds (``key``: warm ``seconds`` or ``seconds_cold``, see
    ``_common.best_of_blocks``) of the cheapest run with error <= target, or None}."""
    out = {}
    for r in runs:
        d = out.setdefault(r["method"], {str(t): None for t in TARGETS})
        for t in TARGETS:
            if r["error"] is not None and r["error"] <= t and r.get(key) is not None:
                k = str(t)
                d[k] = r[key] if d[k] is None else min(d[k], r[key])
    return out


def observed_order(runs, method, floor):
    """-slope of log(error) against log(n_steps) where the error is resolved and small
    (between 1e3 times the reference's uncertainty and 1e-2)."""
    pts = [(r["n_steps"], r["error"]) for r in runs if r["method"] == method
           and r["error"] is not None and 1e3 * floor < r["error"] < 1e-2]
    if len(pts) < 2:
        return None
    n, e = np.log(np.array(pts)).T
    return float(-np.polyfit(n, e, 1)[0])


def summarize(panels) -> dict:
    """Over the panels: time ratios to jetnh's fastest adaptive method at equal error
    (panels whose reference cannot resolve the target left out), the fastest scipy
    method, achieved / requested, and how often jetnh's error equals scipy's."""
    methods = sorted({r["method"] for p in panels for r in p["runs"]})
    ratios = {m: {str(t): [] for t in TARGETS} for m in methods}
    best_scipy = {str(t): [] for t in TARGETS}
    best_scipy_cold = {str(t): [] for t in TARGETS}
    fastest = {str(t): {} for t in TARGETS}
    for p in panels:
        tte = p["time_to_error"]
        cold = p.get("time_to_error_cold")
        for t in map(str, TARGETS):
            base = [tte[m][t] for m in ("jetnh dop853", "jetnh dopri5") if tte[m][t]]
            if not base or p["reference"]["uncertainty"] > 0.1 * float(t):
                continue
            for m in methods:
                if tte.get(m, {}).get(t):
                    ratios[m][t].append(tte[m][t] / min(base))
            sc = {m: tte[f"scipy {m}"][t] for m in SCIPY if tte[f"scipy {m}"][t]}
            if sc:
                m = min(sc, key=sc.get)
                best_scipy[t].append(sc[m] / min(base))
                fastest[t][m] = fastest[t].get(m, 0) + 1
            if cold:
                ours = [cold[m][t] for m in ("jetnh dop853", "jetnh dopri5") if cold[m][t]]
                theirs = [cold[f"scipy {m}"][t] for m in SCIPY if cold[f"scipy {m}"][t]]
                if ours and theirs:
                    best_scipy_cold[t].append(min(theirs) / min(ours))

    def stats(v):
        return (dict(n=len(v), geomean=float(np.exp(np.mean(np.log(v)))), min=min(v),
                     max=max(v)) if v else None)
    achieved = {}
    for m in methods:
        v = [r["achieved_over_requested"] for p in panels for r in p["runs"]
             if r["method"] == m and r.get("achieved_over_requested") is not None
             and r["error"] > 10 * p["reference"]["uncertainty"]]
        if v:
            achieved[m] = dict(n=len(v), median=float(np.median(v)), min=min(v), max=max(v),
                               over_1=int(sum(x > 1 for x in v)),
                               over_10=int(sum(x > 10 for x in v)))
    same = {}
    for ours, theirs in (("jetnh dop853", "scipy DOP853"), ("jetnh dopri5", "scipy RK45")):
        agree = total = 0
        for p in panels:
            floor = 10 * p["reference"]["uncertainty"]
            errs = {(r["method"], r.get("rtol")): r["error"] for r in p["runs"]}
            for (m, rtol), e in errs.items():
                f = errs.get((theirs, rtol))
                if m == ours and e is not None and f is not None:
                    total += 1
                    agree += abs(e - f) <= 0.01 * max(e, f) or max(e, f) < floor
        same[f"{ours} ~ {theirs}"] = dict(agree=int(agree), runs=total)
    floor = {}
    for t in map(str, TARGETS):
        by = {p["label"]: p["floor"]["by_target"][t] for p in panels
              if t in p.get("floor", {}).get("by_target", {})}
        if by:
            floor[t] = dict(stats([f["scipy_over_floor"] for f in by.values()]),
                            jetnh_over_floor=stats([f["jetnh_over_floor"] for f in by.values()]),
                            scipy_over_loop=stats([f["scipy_over_loop"] for f in by.values()]),
                            below_goal=[k for k, f in by.items()
                                        if f["scipy_over_floor"] < GOAL],
                            run_floor=stats([f["scipy_over_run_floor"] for f in by.values()
                                             if f.get("scipy_over_run_floor")]),
                            run_floor_below_goal=[k for k, f in by.items()
                                                  if f.get("scipy_over_run_floor")
                                                  and f["scipy_over_run_floor"] < GOAL],
                            loop_below_goal=[k for k, f in by.items()
                                             if f["scipy_over_loop"] < GOAL])
    return {"targets": list(TARGETS),
            "time_ratio_to_jetnh": {m: {t: stats(v) for t, v in d.items()}
                                    for m, d in ratios.items()},
            "best_scipy_over_jetnh": {t: stats(v) for t, v in best_scipy.items()},
            "best_scipy_over_jetnh_cold": {t: stats(v) for t, v in best_scipy_cold.items()},
            "fastest_scipy_method": fastest,
            "achieved_over_requested": achieved,
            "same_error_as_scipy": same,
            "goal": GOAL,
            "fastest_scipy_over_floor": floor,
            "note": "ratios: time a method needs to reach the target error over the time "
                    "of jetnh's fastest adaptive method (dop853 or dopri5) for the same "
                    "target, per panel (panels whose reference cannot resolve the target "
                    "are left out); achieved/requested: error / rtol over runs whose error "
                    "is resolved (> 10x the reference's uncertainty); same error as scipy: "
                    "runs at equal rtol whose errors agree within 1 % (the same steps); "
                    "the floor: rhs evaluations x the bare cost of one + the fixed cost of "
                    "the bare compiled call (module docstring), fastest_scipy_over_floor "
                    "the best ratio an implementation with jetnh's evaluations could reach "
                    "and the panels where even that is below the goal; scipy_over_loop: "
                    "the ratio of jetnh's compiled loop called directly (no Python side)"}


# ---------------------------------------------------------------------- figures
STYLE = {"jetnh dop853": ("C0", "o", "-"), "jetnh dopri5": ("C1", "s", "-"),
         "jetnh rk4": ("C2", "^", "--"), "jetnh dla": ("C8", "v", "--"),
         "jetnh dvi": ("C8", "v", "--"), "scipy DOP853 (jetnh rhs)": ("C9", "x", ":"),
         "scipy RK45": ("C3", "D", "-."), "scipy DOP853": ("C4", "P", "-."),
         "scipy LSODA": ("C5", "*", "-."), "scipy Radau": ("C7", "h", "-.")}


def plot(panels, out_stem):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    for principle in ("chetaev", "vakonomic"):
        ps = [p for p in panels if p["principle"] == principle]
        if not ps:
            continue
        cols = min(3, len(ps))
        rows = math.ceil(len(ps) / cols)
        fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 4.2 * rows), squeeze=False)
        for ax, p in zip(axes.flat, ps):
            for m, (c, mk, ls) in STYLE.items():
                pts = sorted((r["error"], r["seconds"]) for r in p["runs"]
                             if r["method"] == m and r["error"] and r["seconds"])
                if pts:
                    e, s = zip(*pts)
                    ax.loglog(e, s, color=c, marker=mk, ls=ls, ms=4, lw=1.2, label=m)
            u = p["reference"]["uncertainty"]
            ax.axvspan(1e-17, max(u, 1e-16), color="0.85", zorder=0)
            ax.set_xlim(1e-16, 1)
            ax.set_title(f"{p['label']}  (T = {p['t_end']:g}, "
                         f"{'exact' if p['reference']['kind'] == 'exact' else 'ref.'})",
                         fontsize=9)
            ax.set_xlabel("error at T")
            ax.set_ylabel("wall time [s]")
            ax.grid(True, which="major", alpha=0.3)
        for ax in list(axes.flat)[len(ps):]:
            ax.axis("off")
        handles, labels = axes.flat[0].get_legend_handles_labels()
        for ax in list(axes.flat)[1:len(ps)]:
            for h, lab in zip(*ax.get_legend_handles_labels()):
                if lab not in labels:
                    handles.append(h)
                    labels.append(lab)
        fig.legend(handles, labels, loc="lower center", ncol=5, fontsize=8, frameon=False)
        fig.suptitle(f"Work-precision, {principle} dynamics (grey: below the reference's "
                     "resolution)", fontsize=11)
        fig.tight_layout(rect=(0, 0.07, 1, 0.97))
        path = out_stem.with_name(f"{out_stem.name}_{principle}.png")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)

    adaptive = [m for m in STYLE if m.startswith("scipy") or m in ("jetnh dop853",
                                                                   "jetnh dopri5")]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), sharey=True)
    for ax, principle in zip(axes, ("chetaev", "vakonomic")):
        for m in adaptive:
            c, mk, _ = STYLE[m]
            pts = [(r["rtol"], r["achieved_over_requested"]) for p in panels
                   if p["principle"] == principle for r in p["runs"]
                   if r["method"] == m and r.get("achieved_over_requested")
                   and r["error"] > 10 * p["reference"]["uncertainty"]]
            if pts:
                x, y = zip(*pts)
                jitter = 1.0 + 0.08 * (adaptive.index(m) - len(adaptive) / 2)
                ax.loglog(np.array(x) * jitter, y, ls="none", marker=mk, color=c, ms=4,
                          label=m)
        ax.axhline(1.0, color="k", lw=0.8)
        ax.set_xlabel("requested rtol (atol = 1e-3 rtol)")
        ax.set_title(f"{principle}: achieved error / requested rtol, every system", fontsize=9)
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("achieved / requested")
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    path = out_stem.with_name(f"{out_stem.name}_tolerance.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    paths.append(path)
    return [p.name for p in paths]


def main(argv=None):
    ap = parser(__doc__, "workprecision")
    ap.add_argument("--panels", nargs="+", metavar="LABEL",
                    help="only these panels (of every system, also with --quick), by "
                         "label (e.g. 'knife_edge / chetaev'), or by system or principle")
    args = ap.parse_args(argv)
    if args.quick:
        tolerances, steps, reps, budget, give_up = [1e-3, 1e-6, 1e-9], [10, 100, 1000], 2, 0.2, 0.5
    else:
        tolerances = [10.0 ** -k for k in range(3, 13)]
        steps = [int(round(10 ** (k / 2))) for k in range(2, 11)]
        reps, budget, give_up = 5, 1.0, 2.0
    calls = 200 if args.quick else 2000
    args.out.parent.mkdir(parents=True, exist_ok=True)
    drive = rhs_driver()
    chosen = [c for c in cases(args.quick and not args.panels) if not args.panels
              or {c.label, c.model, c.principle} & set(args.panels)]
    panels = [panel(c, tolerances, steps, reps, budget, give_up, drive, calls)
              for c in chosen]
    figures = plot(panels, args.out.with_suffix(""))
    summary = summarize(panels)
    for t, s in summary["best_scipy_over_jetnh"].items():
        if s:
            print(f"best scipy / jetnh at error {t}: geomean {s['geomean']:.1f}x "
                  f"(min {s['min']:.1f}x, max {s['max']:.1f}x, {s['n']} panels)")
    for t, s in summary["fastest_scipy_over_floor"].items():
        print(f"best scipy / floor at error {t}: geomean {s['geomean']:.1f}x (min "
              f"{s['min']:.1f}x, max {s['max']:.1f}x); below {GOAL:g}x: "
              f"{', '.join(s['below_goal']) or 'none'}; best scipy / compiled loop "
              f"{s['scipy_over_loop']['geomean']:.1f}x (min {s['scipy_over_loop']['min']:.1f}x)"
              f", below {GOAL:g}x: {', '.join(s['loop_below_goal']) or 'none'}")
    write("workprecision", dict(
        method=dict(tolerances=tolerances, atol="1e-3 rtol", fixed_steps=steps,
                    repetitions=reps, budget_s=budget, give_up_s=give_up,
                    error="max_i |y_i(T) - y_ref,i(T)| / max(|y_ref,i(T)|, 1) over every state",
                    timing="best of interleaved rounds of 3 calls in a row (warm; cold: best first call of a round); scene.run(save='final') vs "
                           "solve_ivp(t_eval=[T]) on sympy.lambdify(cse=True, modules='math')",
                    baseline="jetnh's fastest adaptive method (dop853 or dopri5) at equal error",
                    floor="n x e + c: n the fewest rhs evaluations of a jetnh adaptive run "
                          "at the error, e one evaluation in a bare compiled loop (best of "
                          "batches of 20000), c the bare call of the compiled dop853 loop "
                          f"on a one-step span (5th percentile of {calls} calls) less its "
                          "own evaluations"),
        summary=summary, figures=figures, panels=panels), args.out, args.quick)


if __name__ == "__main__":
    main()
