"""What watching the singularity indicators costs a short run: ``scene.run`` with the
indicators watched (the default) against the same run with ``singular="ignore"``, on the
work-precision panels, this tree against another checkout; and what watching the edge of
the split's chart costs a run that never reaches it: the default run (``split="switch"``)
against the watched run kept in its split.

    .venv/bin/python benchmarks/watch_cost.py [--quick] [--vs PATH] [--rounds N] [--panels]
                                              [--out PATH]

(default output: benchmarks/results/watch_cost.json; ``--vs`` a git worktree of the
baseline, e.g. ``git worktree add --detach /tmp/watch-before 299079e``).  Scenes:
``workprecision.scene_of`` of its Chetaev cases (``--quick``: nonholonomic_particle,
knife_edge, chaplygin_sleigh), run as the work-precision benchmark runs them:
``scene.run(method="dop853", save="final", rtol=1e-8, atol=1e-11, split="fixed")``;
``default``: the same without ``split`` (a scene whose split has an edge watches it as an
event of its own, ``numeric.atlas``; measured on the panels whose run does not reach the
edge: ``edge`` = default - watched).

Each measurement runs in a fresh interpreter (``--worker``) with ``PYTHONPATH`` set to its
tree; the trees' workers run in turn, A B A B ... (``--rounds`` rounds).  A worker calls
the runs of a panel in turn, warm, ``calls`` times each, and reports the 10th
percentile of the single calls' wall times (``perf_counter``) and of their CPU times
(``thread_time``: on a loaded machine the wall time counts the waits for a core), and
the same for the compiled loop called directly (``plan.entry``: the run without its
Python side).  Besides, runs whose last steps are searched inside for a dip of an
indicator (``_events.sing_dip``): Appell-Hamel's speed decays to a zero that
x_t^2 + y_t^2 only touches; dop853, dopri5, rk4 (400 steps) and radau stop at its
threshold (CPU time, 10th percentile; the stop times of both trees must be equal).
The figure per tree is the best over the rounds; ``watch`` = watched - ignored, the
extra cost of the watch; both trees' runs must end on the same state bit
for bit (the watch changes no step).  Machine, date, load average (also before and after
each round), commit and command in the JSON (``_common.write``).

With ``--panels`` each tree also runs ``workprecision.panel`` of ``PANEL_CASES`` (in its
first round; the quick tolerances 1e-3, 1e-6, 1e-9 with ``--quick``, else 1e-3 ...
1e-12): the time jetnh's fastest adaptive method and the fastest scipy method need to
reach each error, and their ratio (the work-precision target: >= 50).
"""

import json
import os
import sys
import time

import numpy as np

from _common import ROOT, parser, run_worker, write

PANELS = ("nonholonomic_particle", "knife_edge", "chaplygin_sleigh", "isokinetic_particle",
          "n_trailer", "rolling_disk")
QUICK = ("nonholonomic_particle", "knife_edge", "isokinetic_particle")
RUN = dict(method="dop853", save="final", rtol=1e-8, atol=1e-11, split="fixed")
#: the work-precision panels of ``--panels``: a run that watches its chart's edge, and
#: runs that watch indicators only
PANEL_CASES = ("knife_edge / chetaev", "isokinetic_particle / chetaev",
               "isokinetic_particle / vakonomic")


#: runs whose last steps are searched inside (``_events.sing_dip``): the Appell-Hamel
#: speed decays to a zero it only touches; each method stops at its threshold
SEARCHED = (("dop853", dict(rtol=1e-10, atol=1e-12)), ("dopri5", dict(rtol=1e-8, atol=1e-10)),
            ("rk4", dict(n_steps=400)), ("radau", dict(rtol=1e-8, atol=1e-10)))


