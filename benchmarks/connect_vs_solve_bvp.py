"""Two-point problems: jetnh's connect (shooting with sensitivities) against solve_bvp.

    .venv/bin/python benchmarks/connect_vs_solve_bvp.py [--quick] [--out PATH]

(default output: benchmarks/results/connect_vs_solve_bvp.json; ``--quick``: the first two
cases at every tolerance, fewer repetitions, two sensitivity rows -- under a minute)

1. ``jn.connect`` against ``scipy.integrate.solve_bvp`` (collocation) on the same
   equations: solve_bvp calls the scene's compiled right-hand side over the whole mesh in
   one call (``kernels.calls.Rows``: no Python loop per mesh point, the fastest form of
   the same equations it can be given), with its default finite-difference Jacobian and
   with jetnh's compiled Jacobian (``kernels.jacobian_kernels``, one call per mesh
   point), from a straight-line guess (velocities of the named coordinates, 0.5 for the
   others, zero multipliers) on 11 nodes, at most 20000 nodes, at tol 1e-3 .. 1e-10 (one
   run per decade).  connect runs at rtol 1e-6 .. 1e-10 with its endpoint tolerance
   ``tol`` = rtol (the Newton iteration stops where the integration's accuracy is),
   timed alone ("connect": the shooting to the answer) and with its verdicts ("connect +
   verdicts": cost, conjugate times, Gramian, computed on first access).  The error of
   every route is measured alike: the largest deviation of the initial state found
   (velocities, multipliers) from a reference (connect at rtol 1e-13, which solve_bvp
   at tol 1e-9 matches to ~1e-12).  "Speed-up at equal error": the time of the fastest
   solve_bvp run at least as accurate as connect's, divided by connect's (">" when no
   solve_bvp run was as accurate: its slowest time).
2. What sensitivities cost: one run to t1 (save="final", dop853, rtol 1e-10) without
   them, with them under the error control and with them outside it.  A run with
   sensitivities keeps its split, so the plain run is timed with split="fixed" (the
   same equations in the same chart); the default plain run, which may go on in
   another chart (``numeric.atlas``), is listed apart ("plain_switch_ms").

Wall times are the best of several interleaved repetitions after one call of every route
(kernels and compiled loops built), two per route and round (``cold_and_warm``): "warm",
a call right after one of the same route (a caller's repeated calls), and "cold", a call
right after the other routes' (its caches taken by them: connect's first call after the
solve_bvp runs pays ~0.3 ms of that); speed-ups are given for both, solve_bvp's times
taken alike, and ratios are within this run.
"""

import warnings

import numpy as np
from scipy.integrate import solve_bvp

import math
import time

from _common import best_of, parser, write

import jetnh as jn
from jetnh.models import get
from jetnh.numeric.connect.collocation import problem
from jetnh.numeric.kernels import calls

ZERO_DISK = {"x": 0.0, "y": 0.0, "phi": 0.0, "psi": 0.0}
CASES = (
    ("heisenberg", "vakonomic", {"x": 0.0, "y": 0.0, "z": 0.0},
     {"x": 1.0, "y": 0.5, "z": 0.2}, 1.0),
    ("rolling_disk", "chetaev", ZERO_DISK, {"x": 0.5, "y": 0.3}, 1.0),
    ("rolling_disk", "vakonomic", ZERO_DISK, {"x": 0.0, "y": 0.3, "phi": 0.0, "psi": 0.0},
     1.0),
)
CONNECT_RTOL = (1e-6, 1e-8, 1e-10)
#: solve_bvp's mesh limit and the seconds each route may spend per tolerance
MAX_NODES, BUDGET = 20_000, 20.0
BVP_TOL = tuple(10.0 ** -k for k in range(3, 11))


def mesh_rhs(scene):
    """solve_bvp's ``fun``: the compiled right-hand side at every mesh point, one call."""
    kern, p, n = scene.kernels, scene.p, len(scene.state_names)
    rows = calls.Rows(kern.rhs_fp, (n, len(p), kern.layout.n_rhs))

    def fun(t, Y):
        out = np.empty((Y.shape[1], n))
        rows(np.ascontiguousarray(t, dtype=float), np.ascontiguousarray(Y.T), p, out)
        return out.T
    return fun


