"""Where jetnh's numerical speed comes from: the cost of one right-hand-side evaluation,
and the fixed and per-evaluation cost of one run, against the researcher's route
(``sympy.lambdify`` + scipy ``solve_ivp``).

    .venv/bin/python benchmarks/numeric_speed.py [--quick] [--out PATH]

(default output: benchmarks/results/numeric_speed.json)

1. One rhs call: jetnh's generated numba kernel, a hand-written numba function of the
   same expressions (vertical rolling disk only), and the lambdified Python function
   (``modules="math"``, cse) that ``workprecision.py`` gives scipy -- on the rolling disk
   (Chetaev) and the car with three trailers (vakonomic, 12 states).
2. One run: ``scene.run(dop853, save="final")`` against ``solve_ivp(DOP853)`` on the
   lambdified rhs and on jetnh's compiled rhs, over spans from one step to ~10^4
   evaluations (rolling disk, Chetaev and vakonomic, T = 1e-6, 10, 100): the fixed cost
   of a call and the cost per rhs evaluation.
3. The loop's own cost per evaluation: ``scene.run(method="rk4", n_steps=N,
   save="final", singular="ignore")`` against a bare numba loop of the classical RK4
   step (the step of the hand-written rk4 loop that preceded the shared one: four rhs
   calls, the stage sums, a finiteness check and the halt flag) on the same compiled rhs,
   over runs long enough (N = 10^5 steps) that the fixed cost of a call vanishes.

Wall times are best of several repetitions (``_common.best``); ratios are within this run.
"""

import warnings

import numba
import numpy as np
from scipy.integrate import solve_ivp

from _common import best, best_of, parser, rhs_driver, write
from workprecision import Case, researcher_rhs, scene_of

CALL_CASES = (Case("rolling_disk", "chetaev", 10.0),
              Case("n_trailer", "vakonomic", 0.5, options={"N": 3}, multipliers=0.01))
RUN_CASES = (Case("rolling_disk", "chetaev", 10.0), Case("rolling_disk", "vakonomic", 10.0))


@numba.njit("void(float64, float64[::1], float64[::1], float64[::1])", error_model="numpy")
def disk_by_hand(t, y, p, out):
    """The rolling disk's Chetaev rhs (R = 1: catalogue defaults), written by hand."""
    c, s = np.cos(y[3]), np.sin(y[3])
    out[0] = y[4] * c
    out[1] = y[4] * s
    out[2] = y[4]
    out[3] = y[5]
    out[4] = 0.0
    out[5] = 0.0


