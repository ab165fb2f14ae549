"""The cost per right-hand-side evaluation of jetnh's dop853 and dopri5 loops, this tree
against another checkout (the per-step checks of the loop: budget, stiffness test,
singularity indicators).

    .venv/bin/python benchmarks/explicit_step_cost.py [--quick] [--vs PATH] [--out PATH]

(default output: benchmarks/results/explicit_step_cost.json).  Each measurement runs in a
fresh interpreter (``--worker``) with ``PYTHONPATH`` set to its tree: the compiled loop
of the method called through its entry (``loops.entry``: what ``scene.run(save="final")``
calls, without the run's fixed cost) on catalogue models (Chetaev) over t = 0..200 at
rtol 1e-10 with ``max_step`` 0.005 (>= 40 000 steps a run), once watching nothing and once
watching the scene's singularity indicators.  The figure per case is the best of
``reps`` calls (CPU time of the process: on a loaded machine the wall time counts the
waits for a core) over the number of evaluations; with ``--vs`` the two trees' workers run
in turn, A B A B ..., and the ratio (this tree / the other) is the median over the
rounds; the final states of the two trees must be equal bit for bit (the steps are the
same).  Machine, date, load average, commit and command in the JSON
(``_common.write``).
"""

import json
import os
import sys
import time

import numpy as np

from _common import ROOT, parser, run_worker, write

CASES = [(name, method, watched) for name in ("rolling_disk", "rolling_ball",
                                               "suslov_rigid_body")
         for method in ("dop853", "dopri5") for watched in (False, True)]


def worker(spec):
    from jetnh import models
    from jetnh.numeric import Scene, loops, methods
    from jetnh.numeric.methods._common import ENDPOINTS
    from jetnh.numeric.methods.loop import Control, watch_of

    out = {}
    for name, method, watched in CASES:
        sc = Scene(models.get(name), "chetaev", initial=models.initial(name),
                   t_span=(0.0, 200.0)).compile()
        t0, t1 = sc.t_span
        y0, p = sc.y0.copy(), np.ascontiguousarray(sc.p, dtype=float)
        kern = sc.kernels
        ctl = Control(1e-10, np.full(len(y0), 1e-12), 0.0, 0.005, 10**9, 0)
        watch = watch_of(kern, None, watched, 1e-10)
        loop, prefix, suffix, callbacks = loops.entry(
            sc, methods.method(method), kern, None, None, ctl, np.zeros(0), ENDPOINTS,
            watch, None)
        halt = np.zeros(1, dtype=np.int64)
        args = (*prefix, t0, t1, y0, p, *suffix, halt)
        res = loops.result(loop(*args))             # compile / warm
        best = np.inf
        for _ in range(spec["reps"]):
            tic = time.process_time()
            loop(*args)
            best = min(best, time.process_time() - tic)
        nfev = int(res.stats[2])
        out[f"{name} {method} {'watched' if watched else 'plain'}"] = dict(
            ns_per_eval=best / nfev * 1e9, steps=int(res.stats[0]), status=int(res.status),
            final=[float(v).hex() for v in res.y])
        del callbacks
    print(json.dumps(out))


def main(argv=None):
    ap = parser(__doc__, "explicit_step_cost")
    ap.add_argument("--vs", help="another checkout of jetnh to compare with")
    ap.add_argument("--worker", help=argparse_hidden())
    args = ap.parse_args(argv)
    if args.worker:
        return worker(json.loads(args.worker))
    rounds, reps = (3, 3) if args.quick else (7, 5)
    trees = [str(ROOT)] + ([os.path.abspath(args.vs)] if args.vs else [])
    runs = {tree: [] for tree in trees}
    for _ in range(rounds):
        for tree in trees:
            env = dict(os.environ, PYTHONPATH=tree)
            r = run_worker(__file__, {"reps": reps}, 1800, env)
            if "error" in r or r.get("timeout"):
                sys.exit(f"worker in {tree}: {r}")
            runs[tree].append(r)
    rows = []
    for case in runs[trees[0]][0]:
        mine = [r[case]["ns_per_eval"] for r in runs[trees[0]]]
        row = dict(case=case, steps=runs[trees[0]][0][case]["steps"],
                   ns_per_eval=min(mine))
        if args.vs:
            theirs = [r[case]["ns_per_eval"] for r in runs[trees[1]]]
            row.update(vs_ns_per_eval=min(theirs),
                       ratio=float(np.median(np.array(mine) / np.array(theirs))),
                       same_bits=runs[trees[0]][0][case]["final"]
                       == runs[trees[1]][0][case]["final"])
        rows.append(row)
        print(f"{case:36s} {row['steps']:7d} steps  {row['ns_per_eval']:7.2f} ns/eval"
              + (f"  vs {row['vs_ns_per_eval']:7.2f}: ratio {row['ratio']:.3f}, same "
                 f"bits {row['same_bits']}" if args.vs else ""))
    summary = ("dop853/dopri5 per evaluation" + (
        f", this tree / {args.vs}: " + ", ".join(f"{r['case']} {r['ratio']:.3f}"
                                                   for r in rows)
        + f"; same final bits: {all(r['same_bits'] for r in rows)}" if args.vs else ": "
        + ", ".join(f"{r['case']} {r['ns_per_eval']:.1f} ns" for r in rows)))
    write("explicit_step_cost", dict(title="dop853 and dopri5: cost per evaluation",
                                     summary=summary, rows=rows, vs=args.vs),
          args.out, args.quick)


def argparse_hidden():
    import argparse

    return argparse.SUPPRESS


if __name__ == "__main__":
    main()
