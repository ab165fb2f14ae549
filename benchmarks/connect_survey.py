"""What ``jn.connect`` finds on the catalogue: every model x principle, from the model's
catalogue start to where its Chetaev motion is after ``T`` (1 s, or the catalogue's
span where that is shorter).

    PYTHONPATH=. python benchmarks/connect_survey.py [--quick] [--models a,b] [--out PATH]
        [--update]

(default output: benchmarks/results/connect_survey.json; ``--update`` replaces only the
rows run in that file, keeping the others)

For each model: the Chetaev run of ``T`` from the catalogue initial state gives ``start``
(its configuration at 0) and ``end`` (every coordinate at T); then ``jn.connect(model, P,
start, end, (0, T))`` from the default guess for P in vakonomic, Hoelder, Chetaev,
Suslov.  The end is reachable under Chetaev by construction; under the other principles
it may not be (Suslov's motions with zero multipliers are another family; a vakonomic
end may lie where the endpoint map is singular).  Vakonomic and Hoelder take
``restarts=RESTARTS``: where the first answer has a conjugate time inside the span (no
minimizer of the action), the restarts (``connect.solve.least_action``: the direct
route's guess, then moves around the answer) look for a cheaper extremal without one.
Each case runs in a fresh interpreter with a time-out.  The
table gives the cost, the verdicts (normal, conjugate times, minimizer), the residual and
the wall time; or the failure's class and message.  ``--quick``: the four smallest
models.
"""

from __future__ import annotations

import json
import sys
import time

try:
    from _common import parser, run_worker, write
except ImportError:          # run from the repository root
    from benchmarks._common import parser, run_worker, write

T = 1.0
PRINCIPLES = ("vakonomic", "holder", "chetaev", "suslov")
MODELS = ("heisenberg", "nonholonomic_particle", "chaplygin_sleigh", "knife_edge",
          "rolling_disk", "appell_hamel", "rolling_coin", "isokinetic_particle",
          "rheonomic_knife_edge", "bead_on_parabola", "radial_line", "rolling_ball",
          "ball_on_turntable", "suslov_rigid_body", "n_trailer", "particle_chain",
          "damped_knife_edge", "damped_chaplygin_sleigh")
QUICK = ("heisenberg", "nonholonomic_particle", "chaplygin_sleigh", "knife_edge")
TIMEOUT = 600.0
#: restarts of the least-action search (``connect(restarts=)``, vakonomic and Hoelder)
RESTARTS = 8


def span(name) -> float:
    import jetnh.models

    return min(T, jetnh.models.info(name).t_end)


def endpoints(name):
    """(start, end): the catalogue start and the Chetaev motion's configuration at
    ``span(name)``."""
    import jetnh as jn
    import jetnh.models

    system = jn.models.get(name)
    tr = jn.Scene(system, "chetaev", initial=jn.models.initial(name),
                  t_span=(0.0, span(name))).run(rtol=1e-12, atol=1e-13)
    coords = [q.name for q in system.J.q]
    return ({c: float(tr[c][0]) for c in coords}, {c: float(tr[c][-1]) for c in coords},
            tr.status)


def case(name, principle):
    """One connect: a JSON-able dict (its answer or its failure)."""
    import jetnh as jn
    import jetnh.models

    system = jn.models.get(name)
    start, end, status = endpoints(name)
    if status != 0:
        return {"failure": "the Chetaev run fails before T"}
    tic = time.perf_counter()
    variational = principle in ("vakonomic", "holder")
    try:
        c = jn.connect(system, principle, start, end, (0.0, span(name)),
                       restarts=RESTARTS if variational else 0)
    except jn.ConnectError as e:
        best = e.best
        return {"seconds": time.perf_counter() - tic, "failure": "ConnectError",
                "message": str(e), "best_residual": None if best is None else best.residual}
    except jn.JetnhError as e:
        return {"seconds": time.perf_counter() - tic, "failure": type(e).__name__,
                "message": str(e)}
    seconds = time.perf_counter() - tic
    out = {"seconds": seconds, "T": span(name), "cost": c.cost, "normal": c.normal,
           "conjugate_times": list(c.conjugate_times), "minimizer": c.minimizer,
           "residual": c.residual, "rank": c.rank, "iterations": c.iterations,
           "route": c.route, "search": c.search, "initial": dict(c.initial)}
    return out


def row(name, principle, r):
    if "failure" in r and "message" not in r and "seconds" not in r:
        return f"| {name} | {principle} | {r.get('failure', r.get('error'))} |"
    if r.get("timeout"):
        return f"| {name} | {principle} | time-out (> {r['seconds_lower_bound']:.0f} s) |"
    if "error" in r:
        return f"| {name} | {principle} | crash: {r['error']} |"
    if "failure" in r:
        msg = r["message"].replace("|", "/")
        return f"| {name} | {principle} | {r['failure']} ({r['seconds']:.1f} s): {msg} |"
    ct = ", ".join(f"{t:.4g}" for t in r["conjugate_times"]) or "none"
    text = (f"| {name} | {principle} | cost {r['cost']:.6g}, "
            f"{'normal' if r['normal'] else 'ABNORMAL'}, conjugate times {ct}"
            + (", NOT A MINIMIZER" if r.get("minimizer") is False else "")
            + f", residual {r['residual']:.1e}, rank {r['rank']}, {r['iterations']} it, "
            f"{r['seconds']:.1f} s, by {r['route']}")
    return text + " |"


def main():
    if len(sys.argv) > 2 and sys.argv[1] == "--worker":
        spec = json.loads(sys.argv[2])
        print(json.dumps(case(spec["model"], spec["principle"])))
        return
    ap = parser(__doc__, "connect_survey")
    ap.add_argument("--models", help="comma-separated catalogue names (default: all)")
    ap.add_argument("--principles", default=",".join(PRINCIPLES))
    ap.add_argument("--update", action="store_true",
                    help="replace only these rows in the results file, keep the others")
    args = ap.parse_args()
    names = args.models.split(",") if args.models else (QUICK if args.quick else MODELS)
    results = {}
    print("| model | principle | answer |\n|---|---|---|")
    for name in names:
        for p in args.principles.split(","):
            r = run_worker(__file__, {"model": name, "principle": p}, TIMEOUT)
            results[f"{name}/{p}"] = r
            print(row(name, p, r), flush=True)
    if args.update and args.out.exists():
        results = {**json.loads(args.out.read_text())["results"], **results}
    write("connect_survey", {"T": T, "results": results}, args.out, args.quick)


if __name__ == "__main__":
    main()
