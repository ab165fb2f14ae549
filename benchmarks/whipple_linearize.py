"""The benchmark bicycle's stability diagram, jetnh against sympy: the whole route from
the ``KanesMethod`` model (``jetnh.models.whipple.whipple_kane``, Kane's equations
formed) to the eigenvalues of upright straight running at 100 forward speeds, each route
in a fresh interpreter, sympy's capped at a time budget.

jetnh: ``jn.from_mechanics``, ``jn.linearize`` (Chetaev) at one speed, then
``Linearization.along`` the rear wheel rate (a kernel call per speed; the weave and
capsize crossings found on the way).  sympy: ``KanesMethod.linearize(A_and_B=True,
linear_solver="CRAMER")`` with the benchmark's numeric parameters and the speed left
symbolic in the operating point (the LU default gives NaN on this model), ``lambdify``
of A(v), numpy eigenvalues.  Both figures include forming Kane's equations (reported on
its own too).  When sympy hits the budget the ratio is a lower bound.

    PYTHONPATH=. python benchmarks/whipple_linearize.py [--quick] [--budget SECONDS]
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

try:
    from _common import parser, run_worker, write
except ImportError:
    from benchmarks._common import parser, run_worker, write

SPEEDS = np.linspace(0.0, 10.0, 100)
PUBLISHED = {"weave": 4.29238253634111, "capsize": 6.02426201538837}


def jetnh_route():
    import jetnh as jn
    from jetnh.models.whipple import DEPENDENT, benchmark_parameters, upright, whipple_kane

    tic = time.perf_counter()
    km = whipple_kane()
    kane = time.perf_counter() - tic
    bike = jn.from_mechanics(km, dependent=DEPENDENT)
    params = benchmark_parameters()
    rR = params["WRrad"]
    lin = jn.linearize(bike, "chetaev", at=upright(bike, 5.0, params), params=params)
    scan = lin.along("q3_t", SPEEDS / rR)
    return kane, list(scan.eigenvalues), [c * rR for c in scan.crossings]


def sympy_route():
    import sympy as sp
    from sympy.physics.mechanics import dynamicsymbols

    from jetnh.models.whipple import DEPENDENT, benchmark_parameters, upright, whipple_kane

    tic = time.perf_counter()
    km = whipple_kane()
    kane = time.perf_counter() - tic
    params = benchmark_parameters()
    v = sp.Symbol("v")
    op = {sp.Symbol(k): x for k, x in params.items()}
    op.update({q: 0 for q in km.q})
    op.update({u: 0 for u in km.u})
    op[dynamicsymbols("u3")] = v / params["WRrad"]
    op.update({u.diff(): 0 for u in km.u})
    A = km.linearize(A_and_B=True, op_point=op, linear_solver="CRAMER")[0]
    f = sp.lambdify(v, A, "numpy")
    return kane, [np.linalg.eigvals(np.array(f(s), dtype=float)) for s in SPEEDS], []


def worker(which):
    tic = time.perf_counter()
    kane, ev, crossings = jetnh_route() if which == "jetnh" else sympy_route()
    wall = time.perf_counter() - tic
    top = []
    for e in ev:
        e = e[np.abs(e) > 1e-6]
        top.append(float(e.real.max()) if e.size else 0.0)
    print(json.dumps({"seconds": wall, "kane_s": kane, "max_real": top,
                      "crossings": crossings}))


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--worker":
        return worker(json.loads(sys.argv[2]))
    p = parser(__doc__, "whipple_linearize")
    p.add_argument("--budget", type=float, default=600.0,
                   help="seconds allowed to sympy's route (default 600)")
    args = p.parse_args()
    budget = 60.0 if args.quick else args.budget
    jt = run_worker(__file__, "jetnh", timeout=3600)
    sy = run_worker(__file__, "sympy", timeout=budget)
    if "error" in jt:
        raise SystemExit(f"jetnh route failed: {jt['error']}")
    speeds = dict(zip(PUBLISHED, jt["crossings"]))
    rows = [{"route": "jetnh",
             "seconds": jt["seconds"], "kane_equations_s": jt["kane_s"]}]
    if sy.get("timeout"):
        ratio = f">= {budget / jt['seconds']:.3g} (sympy stopped at the {budget:.0f} s budget)"
        rows.append({"route": "sympy",
                     "seconds": f"> {budget:.0f}", "kane_equations_s": "-"})
        agree = None
    elif "error" in sy:
        ratio, agree = f"- (sympy failed: {sy['error']})", None
        rows.append({"route": "sympy", "seconds": "error",
                     "kane_equations_s": "-"})
    else:
        ratio = f"{sy['seconds'] / jt['seconds']:.3g}"
        agree = float(np.max(np.abs(np.array(jt["max_real"]) - np.array(sy["max_real"]))))
        rows.append({"route": "sympy",
                     "seconds": sy["seconds"], "kane_equations_s": sy["kane_s"]})
    summary = [f"sympy's route over jetnh's, same run: {ratio}."]
    if agree is not None:
        summary.append(f"Largest real parts of the two routes agree to {agree:.1e}.")
    summary += [f"{k} speed: jetnh {c:.14f} m/s, Meijaard et al. (2007) {PUBLISHED[k]:.14f}"
                f" (difference {c - PUBLISHED[k]:+.1e})" for k, c in speeds.items()]
    print("\n".join(summary), flush=True)
    write("whipple_linearize", {
        "title": "Benchmark bicycle: the stability diagram, jetnh against sympy's "
                 "KanesMethod.linearize", "summary": summary,
        "columns": ["route", "seconds", "kane_equations_s"], "rows": rows,
        "speeds": len(SPEEDS), "budget_s": budget, "jetnh": jt, "sympy": sy,
        "crossings": speeds, "published": PUBLISHED}, args.out, args.quick)


if __name__ == "__main__":
    main()
