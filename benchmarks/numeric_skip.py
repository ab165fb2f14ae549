"""What each "skip what a scene doesn't need" option of jetnh.numeric saves, measured in
one run on one machine (ratios are taken within this run):

1. derive only the principle asked for, against all four (fresh System each time);
2. numeric parameters substituted before code generation, against run-time parameters
   (the cost of one right-hand-side call and of a run);
3. output: save="final" against every accepted step against t_eval points;
4. the disk cache of compiled kernels, cold against warm, each in a new process (and the
   integrator loops' own numba cache cold, i.e. the first use on a machine);
5. the cost of what a run adds: the singularity checks and a user event.

    .venv/bin/python benchmarks/numeric_skip.py [--quick] [--out PATH]

(default output: benchmarks/results/numeric_skip.json).  Wall times are the best of
several repetitions; machine, date, load average and command are in the JSON.
"""

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
import time

import numba
import numpy as np
import scipy
import sympy as sp

import jetnh as jn
from jetnh.constraints import PRINCIPLES, System
from jetnh.numeric import Event, Scene


def best(f, reps):
    out, t = None, float("inf")
    for _ in range(reps):
        tic = time.perf_counter()
        out = f()
        t = min(t, time.perf_counter() - tic)
    return t, out


def best_of(fs, reps):
    """Best wall time of each function, the calls interleaved (so that a change in the
    machine's load hits every variant alike); returns [(time, last result), ...]."""
    times = [float("inf")] * len(fs)
    outs = [None] * len(fs)
    for _ in range(reps):
        for i, f in enumerate(fs):
            tic = time.perf_counter()
            outs[i] = f()
            times[i] = min(times[i], time.perf_counter() - tic)
    return list(zip(times, outs))


# ---------------------------------------------------------------------- systems
def disk_system():
    J = jn.JetSpace("x y phi psi")
    x, y, phi, psi = J.q
    xd, yd, phid, psid = J.qd
    R, I1, I2 = sp.symbols("R I1 I2")
    L = (xd**2 + yd**2) / 2 + (I1 * phid**2 + I2 * psid**2) / 2
    return System(J, L, [xd - R * sp.cos(psi) * phid, yd - R * sp.sin(psi) * phid],
                  dependent=[x, y])


DISK_PARAMS = {"R": 1.5, "I1": 0.5, "I2": 0.25}
DISK0 = dict(x=0.1, y=-0.2, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7)


def appell_hamel_system():
    from jetnh.models import appell_hamel
    return appell_hamel()


def ball_system():
    """A ball of radius r rolling on a plane (Euler angles; Neimark & Fufaev): a heavier
    symbolic load than the disk."""
    J = jn.JetSpace("x y th ph ps")
    x, y, th, ph, ps = J.q
    xd, yd, thd, phd, psd = J.qd
    m, I, r = sp.symbols("m I r")
    wx = thd * sp.cos(ps) + phd * sp.sin(th) * sp.sin(ps)
    wy = thd * sp.sin(ps) - phd * sp.sin(th) * sp.cos(ps)
    wz = phd * sp.cos(th) + psd
    L = m * (xd**2 + yd**2) / 2 + I * (wx**2 + wy**2 + wz**2) / 2
    return System(J, L, [xd - r * wy, yd + r * wx], dependent=[x, y])


SYSTEMS = {"vertical rolling disk": disk_system,
           "Appell-Hamel": appell_hamel_system,
           "rolling ball (Euler angles)": ball_system}


# ---------------------------------------------------------------------- 1. derivation
def derive_one_vs_all(reps):
    """A fresh System and an empty sympy cache for every derivation."""
    from sympy.core.cache import clear_cache

    rows = []
    for name, make in SYSTEMS.items():
        def one(make=make):
            clear_cache()
            make().equations("chetaev").accelerations()

        def all_four(make=make):
            clear_cache()
            s = make()
            for p in PRINCIPLES:
                s.equations(p).accelerations()
        (t1, _), (t4, _) = best_of([one, all_four], reps)
        rows.append(dict(system=name, chetaev_only_s=t1, all_four_s=t4, ratio=t4 / t1))
        print(f"derive {name:30s}: chetaev only {t1:7.3f} s, all four {t4:7.3f} s "
              f"({t4 / t1:.1f}x)")
    return rows


# ---------------------------------------------------------------------- 2. parameters
def rhs_ns(kern, y, p, n_calls):
    from jetnh.numeric.integrators._common import RHS, f8, i8

    @numba.njit((RHS, f8[::1], f8[::1], i8))
    def drive(rhs, y, p, n):
        out = np.empty(y.shape[0])
        acc = 0.0
        for i in range(n):
            y[0] = 0.1 + 1e-12 * i
            rhs(0.0, y, p, out)
            acc += out[-1]
        return acc

    drive(kern.rhs, y.copy(), p, 10)
    t, _ = best(lambda: drive(kern.rhs, y.copy(), p, n_calls), 3)
    return t / n_calls * 1e9


