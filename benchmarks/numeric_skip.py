"""Cold and warm start, and what each way a scene skips work it does not need saves,
measured in one run on one machine (ratios are taken within this run):

1. cold and warm, each in a new process: derive + generate + compile + first run with no
   kernels in the cache ($JETNH_CACHE in a temporary directory holding only the compiled
   integrator loops: a new model), with the loops not compiled either (the first use on
   a machine), and with every kernel in the cache;
   against the researcher's route (derive, ``sympy.lambdify``, first ``solve_ivp``), and
   the number of runs after which jetnh's cold start has paid for itself;
2. derive only the principle asked for, against all four (fresh System each time);
3. numeric parameters substituted before code generation, against run-time parameters
   (the cost of one right-hand-side call and of a run);
4. output: save="final" against every accepted step against t_eval points;
5. the cost of what a run adds: the singularity checks and a user event.

    .venv/bin/python benchmarks/numeric_skip.py [--quick] [--out PATH]

(default output: benchmarks/results/numeric_skip.json).  Wall times are the best of
several interleaved repetitions (``_common.best_of``).
"""

import time

_T0 = time.perf_counter()             # a worker's imports count towards its start-up

import argparse  # noqa: E402
import json  # noqa: E402
import os  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import shutil  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
import sympy as sp  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

from _common import best, best_of, parser, write  # noqa: E402
from numeric_speed import rhs_driver  # noqa: E402
from workprecision import Case, researcher_rhs, scene_of  # noqa: E402

import jetnh.models as models  # noqa: E402
from jetnh.mechanics.system import PRINCIPLES  # noqa: E402
from jetnh.numeric import Event, Scene  # noqa: E402

COLD_CASES = (Case("rolling_disk", "vakonomic", 100.0),
              Case("n_trailer", "vakonomic", 0.5, options={"N": 3}, multipliers=0.01))


# ---------------------------------------------------------------------- 1. cold and warm
def worker(spec: dict) -> dict:
    """One start in this (new) process: the times of its phases (imports: this module's,
    the same for both routes)."""
    t0, t1 = _T0, time.perf_counter()
    case = Case(**spec["case"])
    scene = scene_of(case)
    T, kw = case.t_end, dict(rtol=1e-10, atol=1e-13)
    if spec["route"] == "jetnh":
        k = scene.kernels
        extra = dict(cache_hit=k.hit, timings=k.timings)

        def go():
            return scene.run(save="final", **kw)
    else:
        f = researcher_rhs(scene)
        extra = {}

        def go():
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return solve_ivp(f, (0.0, T), scene.y0, method="DOP853", t_eval=[T], **kw)
    t2 = time.perf_counter()
    go()
    t3 = time.perf_counter()
    next_run, _ = best(go, 3)
    return dict(import_s=t1 - t0, prepare_s=t2 - t1, first_run_s=t3 - t2, total_s=t3 - t0,
                work_s=t3 - t1, next_run_s=next_run, **extra)


def start(spec: dict, env: dict) -> dict:
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", json.dumps(spec)]
    r = subprocess.run(cmd, env={**os.environ, **env}, capture_output=True, text=True,
                       check=True)
    return json.loads(r.stdout.strip().splitlines()[-1])


def seed_loops(warm: str, cold: str) -> None:
    """Give the empty kernel cache ``cold`` the integrator loops of ``warm`` (its key,
    marker and ``loops/``, no kernels): the store keeps the loops beside the kernels,
    whatever NUMBA_CACHE_DIR says, so an empty store alone would be the machine's
    first use, not a new model's."""
    for root in Path(warm).glob("v*"):
        dest = Path(cold) / root.name
        dest.mkdir(mode=0o700)
        for name in (".jetnh-kernel-cache", "hmac.key"):
            shutil.copy2(root / name, dest / name)
        shutil.copytree(root / "loops", dest / "loops")