def searched(calls):
    """The Appell-Hamel runs of ``SEARCHED``: 10th percentile of their CPU times and the
    stop."""
    from jetnh.models import appell_hamel
    from jetnh.numeric import Scene

    scene = Scene(appell_hamel(), "chetaev", initial=dict(x=0, y=0, z=0, x_t=0.6, y_t=0.8),
                  t_span=(0.0, 1.0))
    out = {}
    for method, kw in SEARCHED:
        def run(method=method, kw=kw):
            return scene.run(method=method, save="final", **kw)
        traj = run()
        cpu = []
        for _ in range(calls):
            c0 = time.thread_time()
            run()
            cpu.append(time.thread_time() - c0)
        out[method] = {"cpu_us": float(np.percentile(cpu, 10)) * 1e6,
                       "t_stop": float(traj.t[-1]), "status": int(traj.status)}
    return out


def worker(spec):
    from workprecision import cases, scene_of

    from jetnh.numeric import atlas, solve
    from jetnh.numeric.options import options

    calls = spec["calls"]
    out = {}
    for case in cases(False):
        if case.principle != "chetaev" or case.model not in spec["panels"]:
            continue
        scene = scene_of(case)
        runs, loops = [], []
        for singular in ("stop", "ignore"):
            kw = dict(RUN, singular=singular)
            runs.append(lambda kw=kw: scene.run(**kw))
            plan = solve.plan(scene, "dop853", save="final", opts=options(
                rtol=RUN["rtol"], atol=RUN["atol"], split="fixed", singular=singular))
            y0 = np.ascontiguousarray(scene.y0, dtype=float)
            p = np.ascontiguousarray(scene.p, dtype=float)
            halt = np.zeros(1, dtype=np.int64)
            loops.append(lambda plan=plan, y0=y0, p=p, halt=halt: plan.entry(
                *plan.prefix, plan.t0, plan.t1, y0, p, *plan.suffix, halt))
        trajs = [f() for f in runs]                         # compile / warm
        for f in loops:
            f()
        row = {"steps": int(loops[0]()[4][0]),
               "final": [float(v) for v in trajs[0].y[-1]],
               "same_final": bool(np.array_equal(trajs[0].y[-1], trajs[1].y[-1]))}
        default = dict(RUN)
        del default["split"]
        tr = scene.run(**default)
        row["watches_edge"] = atlas.applies(scene, None)
        if not tr.switches:         # the edge watched and not reached (or no edge)
            runs.append(lambda kw=default: scene.run(**kw))
            row["same_final"] &= bool(np.array_equal(trajs[0].y[-1], tr.y[-1]))
        for label, fs in (("run", runs), ("loop", loops)):
            wall = [[] for _ in fs]
            cpu = [[] for _ in fs]
            for _ in range(calls):
                for k, f in enumerate(fs):
                    c0 = time.thread_time()
                    w0 = time.perf_counter()
                    f()
                    w1 = time.perf_counter()
                    c1 = time.thread_time()
                    wall[k].append(w1 - w0)
                    cpu[k].append(c1 - c0)
            for k, name in enumerate(("watched", "ignored", "default")[:len(fs)]):
                row[f"{label}_{name}_wall_us"] = float(np.percentile(wall[k], 10)) * 1e6
                row[f"{label}_{name}_cpu_us"] = float(np.percentile(cpu[k], 10)) * 1e6
        out[case.model] = row
    out["searched"] = searched(spec["calls"])
    if spec.get("panels_wp"):
        out["panels_wp"] = wp_panels(spec["quick"])
    print(json.dumps(out))


def wp_panels(quick):
    """case -> {error: {"jetnh", "scipy", "scipy_method"}} of ``workprecision.panel`` (as
    ``chart_switch.panels``)."""
    from workprecision import JETNH_ADAPTIVE, SCIPY, TARGETS, cases, panel

    steps = [10, 100, 1000]             # the fixed-step methods (not reported here)
    if quick:
        tolerances, reps, budget, give_up = [1e-3, 1e-6, 1e-9], 2, 0.2, 0.5
    else:
        tolerances, reps, budget, give_up = [10.0 ** -k for k in range(3, 13)], 5, 1.0, 2.0
    out = {}
    for case in cases(False):
        if case.label not in PANEL_CASES:
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