def params_compiled_vs_runtime(reps, n_calls):
    rows = []
    cases = [("vertical rolling disk", "chetaev", disk_system, DISK_PARAMS, DISK0, 100.0),
             ("vertical rolling disk", "vakonomic", disk_system, DISK_PARAMS,
              dict(DISK0, lambda_x=0.1, lambda_y=-0.2), 100.0),
             ("rolling ball (Euler angles)", "chetaev", ball_system,
              {"m": 1.0, "I": 0.4, "r": 1.0},
              dict(x=0, y=0, th=0.7, ph=0.1, ps=0.2, th_t=0.3, ph_t=1.0, ps_t=-0.5), 200.0)]
    for name, principle, make, params, ini, T in cases:
        s = make()
        out, scenes = {}, {}
        for label, rt in (("compiled", ()), ("runtime", tuple(params))):
            tic = time.perf_counter()
            sc = Scene(s, principle, params=params, initial=ini, t_span=(0.0, T),
                       runtime_params=rt, cache=False).compile()
            build = time.perf_counter() - tic
            src = (sc.kernels.directory / "kernels.py").read_text()
            body = src[src.index("def rhs("):src.index("def aux(")]
            scenes[label] = sc
            out[label] = dict(build_s=build, rhs_lines=body.count("\n"))
        runs = best_of([lambda sc=sc: sc.run(rtol=1e-10, atol=1e-12, save="final")
                        for sc in scenes.values()], reps)
        for (label, sc), (t_run, tr) in zip(scenes.items(), runs):
            out[label].update(run_s=t_run, nfev=tr.diagnostics.rhs_evaluations,
                              final_x=float(tr.y[-1, 0]))
        for _ in range(2):           # interleaved, best of two
            for label, sc in scenes.items():
                v = rhs_ns(sc.kernels, sc.y0, sc.p, n_calls)
                out[label]["rhs_ns"] = min(out[label].get("rhs_ns", np.inf), v)
        c, r = out["compiled"], out["runtime"]
        row = dict(system=name, principle=principle, compiled=c, runtime=r,
                   rhs_ratio=r["rhs_ns"] / c["rhs_ns"], run_ratio=r["run_s"] / c["run_s"],
                   same_result=abs(c["final_x"] - r["final_x"])
                   <= 1e-12 * max(1, abs(c["final_x"])))
        rows.append(row)
        print(f"params {name:28s} {principle:9s}: rhs {c['rhs_ns']:6.1f} ns compiled vs "
              f"{r['rhs_ns']:6.1f} ns runtime ({row['rhs_ratio']:.2f}x); run "
              f"{c['run_s'] * 1e3:.3f} vs {r['run_s'] * 1e3:.3f} ms ({row['run_ratio']:.2f}x); "
              "rhs lines "
              f"{c['rhs_lines']} vs {r['rhs_lines']}")
    return rows


# ---------------------------------------------------------------------- 3. output
def output_modes(reps):
    s = disk_system()
    T = 2000.0
    sc = Scene(s, "chetaev", params=DISK_PARAMS, initial=DISK0, t_span=(0.0, T),
               cache=False).compile()
    modes = [("final", dict(save="final")), ("every step", dict(save="steps")),
             ("t_eval 100", dict(t_eval=np.linspace(0, T, 100))),
             ("t_eval 10000", dict(t_eval=np.linspace(0, T, 10_000)))]
    rows = []
    runs = best_of([lambda kw=kw: sc.run(rtol=1e-10, atol=1e-12, **kw) for _, kw in modes],
                   reps)
    for (label, _), (t, tr) in zip(modes, runs):
        rows.append(dict(mode=label, run_s=t, rows=len(tr), bytes=tr.y.nbytes + tr.t.nbytes,
                         steps=tr.diagnostics.steps, nfev=tr.diagnostics.rhs_evaluations))
    base = rows[0]["run_s"]
    for r in rows:
        r["ratio_to_final"] = r["run_s"] / base
        print(f"output {r['mode']:13s}: {r['run_s'] * 1e3:8.3f} ms ({r['ratio_to_final']:.2f}x), "
              f"{r['rows']} rows, {r['bytes'] / 1024:.1f} KiB, nfev {r['nfev']}")
    return dict(problem=f"vertical rolling disk, t in [0, {T}], rtol 1e-10", rows=rows)