def cold_warm(case: Case, reps: int, machine_cold: bool) -> dict:
    """Best of ``reps`` interleaved starts of each kind (fresh temporary caches for the
    cold ones).  Ratios compare the work after the imports (``work_s``: prepare and
    first run), since both routes import the same modules."""
    spec = dict(case=dict(model=case.model, principle=case.principle, t_end=case.t_end,
                          options=case.options, multipliers=case.multipliers))
    best_runs = {}
    with tempfile.TemporaryDirectory() as warm_dir:
        start({**spec, "route": "jetnh"}, {"JETNH_CACHE": warm_dir})       # fill it
        for rep in range(reps):
            with tempfile.TemporaryDirectory() as k1, tempfile.TemporaryDirectory() as k2, \
                    tempfile.TemporaryDirectory() as nb:
                seed_loops(warm_dir, k1)
                kinds = {"kernels cold": ("jetnh", {"JETNH_CACHE": k1}),
                         "warm": ("jetnh", {"JETNH_CACHE": warm_dir}),
                         "lambdify + solve_ivp": ("lambdify", {})}
                if machine_cold and rep == 0:              # one is enough: ~30 s
                    kinds["machine cold"] = ("jetnh", {"JETNH_CACHE": k2, "NUMBA_CACHE_DIR": nb})
                for label, (route, env) in kinds.items():
                    r = start({**spec, "route": route}, env)
                    if label not in best_runs or r["work_s"] < best_runs[label]["work_s"]:
                        best_runs[label] = r
    cold, warm, lam = (best_runs[k] for k in ("kernels cold", "warm", "lambdify + solve_ivp"))
    gain = lam["next_run_s"] - warm["next_run_s"]
    out = dict(problem=case.label, t_end=case.t_end, runs=best_runs,
               cold_over_warm=cold["work_s"] / warm["work_s"],
               lambdify_over_warm=lam["work_s"] / warm["work_s"],
               lambdify_over_cold=lam["work_s"] / cold["work_s"],
               run_speedup=lam["next_run_s"] / warm["next_run_s"],
               runs_to_pay_off_cold=(max(0.0, (cold["work_s"] - lam["work_s"]) / gain)
                                     if gain > 0 else None))
    for k, v in best_runs.items():
        print(f"start {case.label:32s} {k:21s}: after imports {v['work_s']:6.2f} s (import "
              f"{v['import_s']:.2f}, prepare {v['prepare_s']:.2f}, first run "
              f"{v['first_run_s']:.3f}, next run {v['next_run_s'] * 1e3:.2f} ms)")
    return out


# ---------------------------------------------------------------------- 2. derivation
DERIVE = ("rolling_disk", "appell_hamel", "rolling_ball")


def derive_one_vs_all(reps):
    """A fresh System and an empty sympy cache for every derivation."""
    from sympy.core.cache import clear_cache

    rows = []
    for name in DERIVE:
        def one(name=name):
            clear_cache()
            models.get(name).equations("chetaev").accelerations()

        def all_four(name=name):
            clear_cache()
            s = models.get(name)
            for p in PRINCIPLES:
                s.equations(p).accelerations()
        (t1, _), (t4, _) = best_of([one, all_four], reps)
        rows.append(dict(system=name, chetaev_only_s=t1, all_four_s=t4, ratio=t4 / t1))
        print(f"derive {name:14s}: chetaev only {t1:7.3f} s, all four {t4:7.3f} s "
              f"({t4 / t1:.1f}x)")
    return rows


# ---------------------------------------------------------------------- 3. parameters
def rhs_ns(kern, y, p, n_calls):
    drive = rhs_driver()
    drive(kern.rhs_fp, y.copy(), p, 10)
    t, _ = best(lambda: drive(kern.rhs_fp, y.copy(), p, n_calls), 3)
    return t / n_calls * 1e9


def params_compiled_vs_runtime(reps, n_calls):
    rows = []
    for name, principle, T in (("rolling_disk", "chetaev", 100.0),
                               ("rolling_disk", "vakonomic", 100.0),
                               ("rolling_ball", "chetaev", 20.0)):
        base = scene_of(Case(name, principle, T))
        out, scenes = {}, {}
        for label, rt in (("compiled", ()), ("runtime", tuple(base.params))):
            tic = time.perf_counter()
            sc = base.replace(runtime_params=rt, cache=False).compile()
            build = time.perf_counter() - tic
            src = (sc.kernels.directory / "kernels.py").read_text()
            body = src[src.index("def rhs_c("):src.index("def aux_c(")]
            scenes[label] = sc
            out[label] = dict(build_s=build, rhs_lines=body.count("\n"))
        runs = best_of([lambda sc=sc: sc.run(rtol=1e-10, atol=1e-12, save="final")
                        for sc in scenes.values()], reps)
        for (label, sc), (t_run, tr) in zip(scenes.items(), runs):
            out[label].update(run_s=t_run, nfev=tr.diagnostics.rhs_evaluations,
                              final=tr.y[-1])
        for _ in range(2):           # interleaved, best of two
            for label, sc in scenes.items():
                v = rhs_ns(sc.kernels, sc.y0, sc.p, n_calls)
                out[label]["rhs_ns"] = min(out[label].get("rhs_ns", np.inf), v)
        c, r = out["compiled"], out["runtime"]
        same = bool(np.allclose(c.pop("final"), r.pop("final"), rtol=1e-12, atol=1e-12))
        row = dict(system=name, principle=principle, compiled=c, runtime=r,
                   rhs_ratio=r["rhs_ns"] / c["rhs_ns"], run_ratio=r["run_s"] / c["run_s"],
                   same_result=same)
        rows.append(row)
        print(f"params {name:14s} {principle:9s}: rhs {c['rhs_ns']:6.1f} ns compiled vs "
              f"{r['rhs_ns']:6.1f} ns runtime ({row['rhs_ratio']:.2f}x); run "
              f"{c['run_s'] * 1e3:.3f} vs {r['run_s'] * 1e3:.3f} ms ({row['run_ratio']:.2f}x); "
              f"rhs lines {c['rhs_lines']} vs {r['rhs_lines']}")
    return rows