def cold_and_warm(fs, reps, budget=math.inf):
    """For each function of ``fs``: the best wall time over ``reps`` interleaved rounds
    of a call right after the other functions' ("cold") and of a call right after its
    own ("warm"), and its last result; a function is not called again once its calls
    have taken ``budget`` seconds in all.  Returns ``[(warm, cold, result), ...]``."""
    warm, cold = [math.inf] * len(fs), [math.inf] * len(fs)
    spent, outs = [0.0] * len(fs), [None] * len(fs)
    for _ in range(reps):
        for i, f in enumerate(fs):
            if spent[i] >= budget:
                continue
            for best in (cold, warm):
                tic = time.perf_counter()
                outs[i] = f()
                dt = time.perf_counter() - tic
                best[i] = min(best[i], dt)
                spent[i] += dt
    return list(zip(warm, cold, outs))


def connect_case(model, principle, start, end, T, reps):
    system = get(model)
    ref = jn.connect(system, principle, start, end, (0.0, T), rtol=1e-13, atol=1e-14,
                     tol=1e-11)
    scene = ref.trajectory.scene
    names = scene.state_names
    want = np.array([ref.initial[k] for k in names])
    # every route of the case in one interleaved timing (``cold_and_warm``): a change of
    # the machine's load hits them alike
    routes = []
    for rtol in CONNECT_RTOL:
        def solve(rtol=rtol):
            return jn.connect(system, principle, start, end, (0.0, T), rtol=rtol,
                              atol=rtol * 1e-2, tol=rtol)

        def judged(solve=solve):
            c = solve()
            c.cost, c.normal, c.conjugate_times
            return c

        routes += [(("connect", rtol), solve), (("connect + verdicts", rtol), judged)]
    for jacobian in (False, True):
        _, fjac, bc, t, Y = problem(scene, start, end, T, jacobian)
        fun = mesh_rhs(scene)
        for tol in BVP_TOL:
            def go(fun=fun, fjac=fjac, bc=bc, t=t, Y=Y, tol=tol):
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    return solve_bvp(fun, bc, t, Y, fun_jac=fjac, tol=tol,
                                     max_nodes=MAX_NODES)
            routes.append((("solve_bvp" + (" + jetnh jac" if jacobian else ""), tol), go))
    for _, f in routes:          # compiled loops and kernels of every route built first
        f()
    rows = []
    for ((route, tol), _), (sec, cold, out) in zip(routes, cold_and_warm(
            [f for _, f in routes], reps, BUDGET)):
        row = dict(model=model, principle=principle, route=route, tol=tol, seconds=sec,
                   seconds_cold=cold)
        if route.startswith("connect"):
            err = float(np.max(np.abs(np.array([out.initial[k] for k in names]) - want)))
            row.update(error=err, iterations=out.iterations)
        else:
            err = float(np.max(np.abs(out.y[:, 0] - want))) if out.status == 0 else None
            row.update(error=err, status=int(out.status), nodes=int(out.x.size))
        rows.append(row)
    return ref, rows


def speedups(rows):
    out = []
    for r in (r for r in rows if r["route"].startswith("connect")):
        for route in ("solve_bvp", "solve_bvp + jetnh jac"):
            other = [o for o in rows if o["route"] == route and o["model"] == r["model"]
                     and o["principle"] == r["principle"] and o["error"] is not None]
            good = [o for o in other if o["error"] <= max(r["error"], 1e-13)]
            texts = []
            for key in ("seconds", "seconds_cold"):
                if good:
                    texts.append(f"{min(o[key] for o in good) / r[key]:.3g}")
                elif other:
                    texts.append(f">{max(o[key] for o in other) / r[key]:.3g}")
                else:
                    texts.append("solve_bvp failed")
            out.append([r["model"], r["principle"], r["route"], f"{r['tol']:.0e}",
                        f"{r['error']:.2e}", f"{r['seconds'] * 1e3:.3g}",
                        f"{r['seconds_cold'] * 1e3:.3g}", route, *texts])
    return out


