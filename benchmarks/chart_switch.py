"""The cost of a run that changes chart (``jetnh.numeric.atlas``): the switching run
against the same run kept in its split, and the switch alone, on this tree and on earlier
ones, and the cost of watching the edge in a run that never reaches it; with ``--panels``,
the work-precision panels of those runs.

    .venv/bin/python benchmarks/chart_switch.py [--tree NAME=PATH ...] [--rounds 3]
                                                [--panels] [--quick] [--out PATH]

(default output: benchmarks/results/chart_switch.json; a tree is a git worktree, e.g.
``git worktree add /tmp/before 08f5e43``; this tree is "after").  Cases: the
work-precision panels (``workprecision.py``) whose run crosses its split's edge once --
chaplygin_sleigh under Chetaev and vakonomic dynamics (T = 2) and knife_edge vakonomic
(T = 0.8) -- run as the work-precision panels run at error 1e-8: dop853, rtol 1e-8, atol
1e-11, ``save="final"``; and knife_edge Chetaev (T = 0.8), whose run watches its split's
edge and ends before it (``WATCHED``: ``run`` and ``fixed`` only).  Each tree measures
in a fresh process of its own (the trees alternating within each of ``--rounds``
rounds; each figure the best over the rounds), the calls interleaved, each figure the
10th percentile of single calls:

- ``run``: the switching run (``scene.run``; where the tree has ``chart_driver``, its
  driver compiled ahead, as ``jetnh cache warm`` does, and the run repeated, so that
  it is one compiled call);
- ``fixed``: the same run with ``split="fixed"``: it keeps its split (the edge, measure
  1/8, is not singular), takes the same steps up to the edge and about as many after:
  the floor a switching run adds to;
- ``read``: the switching run and its rows read (``.y``: a switching run maps its rows
  to the scene's chart when they are first read);
- ``switch``: ``atlas.switch`` alone at the state where the run reached the edge (the
  new chart, its state), what the run pays to change chart beyond running two pieces;
- ``replace``: ``scene.replace(initial=...).run()``, the switching run of a copy of the
  scene with its initial values given again (a shooting loop's run; sampled every
  ``REPLACE_EVERY``-th round of calls).

With ``--panels`` each tree also runs ``workprecision.panel`` of the three panels (the
quick tolerances 1e-3, 1e-6, 1e-9 with ``--quick``, else 1e-3 ... 1e-12): the time jetnh's
fastest adaptive method and the fastest scipy method need to reach each target error,
and their ratio (the work-precision target: >= 50).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

from _common import ROOT, parser, run_worker, write

CASES = ("chaplygin_sleigh / chetaev", "chaplygin_sleigh / vakonomic",
         "knife_edge / vakonomic")
#: a run that watches its edge and never reaches it (no switch)
WATCHED = ("knife_edge / chetaev",)
RUN = dict(method="dop853", save="final", rtol=1e-8, atol=1e-11)
REPLACE_EVERY = 20
FIGURES = ("run", "fixed", "read", "switch", "replace")


def costs(calls: int) -> dict:
    """case -> {"run", "fixed", "switch", "replace"} seconds, and the run's switches (this
    tree)."""
    from workprecision import cases, scene_of

    from jetnh.numeric import atlas

    try:            # (a tree whose switching runs are one compiled call: compiled ahead,
        from jetnh.numeric import precompile    # as ``jetnh cache warm`` does)

        for name in ("atlas:dop853:final",):
            if name in precompile.LOOPS:
                precompile.compile_loop(name)
    except ImportError:
        pass
    found = {c.label: c for c in cases(False)}
    timed, out = [], {}
    for label in WATCHED:
        scene = scene_of(found[label]).compile()
        assert not scene.run(**RUN).switches, label
        fs = {"run": lambda s=scene: s.run(**RUN),
              "fixed": lambda s=scene: s.run(**RUN, split="fixed")}
        for f in fs.values():
            for _ in range(20):
                f()
        out[label] = {"switches": 0}
        timed += [(label, name, f) for name, f in fs.items()]
    for label in CASES:
        scene = scene_of(found[label]).compile()
        tr = scene.run(**RUN)
        *_, seg, _, _ = tr._segments.pieces[0]           # the piece up to the edge
        at, p = atlas.atlas(scene), np.ascontiguousarray(scene.p, dtype=float)
        t, y = float(seg.t[-1]), np.ascontiguousarray(seg.y[-1])
        ini = {n: scene.initial[n] for n in scene.state_names}
        fs = {"run": lambda s=scene: s.run(**RUN),
              "fixed": lambda s=scene: s.run(**RUN, split="fixed"),
              "read": lambda s=scene: s.run(**RUN).y,
              "switch": lambda at=at, t=t, y=y, p=p: atlas.switch(at, at.own, t, y, p),
              "replace": lambda s=scene, ini=ini: s.replace(initial=ini).run(**RUN)}
        for f in fs.values():
            for _ in range(20):
                f()
        out[label] = {"switches": len(tr.switches), "switch_t": tr.switches[0]["t"],
                      "to": tr.switches[0]["to"]}
        timed += [(label, name, f) for name, f in fs.items()]
    samples = {(label, name): [] for label, name, _ in timed}
    for i in range(calls):
        for label, name, f in timed:
            if name == "replace" and i % REPLACE_EVERY:
                continue
            tic = time.perf_counter()
            f()
            samples[label, name].append(time.perf_counter() - tic)
    for (label, name), v in samples.items():
        out[label][name] = float(np.percentile(v, 10))
    return out


def panels(quick: bool) -> dict:
    """case -> {target: {"jetnh", "scipy", "scipy_method"}} of ``workprecision.panel``."""
    from workprecision import JETNH_ADAPTIVE, SCIPY, TARGETS, cases, panel

    steps = [10, 100, 1000]             # the fixed-step methods (not reported here)
    if quick:
        tolerances, reps, budget, give_up = [1e-3, 1e-6, 1e-9], 2, 0.2, 0.5
    else:
        tolerances, reps, budget, give_up = [10.0 ** -k for k in range(3, 13)], 5, 1.0, 2.0
    out = {}
    for case in cases(False):
        if case.label not in CASES:
            continue
        tte = panel(case, tolerances, steps, reps, budget, give_up)["time_to_error"]
        row = {}
        for t in map(str, TARGETS):
            ours = [tte[f"jetnh {m}"][t] for m in JETNH_ADAPTIVE if tte[f"jetnh {m}"][t]]
            theirs = {m: tte[f"scipy {m}"][t] for m in SCIPY if tte[f"scipy {m}"][t]}
            best = min(theirs, key=theirs.get) if theirs else None
            row[t] = {"jetnh": min(ours) if ours else None,
                      "scipy": theirs[best] if best else None, "scipy_method": best}
        out[case.label] = row
    return out


def worker(spec: dict) -> None:
    result = {"costs": costs(spec["calls"])}
    if spec.get("panels"):
        result["panels"] = panels(spec["quick"])
    print(json.dumps(result))


def commit(root) -> str:
    r = subprocess.run(["git", "--no-optional-locks", "rev-parse", "--short=12", "HEAD"],
                       cwd=root, capture_output=True, text=True)
    return r.stdout.strip() or "?"


def main(argv=None):
    ap = parser(__doc__, "chart_switch")
    ap.add_argument("--tree", action="append", default=[], metavar="NAME=PATH",
                    help="an earlier tree to measure too (a git worktree)")
    ap.add_argument("--rounds", type=int, default=None)
    ap.add_argument("--panels", action="store_true",
                    help="also the work-precision panels of the switching runs")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        return worker(json.loads(args.worker))
    trees = dict(t.split("=", 1) for t in args.tree)
    trees["after"] = str(ROOT)
    rounds = args.rounds or (2 if args.quick else 3)
    spec = {"calls": 300 if args.quick else 2000, "quick": args.quick}
    got = {name: [] for name in trees}
    for r in range(rounds):
        for name, root in trees.items():
            one = dict(spec, panels=args.panels and r == 0)
            res = run_worker(__file__, one, 1800, env=dict(os.environ, PYTHONPATH=root))
            if "error" in res or res.get("timeout"):
                sys.exit(f"tree {name} ({root}): {res}")
            got[name].append(res)
            print(f"round {r + 1}, {name}: " + ", ".join(
                f"{c.split(' / ')[0][:8]}/{c.split(' / ')[1][:4]} run "
                f"{v['run'] * 1e6:.1f} us, fixed {v['fixed'] * 1e6:.1f} us"
                + (f", read {v['read'] * 1e6:.1f} us, switch {v['switch'] * 1e6:.1f} us, "
                   f"replace {v['replace'] * 1e6:.0f} us"
                   if "switch" in v else "")
                for c, v in res["costs"].items()), flush=True)
    best = {name: {c: {k: min(r["costs"][c][k] for r in runs) for k in FIGURES}
                   for c in CASES} for name, runs in got.items()}
    for name, runs in got.items():
        for c in WATCHED:
            best[name][c] = {k: min(r["costs"][c][k] for r in runs) for k in ("run", "fixed")}
    names = list(trees)
    rows = [[c, *(f"{best[n][c][k] * 1e6:.3g}" for n in names for k in FIGURES),
             *(f"{best[n][c]['run'] / best[n][c]['fixed']:.2f}" for n in names),
             *(f"{best[n][c]['replace'] / best[n][c]['run']:.2f}" for n in names)]
            for c in CASES]
    trees_note = "trees (commits): " + ", ".join(f"{n} = {commit(p)}" for n, p in trees.items())
    tables = [dict(
        title="A run that changes chart once, against the same run kept in its split "
              "(dop853, rtol 1e-8, atol 1e-11, save='final'; us, 10th percentile of "
              "interleaved calls, best of the rounds; one process per tree)",
        columns=["", *(f"{n} {k}" for n in names for k in FIGURES),
                 *(f"{n} run / fixed" for n in names),
                 *(f"{n} replace / run" for n in names)],
        rows=rows, note=trees_note),
        dict(title="A run that watches its split's edge and ends before it, against the "
                   "same run with split='fixed' (which watches nothing; us, as above)",
             columns=["", *(f"{n} {k}" for n in names for k in ("run", "fixed")),
                      *(f"{n} run - fixed" for n in names)],
             rows=[[c, *(f"{best[n][c][k] * 1e6:.3g}" for n in names for k in ("run", "fixed")),
                    *(f"{(best[n][c]['run'] - best[n][c]['fixed']) * 1e6:.2f}" for n in names)]
                   for c in WATCHED], note=trees_note)]
    if args.panels:
        prow = []
        for c in CASES:
            for t in ("0.0001", "1e-06", "1e-08"):
                cells = []
                for n in names:
                    e = got[n][0]["panels"][c][t]
                    ratio = (e["scipy"] / e["jetnh"]) if e["jetnh"] and e["scipy"] else None
                    cells += [f"{e['jetnh'] * 1e6:.3g}" if e["jetnh"] else "-",
                              f"{ratio:.1f} ({e['scipy_method']})" if ratio else "-"]
                prow.append([c, t, *cells])
        tables.append(dict(
            title="Work-precision panels of these runs (workprecision.panel, "
                  f"{'quick' if args.quick else 'full'} tolerances): jetnh's fastest "
                  "adaptive method (us) to reach the error, and the fastest scipy method "
                  "over it",
            columns=["panel", "error", *(f"{n} {k}" for n in names
                                         for k in ("jetnh (us)", "scipy / jetnh"))],
            rows=prow, note="target: scipy / jetnh >= 50 on every panel"))
    for tab in tables:
        print(tab["title"])
        print(" | ".join(tab["columns"]))
        for row in tab["rows"]:
            print(" | ".join(row))
    a = best["after"]
    write("chart_switch", dict(
        title="A run that changes chart: against the same run kept in its split",
        summary=[f"{c}: the switching run costs {a[c]['run'] / a[c]['fixed']:.2f}x the run "
                 f"kept in its split ({a[c]['run'] * 1e6:.0f} against "
                 f"{a[c]['fixed'] * 1e6:.0f} us; {a[c]['read'] * 1e6:.0f} us with its rows "
                 f"read), the switch alone "
                 f"{a[c]['switch'] * 1e6:.1f} us, a replace(initial=...) copy's run "
                 f"{a[c]['replace'] / a[c]['run']:.2f}x the run" for c in CASES]
                + [f"{c}: watching the edge without reaching it costs "
                   f"{(a[c]['run'] - a[c]['fixed']) * 1e6:.1f} us over split='fixed' "
                   f"({a[c]['run'] * 1e6:.1f} against {a[c]['fixed'] * 1e6:.1f} us)"
                   for c in WATCHED],
        tables=tables, trees={n: commit(p) for n, p in trees.items()}, rounds=got),
        args.out, args.quick)


if __name__ == "__main__":
    main()
