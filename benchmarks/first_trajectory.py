"""Model to first trajectory on the N-trailer, every principle: where the time goes, and
what compiling huge kernels quickly saves and costs.

    .venv/bin/python benchmarks/first_trajectory.py [--quick] [--ns 8,16,32,64]
        [--principles chetaev,vakonomic,holder,suslov] [--baseline-ns 8,16,32]
        [--timeout 1800] [--out PATH]

(default output: benchmarks/results/first_trajectory.json)

Each (N, principle) runs in a fresh interpreter with an empty kernel cache
(``JETNH_CACHE`` a new directory); the integrator loops are compiled (and cached by numba)
by a warm-up scene before the clock starts, as in a session that has simulated anything
before.  The model is ``models.get("n_trailer", N=N)``, initial state the steadily
turning rig (multipliers 0), t in [0, 1], dop853 with rtol 1e-8, atol 1e-10.  Timed,
wall and CPU seconds (the CPU seconds are what a loaded machine does not inflate):

- ``scene``: the model and the ``Scene`` constructor; ``kernels``: ``scene.kernels``,
  i.e. the derivation (``derive``), the source (``print``) and numba's compilation of the
  kernels with the cache written (``compile``); ``run``: the integration; ``total`` the
  sum.  CPU seconds: ``scene_cpu``, ``kernels_cpu``, ``generate_cpu`` (derivation and
  source), ``compile_cpu``, ``run_cpu``, ``cpu`` (total).
- per kernel (rhs, aux, sing): its straight-line instructions and how it was compiled
  (``quick``: LLVM -O1 passes and -O0 code generation, above the threshold of its kind,
  ``jetnh.numeric.codegen.quick.quick_ops``; ``full``: numba's -O3).

For N in ``--baseline-ns`` the same kernel source is compiled twice more in the same
process, numba's cache off: as generated (``compile_again_cpu``) and with every kernel at
numba's -O3 (``compile_full_cpu``, the route before quick compilation), and one rhs call
is timed both ways (``rhs_ns``, ``rhs_ns_full``: best of rounds of a compiled loop calling
``rhs_c`` by address, as the integrators do).  ``before_seconds_est`` is the measured
total with the compile CPU seconds of the -O3 route in place of the generated route's.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import call_ns, exec_kernels, parser, run_worker, write  # noqa: E402

PRINCIPLES = ("chetaev", "vakonomic", "holder", "suslov")
KERNELS = ("rhs", "aux", "sing")


def _clock():
    return time.perf_counter(), time.process_time()


def _since(start) -> tuple[float, float]:
    w, c = _clock()
    return w - start[0], c - start[1]


def _rhs_ns(cfunc, y0, reps_hint: int) -> float:
    """Nanoseconds per call of ``cfunc`` (an rhs callback) from a compiled loop."""
    return call_ns(cfunc, y0, [], len(y0), reps_hint, rounds=5)


def _compile(source: str, full: bool) -> tuple[float, object]:
    """CPU seconds to compile ``source`` again (numba's cache off), as generated or
    (``full``) with every kernel at numba's -O3, and the module."""
    if full:
        source = re.sub(r"@quick_cfunc\(", "@numba.cfunc(", source)
    tic = time.process_time()
    mod = exec_kernels(source, "jetnh_bench_kernels_" + ("full" if full else "quick"))
    return time.process_time() - tic, mod


def _cpu_spent(module, name: str) -> list:
    """``[CPU seconds]`` spent in ``module.name`` (replaced by a timed wrapper),
    accumulated from now on."""
    spent, run = [0.0], getattr(module, name)

    def timed(*args, **kwargs):
        tic = time.process_time()
        try:
            return run(*args, **kwargs)
        finally:
            spent[0] += time.process_time() - tic

    setattr(module, name, timed)
    return spent


def work(N: int, principle: str, baseline: bool) -> dict:
    from jetnh import models
    from jetnh.numeric import Scene, codegen
    from jetnh.numeric.codegen import multiplier_names
    from jetnh.numeric.kernels import loader

    # numba compiling the kernel modules; derivation and source (derive and print)
    compile_cpu = _cpu_spent(loader, "_exec_kernels")
    generate_cpu = _cpu_spent(codegen, "generate")
    warm = models.get("knife_edge")
    Scene(warm, "chetaev", initial=models.initial("knife_edge"), t_span=(0, 0.1)).run()
    compile_cpu[0] = generate_cpu[0] = 0.0     # the warm-up's kernels are not counted
    start = _clock()
    system = models.get("n_trailer", N=N)
    ini = dict(models.initial("n_trailer", N=N))
    ini.update({m: 0.0 for m in multiplier_names(system, principle)})
    sc = Scene(system, principle, initial=ini, t_span=(0.0, 1.0))
    scene = _since(start)
    t1 = _clock()
    ck = sc.kernels
    kernels = _since(t1)
    t2 = _clock()
    tr = sc.run(method="dop853", rtol=1e-8, atol=1e-10)
    run = _since(t2)
    total = _since(start)
    tm = ck.timings
    out = {"seconds": total[0], "cpu": total[1], "scene": scene[0], "scene_cpu": scene[1],
           "kernels": kernels[0], "kernels_cpu": kernels[1],
           "derive": tm.get("derive"), "print": tm.get("print"), "compile": tm.get("write"),
           "run": run[0], "run_cpu": run[1], "steps": int(len(tr.t)),
           "x_end": float(tr["x"][-1])}
    out["compile_cpu"] = compile_cpu[0]
    out["generate_cpu"] = generate_cpu[0]
    src = ck.source
    for k in KERNELS:
        ops = getattr(ck.kernels, f"_P_{k}", None)
        quick = re.search(rf"@quick_cfunc\([^)]*\)\ndef {k}_c\(", src) is not None
        out[f"{k}_ops"] = len(ops) if ops is not None else None
        out[f"{k}_level"] = "quick" if quick else "full"
    n_ops = out["rhs_ops"] or 1
    reps = max(20, int(2e6 / n_ops))
    y0 = list(sc.y0)
    out["rhs_ns"] = _rhs_ns(ck.rhs_c, y0, reps)
    if baseline:                     # the two routes again, alternately, in this process
        out["compile_again_cpu"], _ = _compile(src, full=False)
        out["compile_full_cpu"], mod = _compile(src, full=True)
        out["rhs_ns_full"] = _rhs_ns(mod.rhs_c, y0, reps)
    return out


def main(argv=None) -> int:
    ap = parser(__doc__, "first_trajectory")
    ap.add_argument("--ns", default="8,16,32,64")
    ap.add_argument("--principles", default=",".join(PRINCIPLES))
    ap.add_argument("--baseline-ns", default="8,16,32",
                    help="N at which the kernels are also compiled at -O3 throughout")
    ap.add_argument("--timeout", type=float, default=1800.0, help="per run (seconds)")
    ap.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        spec = json.loads(args.worker)
        print(json.dumps(work(spec["N"], spec["principle"], spec["baseline"])))
        return 0
    ns = [4] if args.quick else [int(n) for n in args.ns.split(",")]
    base_ns = {4} if args.quick else {int(n) for n in args.baseline_ns.split(",") if n}
    principles = args.principles.split(",")
    rows = []
    for N in ns:
        for p in principles:
            load = os.getloadavg()
            with tempfile.TemporaryDirectory(prefix="jetnh-first-") as tmp:
                env = dict(os.environ, JETNH_CACHE=tmp)
                r = run_worker(__file__, {"N": N, "principle": p, "baseline": N in base_ns},
                               args.timeout, env=env)
            row = {"N": N, "principle": p, "load": round(load[0], 1), **r}
            if "compile_full_cpu" in r:
                row["before_seconds_est"] = (r["seconds"] - r["compile_again_cpu"]
                                             + r["compile_full_cpu"])
                row["compile_ratio"] = r["compile_full_cpu"] / r["compile_again_cpu"]
                row["rhs_cost_ratio"] = r["rhs_ns"] / r["rhs_ns_full"]
            rows.append(row)
            print(json.dumps(row), flush=True)
            write("first_trajectory", summarize(rows), args.out, args.quick)
    return 0


def summarize(rows) -> dict:
    ok = [r for r in rows if "seconds" in r]
    summary = []
    for r in ok:
        line = (f"N = {r['N']} {r['principle']}: {r['seconds']:.1f} s wall, "
                f"{r['cpu']:.1f} CPU s (derivation {r['derive']:.1f} s wall; compilation "
                f"{r['compile_cpu']:.1f} CPU s, {r['rhs_level']} rhs; run {r['run']:.2f} s "
                f"wall) at load {r['load']}")
        if "compile_full_cpu" in r:
            line += (f"; compiled again: {r['compile_again_cpu']:.2f} CPU s as generated, "
                     f"{r['compile_full_cpu']:.2f} at -O3 throughout "
                     f"({r['compile_ratio']:.1f}x), rhs call {r['rhs_ns']:.0f} ns against "
                     f"{r['rhs_ns_full']:.0f} ns ({r['rhs_cost_ratio']:.2f}x)")
        summary.append(line)
    columns = ["N", "principle", "load", "seconds", "cpu", "scene", "scene_cpu", "derive",
               "print", "generate_cpu", "compile_cpu", "compile_again_cpu",
               "compile_full_cpu", "run", "rhs_ops", "rhs_level", "aux_ops", "aux_level",
               "sing_ops", "sing_level", "rhs_ns", "rhs_ns_full", "before_seconds_est"]
    return {"title": "Model to first trajectory (N-trailer, every principle, empty kernel "
                     "cache): quick compilation of huge kernels",
            "summary": summary, "columns": columns, "rows": rows}


if __name__ == "__main__":
    sys.exit(main())