def rhs_call(case, n_calls, reps):
    """ns per call of each implementation of the same rhs."""
    scene = scene_of(case).compile()
    f = researcher_rhs(scene)
    y, p = scene.y0.copy(), scene.p
    from jetnh.numeric.methods._common import RHS_SIGNATURE, FunctionAddress

    drive = rhs_driver()
    fns = {"generated": scene.kernels.rhs_fp}
    if case.model == "rolling_disk":
        out = np.empty(6)
        disk_by_hand(0.0, y, p, out)
        ref = np.empty(6)
        scene.kernels.rhs(0.0, y, p, ref)
        assert np.allclose(out, ref), "the hand-written disk rhs must be the same function"
        fns["hand-written numba"] = FunctionAddress(
            numba.cfunc(RHS_SIGNATURE, error_model="numpy")(disk_by_hand.py_func))
    res = {}
    for label, fn in fns.items():
        drive(fn, y.copy(), p, 10)
        t, _ = best(lambda: drive(fn, y.copy(), p, n_calls), reps)
        res[label] = t / n_calls * 1e9
    n_py = max(1000, n_calls // 500)
    t, _ = best(lambda: [f(0.0, y) for _ in range(n_py)], reps)
    res["lambdify (math) + numpy array"] = t / n_py * 1e9
    ratios = {k: v / res["generated"] for k, v in res.items()}
    print(f"rhs call, {case.label}: " + ", ".join(f"{k} {v:.0f} ns ({ratios[k]:.2f}x)"
                                                  for k, v in res.items()))
    return dict(problem=case.label, states=len(scene.state_names), ns_per_call=res,
                ratio_to_generated=ratios)


def run_cost(case, spans, reps):
    """Call time and rhs evaluations per span; fixed cost and cost per evaluation."""
    scene = scene_of(case).compile()
    f = researcher_rhs(scene)
    rows = []
    for T in spans:
        kw = dict(rtol=1e-9, atol=1e-12)

        def scipy_(fun):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return solve_ivp(fun, (0.0, T), scene.y0, method="DOP853", t_eval=[T], **kw)
        runs = {"jetnh dop853": lambda: scene.run(save="final", t_span=(0.0, T), **kw),
                "scipy DOP853 (jetnh rhs)": lambda: scene.run(
                    method="scipy-DOP853", singular="ignore", t_span=(0.0, T), **kw),
                "scipy DOP853 (lambdify)": lambda: scipy_(f)}
        row = dict(t_end=T)
        for name, g in runs.items():
            g()
            t, r = best(g, reps, budget=2.0)
            nfev = r.diagnostics.rhs_evaluations if hasattr(r, "diagnostics") else int(r.nfev)
            row[name] = dict(seconds=t, nfev=nfev)
        rows.append(row)
        print(f"run {case.label} T = {T:g}: " + ", ".join(
            f"{k} {v['seconds'] * 1e6:.0f} us ({v['nfev']} evals)"
            for k, v in row.items() if k != "t_end"))
    summary = {}
    for name in rows[0]:
        if name == "t_end":
            continue
        first, last = rows[0][name], rows[-1][name]
        per = (last["seconds"] - first["seconds"]) / max(last["nfev"] - first["nfev"], 1)
        summary[name] = dict(fixed_us=first["seconds"] * 1e6, per_evaluation_ns=per * 1e9)
    base = summary["jetnh dop853"]
    for name, s in summary.items():
        s["fixed_ratio"] = s["fixed_us"] / base["fixed_us"]
        s["per_evaluation_ratio"] = s["per_evaluation_ns"] / base["per_evaluation_ns"]
    return dict(problem=case.label, rtol=1e-9, rows=rows, summary=summary)


def bare_rk4():
    """``bare(rhs, t0, t_end, y, p, n_steps, halt)``: the classical RK4 step, as the
    hand-written rk4 loop took it, and nothing else (its final state in ``y``)."""
    from jetnh.numeric.methods._common import RHS, all_finite, entry_point, f8, i8

    @numba.njit((RHS, f8, f8, f8[::1], f8[::1], i8, i8[::1]), error_model="numpy")
    def bare(rhs, t0, t_end, y, p, n_steps, halt):
        n = y.shape[0]
        h = (t_end - t0) / n_steps
        k1, k2, k3, k4 = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        ytmp, y_new = np.empty(n), np.empty(n)
        t = t0
        for step in range(n_steps):
            if halt[0] != 0:
                return -1
            rhs(t, y, p, k1)
            for i in range(n):
                ytmp[i] = y[i] + 0.5 * h * k1[i]
            rhs(t + 0.5 * h, ytmp, p, k2)
            for i in range(n):
                ytmp[i] = y[i] + 0.5 * h * k2[i]
            rhs(t + 0.5 * h, ytmp, p, k3)
            for i in range(n):
                ytmp[i] = y[i] + h * k3[i]
            rhs(t + h, ytmp, p, k4)
            for i in range(n):
                y_new[i] = y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            if not all_finite(y_new):
                return -1
            for i in range(n):
                y[i] = y_new[i]
            t = t0 + (step + 1) * h
        return 0
    return entry_point(bare)


def rk4_loop_cost(case, n_steps, reps):
    """ns per rhs evaluation of jetnh's rk4 run and of the bare loop (``bare_rk4``) on
    the same compiled rhs, interleaved; the final states must agree bit for bit."""
    scene = scene_of(case).compile()
    bare = bare_rk4()
    rhs, p, halt = scene.kernels.rhs_fp, scene.p, np.zeros(1, dtype=np.int64)
    T = 1.0

    def jet():
        return scene.run(method="rk4", n_steps=n_steps, save="final", singular="ignore",
                         t_span=(0.0, T))

    def by_hand():
        y = scene.y0.copy()
        bare(rhs, 0.0, T, y, p, n_steps, halt)
        return y
    (tj, rj), (tb, yb) = best_of([jet, by_hand], reps)
    same = bool(np.array_equal(rj.y[-1], yb))
    evals = 4 * n_steps
    out = dict(problem=case.label, n_steps=n_steps, jetnh_ns=tj / evals * 1e9,
               bare_ns=tb / evals * 1e9, ratio=tj / tb, bit_for_bit=same)
    print(f"rk4 loop, {case.label}: jetnh {out['jetnh_ns']:.1f} ns/eval, bare loop "
          f"{out['bare_ns']:.1f} ns/eval, ratio {out['ratio']:.3f}, same result: {same}")
    return out


def main(argv=None):
    args = parser(__doc__, "numeric_speed").parse_args(argv)
    n_calls, reps = (200_000, 3) if args.quick else (2_000_000, 7)
    spans = (1e-6, 10.0) if args.quick else (1e-6, 10.0, 100.0)
    write("numeric_speed", dict(
        rhs_call=[rhs_call(c, n_calls, reps) for c in CALL_CASES],
        run_cost=[run_cost(c, spans, reps) for c in RUN_CASES],
        rk4_loop=[rk4_loop_cost(c, 10_000 if args.quick else 100_000, reps)
                  for c in CALL_CASES]),
        args.out, args.quick)


if __name__ == "__main__":
    main()
