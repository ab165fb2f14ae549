"""The first run on a fresh machine: what compiling the integrator loops costs.

Each measurement is a new interpreter with an empty numba cache (``NUMBA_CACHE_DIR`` a
new temporary directory) and an empty jetnh cache (``JETNH_CACHE`` another one: its
kernels and its integrator loops, ``kernels.loop_cache``).  After the imports it builds
the rolling disk (Chetaev) and times its first run with the method asked for, then the
first run of each further method in the same process (what a user who tries another
method pays), then a second run of each (the warm cost, for scale).  The figures are
wall and CPU seconds after the imports; the loops' share is the first run's time less
the warm run's.

Two profiles: ``cold``, nothing compiled ahead (every loop is compiled by its first
run: a user who skipped the install step); ``installed``, the install step ``jetnh cache
warm`` run first in the fresh caches (what ``make`` does once; its wall time is
``install_s``), then the same first runs, which load their loops.

    .venv/bin/python benchmarks/first_run.py [--quick] [--out PATH] [--methods M,...]
        [--profiles cold,installed]

(default output: benchmarks/results/first_run.json).  ``--quick``: one start per method
and profile, and in ``installed`` only the default method followed by the others
(default: the best of two, and every method alone too).  The machine's load is
recorded with the figures.
"""

import time

_T0 = time.perf_counter()

import json  # noqa: E402
import os  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402

from _common import parser, run_worker, write  # noqa: E402

DEFAULT = "dop853"
FURTHER = ("dopri5", "rk4", "radau")


def worker(spec: dict) -> dict:
    """In this fresh process: the import time, then per method its first and second run
    (wall and CPU seconds), the first method first."""
    import jetnh.models as models
    from jetnh.numeric import Scene

    t_imports = time.perf_counter() - _T0
    out = {"import_s": t_imports, "methods": {}}
    w0, c0 = time.perf_counter(), time.process_time()
    scene = Scene(models.get("rolling_disk"), "chetaev", initial=models.initial("rolling_disk"),
                  t_span=(0.0, 1.0)).compile()
    out["scene_s"] = time.perf_counter() - w0
    out["scene_cpu_s"] = time.process_time() - c0
    for m in spec["methods"]:
        kw = dict(n_steps=10) if m == "rk4" else {}
        w0, c0 = time.perf_counter(), time.process_time()
        scene.run(method=m, save="final", **kw)
        first = (time.perf_counter() - w0, time.process_time() - c0)
        w0 = time.perf_counter()
        scene.run(method=m, save="final", **kw)
        out["methods"][m] = dict(first_s=first[0], first_cpu_s=first[1],
                                 warm_s=time.perf_counter() - w0)
    out["total_after_imports_s"] = time.perf_counter() - _T0 - t_imports
    return out


def fresh_start(methods, installed: bool) -> dict:
    with tempfile.TemporaryDirectory() as nb, tempfile.TemporaryDirectory() as kc:
        env = {**os.environ, "NUMBA_CACHE_DIR": nb, "JETNH_CACHE": kc}
        install_s = None
        if installed:
            tic = time.perf_counter()
            done = subprocess.run([sys.executable, "-m", "jetnh", "--quiet", "cache", "warm"],
                                  env=env, capture_output=True, text=True, timeout=900)
            install_s = time.perf_counter() - tic
            if done.returncode != 0:
                return {"error": done.stderr[-2000:]}
        r = run_worker(__file__, {"methods": list(methods)}, timeout=600, env=env)
        if install_s is not None:
            r["install_s"] = install_s
        return r


def main():
    ap = parser(__doc__, "first_run")
    ap.add_argument("--methods", default=",".join((DEFAULT,) + FURTHER),
                    help="the first is the default method; the others follow it")
    ap.add_argument("--profiles", default="cold,installed",
                    help="cold (nothing compiled ahead), installed (jetnh cache warm first)")
    ap.add_argument("--worker")
    args = ap.parse_args()
    if args.worker:
        print(json.dumps(worker(json.loads(args.worker))))
        return
    methods = args.methods.split(",")
    reps = 1 if args.quick else 2
    starts = {}
    # every method first in a process of its own, and the default followed by the others
    orders = [methods] + [[m] for m in methods[1:]]
    runs = [(profile, order) for profile in args.profiles.split(",") for order in
            (orders[:1] if args.quick and profile == "installed" else orders)]
    for _ in range(reps):
        for profile, order in runs:
            r = fresh_start(order, profile == "installed")
            if "error" in r:
                print(profile, order, r, file=sys.stderr)
                continue
            key = f"{profile}: " + " then ".join(order)
            if (key not in starts or r["total_after_imports_s"]
                    < starts[key]["total_after_imports_s"]):
                starts[key] = r
    rows = []
    for key, r in starts.items():
        for i, (m, v) in enumerate(r["methods"].items()):
            rows.append(dict(order=key, method=m, position=i, first_s=v["first_s"],
                             first_cpu_s=v["first_cpu_s"], warm_s=v["warm_s"]))
            print(f"{key:47s} {m:7s} {'first' if i == 0 else 'further':8s} "
                  f"wall {v['first_s']:6.2f} s  cpu {v['first_cpu_s']:6.2f} s  "
                  f"(warm run {v['warm_s'] * 1e3:.2f} ms)")
        extra = f", install step {r['install_s']:.1f} s" if "install_s" in r else ""
        print(f"{key:47s} imports {r['import_s']:.2f} s, scene {r['scene_s']:.2f} s{extra}")
    print("load", os.getloadavg())
    write("first_run", dict(starts=starts, rows=rows), args.out, args.quick)


if __name__ == "__main__":
    main()