def main():
    ap = parser(__doc__, "watch_cost")
    ap.add_argument("--vs", help="an earlier tree to measure too (a git worktree)")
    ap.add_argument("--rounds", type=int, default=None)
    ap.add_argument("--panels", action="store_true",
                    help="also the work-precision panels of PANEL_CASES")
    ap.add_argument("--worker", help=argparse_hidden())
    args = ap.parse_args()
    if args.worker:
        worker(json.loads(args.worker))
        return
    panels = QUICK if args.quick else PANELS
    rounds = args.rounds or (2 if args.quick else 5)
    spec = {"panels": panels, "calls": 200 if args.quick else 400, "quick": args.quick}
    trees = {"this": str(ROOT)}
    if args.vs:
        trees["vs"] = os.path.abspath(args.vs)
    raw = {k: [] for k in trees}
    loads = []
    for r in range(rounds):
        for name, root in trees.items():
            load0 = os.getloadavg()[0]
            env = dict(os.environ, PYTHONPATH=os.pathsep.join(
                [root, str(ROOT / "benchmarks")]))
            res = run_worker(__file__, dict(spec, panels_wp=args.panels and r == 0), 1800,
                             env=env)
            loads.append([name, r, load0, os.getloadavg()[0]])
            raw[name].append(res)
            if "error" in res:
                print(name, r, res["error"])
            print(name, r, "load", f"{load0:.2f}",
                  {m: round(v.get("run_watched_wall_us", -1), 1) for m, v in res.items()
                   if isinstance(v, dict) and m not in ("searched", "panels_wp")},
                  flush=True)
    summary = {}
    for name, results in raw.items():
        good = [res for res in results if "error" not in res and "timeout" not in res]
        if not good:
            summary[name] = results[-1]
            continue
        rows = {"searched": {m: dict(v, cpu_us=min(res["searched"][m]["cpu_us"]
                                                   for res in good))
                             for m, v in good[0]["searched"].items()}}
        for model in good[0]:
            if model in ("searched", "panels_wp"):
                continue
            row = {k: min(res[model][k] for res in good)
                   for k in good[0][model] if k.endswith("_us")}
            row["steps"] = good[0][model]["steps"]
            row["watches_edge"] = good[0][model].get("watches_edge")
            for kind in ("run", "loop"):
                for clock in ("wall", "cpu"):
                    row[f"{kind}_watch_{clock}_us"] = (row[f"{kind}_watched_{clock}_us"]
                                                       - row[f"{kind}_ignored_{clock}_us"])
            if "run_default_wall_us" in row:
                for clock in ("wall", "cpu"):
                    row[f"run_edge_{clock}_us"] = (row[f"run_default_{clock}_us"]
                                                   - row[f"run_watched_{clock}_us"])
            row["same_final"] = all(res[model]["same_final"] for res in good)
            row["final"] = good[0][model]["final"]
            rows[model] = row
        summary[name] = rows
    if "vs" in summary and "error" not in summary["vs"] and "error" not in summary["this"]:
        for method, row in summary["this"]["searched"].items():
            before = summary["vs"]["searched"][method]
            row["same_stop"] = row["t_stop"] == before["t_stop"]
            row["ratio_cpu_us"] = row["cpu_us"] / before["cpu_us"]
        for model, row in summary["this"].items():
            if model in ("searched", "panels_wp"):
                continue
            before = summary["vs"][model]
            row["bitwise_equal_to_vs"] = row["final"] == before["final"]
            for key in ("run_watched_wall_us", "run_watched_cpu_us", "loop_watched_cpu_us",
                        "loop_watched_wall_us", "run_default_wall_us", "run_default_cpu_us"):
                if key in row and key in before:
                    row[f"ratio_{key}"] = row[key] / before[key]
    print(json.dumps(summary, indent=1))
    tables, lines = tables_of(summary, loads)
    if args.panels:
        tables.append(panel_table({n: raw[n][0].get("panels_wp") for n in trees},
                                  args.quick))
    for tab in tables:
        print(tab["title"])
        print(" | ".join(tab["columns"]))
        for row in tab["rows"]:
            print(" | ".join(row))
    write("watch_cost", {"title": "What watching the singularity indicators and the chart's "
                                  "edge costs a short run",
                         "summary": lines, "tables": tables, "trees": trees, "spec": spec,
                         "rounds": rounds, "loads": loads, "results": summary, "raw": raw},
          args.out, args.quick)