# ---------------------------------------------------------------------- 4. output
def output_modes(reps):
    T = 2000.0
    sc = scene_of(Case("rolling_disk", "chetaev", T)).compile()
    modes = [("final", dict(save="final")), ("every step", dict(save="steps")),
             ("t_eval 100", dict(t_eval=np.linspace(0, T, 100))),
             ("t_eval 10000", dict(t_eval=np.linspace(0, T, 10_000)))]
    rows = []
    runs = best_of([lambda kw=kw: sc.run(rtol=1e-10, atol=1e-12, **kw) for _, kw in modes],
                   reps)
    for (label, _), (t, tr) in zip(modes, runs):
        rows.append(dict(mode=label, run_s=t, rows=len(tr), bytes=tr.y.nbytes + tr.t.nbytes,
                         steps=tr.diagnostics.steps, nfev=tr.diagnostics.rhs_evaluations))
    for r in rows:
        r["ratio_to_final"] = r["run_s"] / rows[0]["run_s"]
        print(f"output {r['mode']:13s}: {r['run_s'] * 1e3:8.3f} ms ({r['ratio_to_final']:.2f}x), "
              f"{r['rows']} rows, {r['bytes'] / 1024:.1f} KiB, nfev {r['nfev']}")
    return dict(problem=f"rolling_disk / chetaev, t in [0, {T:g}], rtol 1e-10", rows=rows)


# ---------------------------------------------------------------------- 5. checks
def checks_cost(reps):
    """Singularity checks and a user event: run time with and without."""
    rows = []
    ah = Scene(models.get("appell_hamel"), "chetaev",
               initial=dict(x=0, y=0, z=0, x_t=300.0, y_t=400.0), t_span=(0.0, 100.0),
               cache=False).compile()
    disk = scene_of(Case("rolling_disk", "vakonomic", 200.0)).replace(cache=False).compile()
    psi = disk.system.J.q[3]
    ev = [Event(sp.sin(psi), name="sin psi")]
    disk.run(events=ev, save="final")
    for name, sc in (("appell_hamel / chetaev, no stop in span", ah),
                     ("rolling_disk / vakonomic", disk)):
        fs = [lambda sc=sc: sc.run(rtol=1e-10, atol=1e-12, save="final"),
              lambda sc=sc: sc.run(rtol=1e-10, atol=1e-12, save="final", singular="ignore")]
        if sc is disk:
            fs.append(lambda: sc.run(rtol=1e-10, atol=1e-12, save="final", events=ev))
        res = best_of(fs, reps)
        (t_on, a), (t_off, b) = res[:2]
        row = dict(problem=name, indicators=list(sc.kernels.layout.indicators),
                   checks_s=t_on, no_checks_s=t_off, ratio=t_on / t_off,
                   same_result=bool(np.array_equal(a.y, b.y)))
        if sc is disk:
            t_ev, c = res[2]
            row.update(event_s=t_ev, event_ratio=t_ev / t_on,
                       event_count=len(c.t_events[0]))
        rows.append(row)
        print(f"checks {name:42s}: {t_on * 1e3:.3f} ms with, {t_off * 1e3:.3f} ms without "
              f"({row['ratio']:.2f}x)" + (f"; + event sin(psi): {row['event_s'] * 1e3:.3f} ms "
                                          f"({row['event_ratio']:.2f}x, {row['event_count']} "
                                          "events)" if "event_s" in row else ""))
    return rows


def main(argv=None):
    ap = parser(__doc__, "numeric_skip")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        print(json.dumps(worker(json.loads(args.worker))))
        return
    reps = 3 if args.quick else 15
    cases = COLD_CASES[:1] if args.quick else COLD_CASES
    write("numeric_skip", dict(
        cold_warm=[cold_warm(c, 1 if args.quick else 2, not args.quick and i == 0)
                   for i, c in enumerate(cases)],
        derive_one_vs_all=derive_one_vs_all(2 if args.quick else 5),
        params_compiled_vs_runtime=params_compiled_vs_runtime(
            reps, 200_000 if args.quick else 1_000_000),
        output_modes=output_modes(reps),
        checks=checks_cost(reps)), args.out, args.quick)


if __name__ == "__main__":
    main()
