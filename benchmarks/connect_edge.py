"""connect and runs with sensitivities across the edge of a split: the damped sleigh
(``tests/damped_sleigh.py``; y dependent, its split singular at cos th = 0).

    .venv/bin/python benchmarks/connect_edge.py [--quick] [--out PATH]

(default output: benchmarks/results/connect_edge.json).  In one process, the calls
interleaved (``_common.best_of``), each figure the best of its repetitions:

- ``connect``: ``jn.connect`` (warm: its scene and kernels made by a first call) from
  the origin to th = 2.0 in 1 s -- past pi / 2, so its runs cross the split's edge --
  Chetaev (end x, th) and vakonomic (end x, y, th), against scipy's ``least_squares``
  around ``scene.run`` (finite-difference Jacobian, the same rtol and atol) from the same
  straight-line guess: seconds, the end missed, and the initial unknowns' difference;
- ``sensitivities``: one run with sensitivities that crosses the edge (x_t = 0.2,
  th_t = 2.5, rtol 1e-10): steps and seconds with ``split="switch"`` (it changes split,
  S carried across) and with ``split="fixed"`` (it keeps its split and runs on into its
  singular set, where the indicator stops it: what every run with sensitivities did
  before), and the plain switching run, for the cost of the sensitivities.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from _common import ROOT, best_of, parser, write

sys.path.insert(0, str(ROOT / "tests"))
TOL = dict(rtol=1e-11, atol=1e-12)            # connect's defaults


def connect_case(principle, end, unknowns, reps):
    import jetnh as jn
    from damped_sleigh import ORIGIN, PARAMS, damped_sleigh
    from scipy.optimize import least_squares

    system = damped_sleigh()
    span = (0.0, 1.0)
    line = [end["x"], end["th"]] + [0.0] * (len(unknowns) - 2)
    tic = time.perf_counter()
    jn.connect(system, principle, ORIGIN, end, span, params=PARAMS)
    first = time.perf_counter() - tic
    scene = jn.Scene(system, principle, params=PARAMS, t_span=span,
                     initial={**ORIGIN, **{u: 0.0 for u in unknowns}})

    def miss(u):
        tr = scene.run(y0={**ORIGIN, **dict(zip(unknowns, u))}, **TOL)
        return [tr[c][-1] - v for c, v in end.items()]

    def ours():
        return jn.connect(system, principle, ORIGIN, end, span, params=PARAMS)

    def theirs():
        return least_squares(miss, line, xtol=1e-12, ftol=1e-12, gtol=1e-12)

    (t_ours, c), (t_theirs, fit) = best_of([ours, theirs], reps)
    u = np.array([c.initial[k] for k in unknowns])
    return {"connect_s": t_ours, "connect_first_call_s": first,
            "least_squares_s": t_theirs, "ratio": t_theirs / t_ours,
            "connect_residual": c.residual, "least_squares_residual":
            float(np.abs(fit.fun).max()), "least_squares_nfev": int(fit.nfev),
            "unknowns_difference": float(np.abs(u - fit.x).max()),
            "switches": len(c.trajectory.switches), "route": c.route,
            "iterations": c.iterations}


def sensitivity_case(reps):
    import jetnh as jn
    from damped_sleigh import ORIGIN, PARAMS, damped_sleigh

    scene = jn.Scene(damped_sleigh(), "chetaev", params=PARAMS, t_span=(0.0, 1.0),
                     initial={**ORIGIN, "x_t": 0.2, "th_t": 2.5})
    kw = dict(rtol=1e-10, atol=1e-12)
    calls = {"switch": lambda: scene.run(sensitivities=True, **kw),
             "fixed": lambda: scene.run(sensitivities=True, split="fixed", **kw),
             "plain": lambda: scene.run(**kw)}
    calls["switch"](), calls["plain"]()          # warm (the fixed run takes seconds)
    timed = best_of(list(calls.values()), reps, budget=1.0)
    out = {}
    for name, (seconds, tr) in zip(calls, timed):
        out[name] = {"seconds": seconds, "steps": tr.diagnostics.steps,
                     "status": tr.status, "t_end": float(tr.t[-1]),
                     "switches": len(tr.switches)}
    out["fixed_over_switch"] = out["fixed"]["seconds"] / out["switch"]["seconds"]
    out["switch_over_plain"] = out["switch"]["seconds"] / out["plain"]["seconds"]
    return out


def main():
    ap = parser(__doc__, "connect_edge")
    args = ap.parse_args()
    reps = 3 if args.quick else 15
    data = {"connect": {
        "chetaev": connect_case("chetaev", {"x": 0.2, "th": 2.0}, ("x_t", "th_t"), reps),
        "vakonomic": connect_case("vakonomic", {"x": 0.2, "y": 0.5, "th": 2.0},
                                  ("x_t", "th_t", "lambda_y"), reps)},
        "sensitivities": sensitivity_case(2 if args.quick else 5)}
    for name, r in data["connect"].items():
        print(f"{name}: connect {r['connect_s'] * 1e3:.2f} ms, least_squares "
              f"{r['least_squares_s'] * 1e3:.2f} ms ({r['ratio']:.1f}x), unknowns within "
              f"{r['unknowns_difference']:.1e}")
    s = data["sensitivities"]
    print(f"sensitivities: switch {s['switch']['steps']} steps "
          f"{s['switch']['seconds'] * 1e3:.2f} ms, fixed {s['fixed']['steps']} steps "
          f"{s['fixed']['seconds'] * 1e3:.1f} ms ({s['fixed_over_switch']:.0f}x), "
          f"switch / plain {s['switch_over_plain']:.2f}")
    write("connect_edge", data, args.out, args.quick)


if __name__ == "__main__":
    main()