def panel_table(got, quick):
    """The table of ``--panels`` (each tree's first round)."""
    names = [n for n, g in got.items() if g]
    rows = []
    for c in PANEL_CASES:
        for t in ("0.0001", "1e-06", "1e-08"):
            cells = []
            for n in names:
                e = got[n][c][t]
                ratio = (e["scipy"] / e["jetnh"]) if e["jetnh"] and e["scipy"] else None
                cells += [f"{e['jetnh'] * 1e6:.3g}" if e["jetnh"] else "-",
                          f"{ratio:.1f} ({e['scipy_method']})" if ratio else "-"]
            rows.append([c, t, *cells])
    return dict(title="Work-precision panels (workprecision.panel, "
                      f"{'quick' if quick else 'full'} tolerances): jetnh's fastest adaptive "
                      "method (us) to reach the error, and the fastest scipy method over it",
                columns=["panel", "error", *(f"{n} {k}" for n in names
                                             for k in ("jetnh (us)", "scipy / jetnh"))],
                rows=rows, note="target: scipy / jetnh >= 50 on every panel")


def tables_of(summary, loads):
    """The tables and summary lines of the results (this tree, and ``vs`` where measured:
    wall times, us, the best over the rounds of the 10th percentiles)."""
    names = [n for n in ("this", "vs") if n in summary and "error" not in summary[n]]
    this = summary["this"]
    load = (f"load {min(x for r in loads for x in r[2:]):.1f}-"
            f"{max(x for r in loads for x in r[2:]):.1f}")
    keys = (("loop_watched_wall_us", "loop watched"), ("loop_ignored_wall_us", "loop ignored"),
            ("run_watched_wall_us", "run watched"), ("run_ignored_wall_us", "run ignored"),
            ("run_default_wall_us", "run default"))
    rows, lines = [], []
    for model, row in this.items():
        if model in ("searched", "panels_wp"):
            continue
        cells = [model]
        for key, _ in keys:
            for n in names:
                v = summary[n][model].get(key)
                cells.append(f"{v:.2f}" if v is not None else "-")
            if len(names) == 2 and key in row and key in summary["vs"][model]:
                cells.append(f"{row[key] / summary['vs'][model][key]:.2f}")
            elif len(names) == 2:
                cells.append("-")
        rows.append(cells)
        w = row["loop_watched_wall_us"] - row["loop_ignored_wall_us"]
        text = (f"{model}: the watching loop costs {w:.2f} us over the loop that watches "
                "nothing")
        if len(names) == 2:
            b = summary["vs"][model]
            ratio = row["loop_watched_wall_us"] / b["loop_watched_wall_us"]
            text += (f" ({b['loop_watched_wall_us'] - b['loop_ignored_wall_us']:.2f} us at "
                     f"vs; the watching loop {ratio:.2f}x vs's)")
        if "run_edge_wall_us" in row and row.get("watches_edge"):
            text += (f"; the default run, which watches its chart's edge, "
                     f"{row['run_edge_wall_us']:.2f} us over the run kept in its split")
            if len(names) == 2 and "run_edge_wall_us" in summary["vs"][model]:
                text += f" ({summary['vs'][model]['run_edge_wall_us']:.2f} us at vs)"
        lines.append(text + f" ({load})")
    columns = ["panel"] + [f"{label} {n}" for _, label in keys
                           for n in names + (["this/vs"] if len(names) == 2 else [])]
    return [dict(title="A short run watched and not (dop853, rtol 1e-8, atol 1e-11, "
                       "save='final'; us, wall, the best of the rounds' 10th percentiles; "
                       "loop: the compiled call alone; default: split='switch', which "
                       f"watches the chart's edge where the split has one; {load})",
                 columns=columns, rows=rows)], lines


def argparse_hidden():
    import argparse

    return argparse.SUPPRESS


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    main()