def sensitivity_cost(model, principle, initial, T, reps):
    sc = jn.Scene(get(model), principle, initial=initial, t_span=(0.0, T))
    kw = dict(rtol=1e-10, atol=1e-12, save="final")
    # the run with sensitivities keeps its split: the plain run in the same chart
    fs = [lambda: sc.run(split="fixed", **kw), lambda: sc.run(sensitivities=True, **kw),
          lambda: sc.run(sensitivities=True, sensitivity_error=False, **kw),
          lambda: sc.run(**kw)]
    for f in fs:
        assert f().status == 0
    plain, ctl, free, switch = best_of(fs, 5 * reps)
    return dict(model=model, principle=principle, n_state=len(sc.state_names),
                plain_ms=plain[0] * 1e3, plain_nfev=plain[1].diagnostics.rhs_evaluations,
                controlled_ms=ctl[0] * 1e3,
                controlled_nfev=ctl[1].diagnostics.rhs_evaluations,
                uncontrolled_ms=free[0] * 1e3,
                uncontrolled_nfev=free[1].diagnostics.rhs_evaluations,
                ratio_controlled=ctl[0] / plain[0], ratio_uncontrolled=free[0] / plain[0],
                plain_switch_ms=switch[0] * 1e3, switches=len(switch[1].switches))


def main():
    args = parser(__doc__, "connect_vs_solve_bvp").parse_args()
    reps = 5 if args.quick else 9
    rows, found = [], []
    for case in CASES[:2] if args.quick else CASES:
        ref, r = connect_case(*case, reps)
        rows += r
        found.append([case[0], case[1], f"{ref.cost:.10g}", f"{ref.residual:.1e}",
                      str(ref.normal), ", ".join(f"{t:.6g}" for t in ref.conjugate_times)
                      or "none", str(ref.iterations)])
    sens = [sensitivity_cost("heisenberg", "vakonomic",
                             {"x": 0.1, "y": 0.2, "z": 0.0, "x_t": 1.0, "y_t": 0.3,
                              "lambda_z": 0.7}, 10.0, reps),
            sensitivity_cost("chaplygin_sleigh", "chetaev",
                             {"x": 0.0, "y": 0.0, "theta": 0.0, "x_t": 0.5,
                              "theta_t": 1.0}, 10.0, reps)]
    if not args.quick:
        sens.append(sensitivity_cost("rolling_disk", "vakonomic",
                                     {**ZERO_DISK, "phi_t": 1.0, "psi_t": 0.7,
                                      "lambda_x": 0.1, "lambda_y": -0.2}, 10.0, reps))
    sp = speedups(rows)
    best_ratio = {}
    for m, p, mine, tol, err, ms, ms_cold, route, text, text_cold in sp:
        if route == "solve_bvp":
            best_ratio.setdefault((m, p, mine), []).append((text, text_cold))
    summary = [f"{m} {p}: {mine} against solve_bvp (its finite-difference Jacobian) at "
               f"equal error: {', '.join(w for w, _ in v)} times faster warm, "
               f"{', '.join(c for _, c in v)} cold (connect rtol = tol "
               f"{', '.join(f'{t:.0e}' for t in CONNECT_RTOL[:len(v)])})"
               for (m, p, mine), v in best_ratio.items()]
    summary += [f"sensitivities on {s['model']} {s['principle']} ({s['n_state']} states): "
                f"{s['ratio_controlled']:.2g}x the plain run under the error control, "
                f"{s['ratio_uncontrolled']:.2g}x outside it" for s in sens]
    write("connect_vs_solve_bvp", {
        "summary": summary,
        "columns": ["model", "principle", "route", "tol", "seconds", "seconds_cold",
                    "error", "iterations", "status", "nodes"],
        "rows": rows,
        "tables": [
            {"title": "Speed-up at equal error", "columns": [
                "model", "principle", "connect", "connect rtol = tol", "connect error",
                "connect ms", "connect ms (cold)", "against", "speed-up",
                "speed-up (cold)"], "rows": sp,
             "note": "the fastest solve_bvp run at least as accurate as connect, over "
                     "connect's time ('>': no solve_bvp run was as accurate); warm: "
                     "each call right after one of the same route, cold: after the "
                     "other routes' calls"},
            {"title": "What connect found (reference runs)", "columns": [
                "model", "principle", "cost", "residual", "normal", "conjugate times",
                "iterations"], "rows": found},
            {"title": "The cost of sensitivities (one run, save='final')", "columns": list(
                sens[0]), "rows": [[f"{v:.3g}" if isinstance(v, float) else v
                                    for v in s.values()] for s in sens]},
        ],
    }, args.out, args.quick)


if __name__ == "__main__":
    main()