# ---------------------------------------------------------------------- 4. disk cache
COLD = r"""
import time, json
t0 = time.perf_counter()
import sympy as sp, jetnh as jn
from jetnh.constraints import System
from jetnh.numeric import Scene
J = jn.JetSpace("x y phi psi"); x, y, phi, psi = J.q; xd, yd, phid, psid = J.qd
R, I1, I2 = sp.symbols("R I1 I2")
s = System(J, (xd**2 + yd**2)/2 + (I1*phid**2 + I2*psid**2)/2,
           [xd - R*sp.cos(psi)*phid, yd - R*sp.sin(psi)*phid], dependent=[x, y])
t1 = time.perf_counter()
sc = Scene(s, "vakonomic", params={R: 1.5, I1: 0.5, I2: 0.25},
           initial=dict(x=0, y=0, phi=0, psi=0, phi_t=1, psi_t=0.7, lambda_x=0.1,
                        lambda_y=-0.2), t_span=(0, 100))
k = sc.kernels
t2 = time.perf_counter()
tr = sc.run(rtol=1e-10, atol=1e-13, save="final")
t3 = time.perf_counter()
print(json.dumps(dict(import_s=t1 - t0, kernels_s=t2 - t1, first_run_s=t3 - t2,
                      total_s=t3 - t0, cache_hit=k.hit, timings=k.timings)))
"""


def disk_cache():
    runs = {}
    with tempfile.TemporaryDirectory() as kernels, tempfile.TemporaryDirectory() as nb:
        env = dict(os.environ, JETNH_CACHE=kernels)

        def run(label, extra_env):
            r = subprocess.run([sys.executable, "-c", COLD], env={**env, **extra_env},
                               capture_output=True, text=True, check=True)
            runs[label] = json.loads(r.stdout.strip().splitlines()[-1])

        # first use on a machine: no kernels, no compiled integrator loops
        run("machine cold", {"NUMBA_CACHE_DIR": nb})
        shutil_rm(kernels)
        # kernels cold, integrator loops cached
        run("kernels cold", {})
        run("warm", {})
    for k, v in runs.items():
        print(f"disk cache {k:13s}: total {v['total_s']:6.2f} s (import {v['import_s']:.2f}, "
              f"kernels {v['kernels_s']:.2f}, first run {v['first_run_s']:.3f}; hit "
              f"{v['cache_hit']})")
    cold, warm = runs["kernels cold"], runs["warm"]
    return dict(runs=runs, kernels_saved_s=cold["kernels_s"] - warm["kernels_s"],
                kernels_ratio=cold["kernels_s"] / warm["kernels_s"],
                total_ratio=cold["total_s"] / warm["total_s"],
                machine_cold_total_s=runs["machine cold"]["total_s"])


def shutil_rm(path):
    import shutil

    for entry in os.listdir(path):
        shutil.rmtree(os.path.join(path, entry), ignore_errors=True)


# ---------------------------------------------------------------------- 5. checks
def checks_cost(reps):
    """Singularity checks and a user event: run time with and without."""
    from jetnh.models import appell_hamel

    rows = []
    ah = Scene(appell_hamel(), "chetaev", initial=dict(x=0, y=0, z=0, x_t=300.0, y_t=400.0),
               t_span=(0.0, 100.0), cache=False).compile()
    s = disk_system()
    disk = Scene(s, "vakonomic", params=DISK_PARAMS,
                 initial=dict(DISK0, lambda_x=0.1, lambda_y=-0.2), t_span=(0.0, 200.0),
                 cache=False).compile()
    psi = s.J.q[3]
    ev = [Event(sp.sin(psi), name="sin psi")]
    disk.run(events=ev, save="final")
    for name, sc in (("Appell-Hamel (1 indicator), no stop in span", ah),
                     ("disk vakonomic (1 indicator)", disk)):
        fs = [lambda: sc.run(rtol=1e-10, atol=1e-12, save="final"),
              lambda: sc.run(rtol=1e-10, atol=1e-12, save="final", singular="ignore")]
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
        print(f"checks {name:45s}: {t_on * 1e3:.3f} ms with, {t_off * 1e3:.3f} ms without "
              f"({row['ratio']:.2f}x)" + (f"; + event sin(psi): {row['event_s'] * 1e3:.3f} ms "
                                          f"({row['event_ratio']:.2f}x, {row['event_count']} "
                                          "events)" if "event_s" in row else ""))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer repetitions")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "results",
                                                  "numeric_skip.json"))
    args = ap.parse_args()
    reps = 5 if args.quick else 21
    results = dict(
        benchmark="numeric_skip",
        date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        command=" ".join([os.path.relpath(sys.executable)] + sys.argv),
        machine=dict(platform=platform.platform(), processor=platform.processor(),
                     cpus=os.cpu_count(), python=platform.python_version(),
                     numba=numba.__version__, scipy=scipy.__version__,
                     numpy=np.__version__, sympy=sp.__version__,
                     loadavg_start=os.getloadavg()))
    results["derive_one_vs_all"] = derive_one_vs_all(3 if args.quick else 5)
    results["params_compiled_vs_runtime"] = params_compiled_vs_runtime(
        reps, 200_000 if args.quick else 1_000_000)
    results["output_modes"] = output_modes(reps)
    results["checks"] = checks_cost(reps)
    results["disk_cache"] = disk_cache()
    results["machine"]["loadavg_end"] = os.getloadavg()
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w") as fh:
        json.dump(results, fh, indent=2)
    print("wrote", args.out)


if __name__ == "__main__":
    main()
