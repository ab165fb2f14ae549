"""Compilation of the N-trailer's kernels against their size: CPU seconds per kernel
module against the straight-line instructions (the shared size: each distinct node of
the kernels' graphs is one instruction), the fitted exponent, the cost of an rhs call,
and the kernels' values -- optionally against another tree measured in the same run.

    .venv/bin/python benchmarks/compile_scaling.py [--quick] [--ns 3,4,8,16,24,32,48,64]
        [--principles vakonomic,chetaev] [--vs /path/to/other/tree] [--timeout 900]
        [--out PATH]

(default output: benchmarks/results/compile_scaling.json)

Each (N, principle, tree) runs in a fresh interpreter (``PYTHONPATH`` the tree): the
kernel source of ``models.get("n_trailer", N=N)`` is generated (not timed; numba warmed
up on the N = 1 kernels first), then compiled from that source with numba's cache off,
as the loader compiles a new entry; timed in CPU seconds (``compile_cpu``, and per
kernel: ``rhs_cpu``, ...; ``rhs_route``: "quick" or "full", numba's -O3).  Then one call
of each kernel from a compiled loop (best of rounds: ``rhs_ns``, ``aux_ns``,
``sing_ns``), and rhs, aux and sing at five random states near the initial state (kept
for comparing the trees bit for bit).  With ``--vs`` the other tree is measured right
after each row of this one, at the same load; ``--quick``: N = 3, 4, 8.
``exponent``: the least-squares slope of log compile CPU against log instructions over
N >= 4, for the module and for each kernel kind.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import (call_ns, exec_kernels, n_trailer_source, parser,  # noqa: E402
                     run_worker, write)

KERNELS = ("rhs", "aux", "sing")


def _exec(source: str, name: str, spent: dict):
    """The module of ``source`` compiled with numba's cache off; CPU seconds per kernel
    into ``spent`` (the callback decorators timed)."""
    import numba

    from jetnh.numeric.codegen import quick

    def timed(make):
        def decorator(*args, **kwargs):
            wrap = make(*args, **kwargs)

            def timed_wrap(func):
                tic = time.process_time()
                try:
                    return wrap(func)
                finally:
                    spent[func.__name__] = time.process_time() - tic
            return timed_wrap
        return decorator

    cfunc, qcfunc = numba.cfunc, quick.quick_cfunc
    numba.cfunc, quick.quick_cfunc = timed(cfunc), timed(qcfunc)
    try:
        return exec_kernels(source, name)
    finally:
        numba.cfunc, quick.quick_cfunc = cfunc, qcfunc


def work(N: int, principle: str) -> dict:
    import numpy as np

    import jetnh
    from jetnh.numeric.kernels.calls import Kernel
    from jetnh.numeric.methods._common import FunctionAddress

    warm, _ = n_trailer_source(1, principle)
    _exec(warm.source, "jetnh_scaling_warm", {})
    tic = time.process_time()
    ks, y0 = n_trailer_source(N, principle)
    generate = time.process_time() - tic
    source, lay = ks.source, ks.layout
    spent: dict = {}
    tic = time.process_time()
    mod = _exec(source, "jetnh_scaling_kernels", spent)
    compile_cpu = time.process_time() - tic
    out = {"tree": os.path.dirname(os.path.dirname(os.path.abspath(jetnh.__file__))),
           "generate_cpu": generate, "compile_cpu": compile_cpu, "chars": len(source)}
    y, p = np.array(y0, dtype=float), np.zeros(len(lay.runtime_params))
    sizes = {"rhs": len(y), "aux": lay.n_aux, "sing": len(lay.indicators)}
    total = 0
    for k in KERNELS:
        ops = getattr(mod, f"_P_{k}", None)
        out[f"{k}_ops"] = len(ops) if ops is not None else None
        out[f"{k}_cpu"] = spent.get(f"{k}_c")
        out[f"{k}_route"] = ("quick" if re.search(rf"@quick_cfunc\([^)]*\)\ndef {k}_c\(",
                                                  source) else "full")
        total += len(ops) if ops is not None else 0
        reps = max(20, int(2e6 / max(len(ops) if ops is not None else 1, 1)))
        out[f"{k}_ns"] = call_ns(getattr(mod, f"{k}_c"), y, p, sizes[k], reps)
    out["ops"] = total
    rng = np.random.default_rng(0)
    states = [y + 0.1 * rng.uniform(-1.0, 1.0, len(y)) for _ in range(5)]
    values = {}
    for k in KERNELS:
        kernel = Kernel(FunctionAddress(getattr(mod, f"{k}_c")), (len(y), len(p), sizes[k]))
        rows = []
        for yy in states:
            buf = np.zeros(sizes[k])
            kernel(0.25, yy, p, buf)
            rows.append(buf.tolist())
        values[k] = rows
    out["values"] = values
    return out


def fit(rows, key="compile_cpu", ops="ops") -> float | None:
    """Least-squares slope of log ``key`` against log ``ops`` (rows with N >= 4)."""
    pts = [(math.log(r[ops]), math.log(r[key])) for r in rows
           if r.get(key) and r.get(ops) and r["N"] >= 4]
    if len(pts) < 2:
        return None
    mx = sum(x for x, _ in pts) / len(pts)
    my = sum(y for _, y in pts) / len(pts)
    sxx = sum((x - mx) ** 2 for x, _ in pts)
    return sum((x - mx) * (y - my) for x, y in pts) / sxx if sxx else None


def _compare(a: dict, b: dict) -> dict:
    """Largest relative difference of the kernels' values between two rows, and whether
    they are equal bit for bit (NaN equal to NaN)."""
    import numpy as np

    worst, equal = 0.0, True
    for k, rows in a.get("values", {}).items():
        x, y = np.array(rows), np.array(b.get("values", {}).get(k, []))
        if x.shape != y.shape:
            return {"bitwise_equal": False, "max_rel_diff": None}
        same = (x == y) | (np.isnan(x) & np.isnan(y))
        equal &= bool(same.all())
        d = np.abs(x - y)[~same]
        if d.size:
            worst = max(worst, float(np.max(d / np.maximum(np.abs(x[~same]), 1e-300))))
    return {"bitwise_equal": equal, "max_rel_diff": worst}


def main(argv=None) -> int:
    ap = parser(__doc__, "compile_scaling")
    ap.add_argument("--ns", default="3,4,8,16,24,32,48,64")
    ap.add_argument("--principles", default="vakonomic,chetaev")
    ap.add_argument("--vs", default=None, help="another tree, measured in the same run")
    ap.add_argument("--timeout", type=float, default=900.0, help="per run (seconds)")
    ap.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        spec = json.loads(args.worker)
        print(json.dumps(work(spec["N"], spec["principle"])))
        return 0
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    trees = [("this", here)] + ([("vs", os.path.abspath(args.vs))] if args.vs else [])
    ns = [3, 4, 8] if args.quick else [int(n) for n in args.ns.split(",")]
    rows = []
    for N in ns:
        for principle in args.principles.split(","):
            pair = {}
            for label, tree in trees:
                load = os.getloadavg()[0]
                env = dict(os.environ, PYTHONPATH=tree)
                r = run_worker(__file__, {"N": N, "principle": principle}, args.timeout,
                               env=env)
                row = {"N": N, "principle": principle, "tree": label, "load": round(load, 1),
                       **{k: v for k, v in r.items() if k != "tree"}}
                pair[label] = row
                rows.append(row)
                print(json.dumps({k: v for k, v in row.items() if k != "values"}),
                      flush=True)
            if "vs" in pair and "values" in pair["this"] and "values" in pair["vs"]:
                pair["this"].update(_compare(pair["vs"], pair["this"]))
    for r in rows:
        r.pop("values", None)
    summary = []
    for label, tree in trees:
        mine = [r for r in rows if r["tree"] == label and "compile_cpu" in r]
        for principle in args.principles.split(","):
            sel = [r for r in mine if r["principle"] == principle]
            e = fit(sel)
            if e is not None:
                kinds = ", ".join(f"{k} ^{fit(sel, f'{k}_cpu', f'{k}_ops'):.2f}"
                                  for k in KERNELS)
                summary.append(f"{label} ({tree}), {principle}: compile CPU ~ "
                               f"instructions^{e:.2f} over N >= 4 (per kernel: {kinds})")
        for r in mine:
            kinds = "; ".join(f"{k} {r[f'{k}_ops']} {r[f'{k}_route']} {r[f'{k}_cpu']:.2f} s "
                              f"{r[f'{k}_ns']:.0f} ns" for k in KERNELS)
            line = (f"{label}: N = {r['N']} {r['principle']}: {r['ops']} instructions, "
                    f"compile {r['compile_cpu']:.2f} CPU s ({kinds}) (load {r['load']})")
            if "bitwise_equal" in r:
                line += (f"; kernels' values against vs: bitwise equal "
                         f"{r['bitwise_equal']}, largest relative difference "
                         f"{r['max_rel_diff']:.1e}")
            summary.append(line)
    print("\n".join(summary))
    write("compile_scaling", {
        "title": "Compilation of the N-trailer's kernels against their size (straight-line "
                 "instructions), and the cost of an rhs call",
        "summary": summary,
        "columns": ["N", "principle", "tree", "load", "ops", "rhs_ops", "aux_ops",
                    "sing_ops", "compile_cpu", "rhs_cpu", "aux_cpu", "sing_cpu", "rhs_route",
                    "aux_route", "sing_route", "rhs_ns", "aux_ns", "sing_ns",
                    "bitwise_equal", "max_rel_diff"],
        "rows": rows}, args.out, args.quick)
    return 0


if __name__ == "__main__":
    sys.exit(main())
