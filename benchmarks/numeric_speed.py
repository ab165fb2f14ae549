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

Wall times are best of several repetitions (``_common.best``); ratios are within this run.
"""

import warnings

import numba
import numpy as np
from scipy.integrate import solve_ivp

from _common import best, parser, write
from workprecision import Case, researcher_rhs, scene_of

CALL_CASES = (Case("rolling_disk", "chetaev", 10.0),
              Case("n_trailer", "vakonomic", 0.5, options={"N": 3}, multipliers=0.01))
RUN_CASES = (Case("rolling_disk", "chetaev", 10.0), Case("rolling_disk", "vakonomic", 10.0))


def rhs_driver():
    """A compiled loop calling an rhs kernel n times (``drive(rhs, y, p, n)``), ``rhs`` a
    C callback by address (``FunctionAddress``), as the integrators call it."""
    from jetnh.numeric.methods._common import RHS, entry_point, f8, i8

    @numba.njit((RHS, f8[::1], f8[::1], i8))
    def drive(rhs, y, p, n):
        out = np.empty(y.shape[0])
        acc = 0.0
        for i in range(n):
            y[0] += 1e-15                     # keep the compiler from hoisting the call
            rhs(0.0, y, p, out)
            acc += out[-1]
        return acc
    return entry_point(drive)


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


def main(argv=None):
    args = parser(__doc__, "numeric_speed").parse_args(argv)
    n_calls, reps = (200_000, 3) if args.quick else (2_000_000, 7)
    spans = (1e-6, 10.0) if args.quick else (1e-6, 10.0, 100.0)
    write("numeric_speed", dict(
        rhs_call=[rhs_call(c, n_calls, reps) for c in CALL_CASES],
        run_cost=[run_cost(c, spans, reps) for c in RUN_CASES]),
        args.out, args.quick)


if __name__ == "__main__":
    main()
