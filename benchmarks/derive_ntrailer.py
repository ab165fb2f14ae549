"""Derivation speed on the N-trailer family: jetnh (all four principles) against
sympy.physics.mechanics.LagrangesMethod (Chetaev / Lagrange-d'Alembert), N = 1..16.

    .venv/bin/python benchmarks/derive_ntrailer.py [--max-n 16] [--lm-budget 60]
        [--lm-timeout 900] [--jetnh-timeout 900] [--also-patched] [--out PATH]

(default output: benchmarks/results/derive_ntrailer.json)

The model is the standard kinematic car pulling N trailers with on-axle hitches
(Murray and Sastry, "Nonholonomic motion planning: steering using sinusoids", IEEE TAC 38
(1993) 700-716, sec. V; Sordalen, "Conversion of the kinematics of a car with n trailers
into a chained form", ICRA 1993; Bloch, "Nonholonomic Mechanics and Control" (2003),
sec. 1.x): coordinates (x, y) of the car's rear axle, heading th0 of the car and th1..thN
of the trailers, hitch lengths d.  Axle i sits at
    x_i = x - d sum_{j<=i} cos th_j,   y_i = y - d sum_{j<=i} sin th_j
and rolls without slipping sideways (a knife edge per body):
    x_i' sin th_i - y_i' cos th_i = x' sin th_i - y' cos th_i + d sum_{j<=i} cos(th_i - th_j) th_j' = 0,
i = 0..N: N + 1 affine constraints on N + 3 coordinates.  Lagrangian: a point mass m at
each axle plus a rotational inertia I per body, L = sum_i m/2 (x_i'^2 + y_i'^2) + I/2 th_i'^2
with m = 1, I = 1/3, d = 1 (exact rationals).  Split: dependent y, th1..thN (the trailer
constraints have the constant coefficient d on th_i').

Measured (each in a fresh interpreter, so that sympy's cache does not carry over):
- jetnh: time from ``System(...)`` to ``equations(p).accelerations()`` for each principle;
- LagrangesMethod: time from ``LagrangesMethod(...)`` through ``form_lagranges_equations()``
  and ``rhs()`` (the model is converted to dynamicsymbols before the clock starts);
- expression size: ``count_ops`` of the accelerations after ``cse`` (replacements plus
  reduced expressions); for jetnh the q'' and multiplier rates, for LagrangesMethod the q''
  rows of rhs(); measured in a separate run after the timing (``--size-timeout``), since
  for LagrangesMethod it takes far longer than the derivation itself.
LagrangesMethod is run for increasing N until one run takes longer than ``--lm-budget``
seconds (or hits ``--lm-timeout``); N = 8 is always attempted so that the target ratio
can be stated.  ``--also-patched`` adds jetnh runs with the proposed fix (linear algebra
under ``dotprodsimp(False)``) applied by monkeypatching, to show its effect.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import time

PRINCIPLES = ("chetaev", "vakonomic", "holder", "suslov")


# ---------------------------------------------------------------------- the model
def ntrailer(N: int):
    """(J, L, constraints, dependent) of the car with N trailers."""
    import sympy as sp

    from jetnh import JetSpace

    names = ["x", "y"] + [f"th{i}" for i in range(N + 1)]
    J = JetSpace(names)
    x, y, *th = J.q
    xd, yd, *thd = J.qd
    m, I, d = sp.Integer(1), sp.Rational(1, 3), sp.Integer(1)
    L = sp.S.Zero
    vx, vy = xd, yd
    for i in range(N + 1):
        if i:
            vx = vx + d * sp.sin(th[i]) * thd[i]
            vy = vy - d * sp.cos(th[i]) * thd[i]
        L += m * (vx**2 + vy**2) / 2 + I * thd[i] ** 2 / 2
    constraints = [xd * sp.sin(th[i]) - yd * sp.cos(th[i])
                   + sum((d * sp.cos(th[i] - th[j]) * thd[j] for j in range(1, i + 1)), sp.S.Zero)
                   for i in range(N + 1)]
    dependent = [y] + th[1:]
    return J, L, constraints, dependent


def cse_size(exprs) -> int:
    import sympy as sp

    repl, red = sp.cse(list(exprs))
    return int(sum(sp.count_ops(e) for _, e in repl) + sum(sp.count_ops(e) for e in red))


def _patch_dotprodsimp():
    """The proposed fix: jetnh.linalg.solve and equations._solve without dotprodsimp."""
    import functools

    from sympy.matrices.utilities import dotprodsimp

    import jetnh.equations as eq
    import jetnh.linalg as la

    def off(f):
        @functools.wraps(f)
        def g(*a, **k):
            with dotprodsimp(False):
                return f(*a, **k)
        return g
    la.solve = off(la.solve)
    eq._solve = off(eq._solve)


# ---------------------------------------------------------------------- workers
def work_jetnh(N: int, principle: str, patched: bool, sizes: bool) -> dict:
    if patched:
        _patch_dotprodsimp()
    from jetnh.constraints import System

    J, L, cons, dep = ntrailer(N)
    tic = time.perf_counter()
    system = System(J, L, cons, dependent=dep)
    acc = system.equations(principle).accelerations()
    seconds = time.perf_counter() - tic
    out = {"seconds": seconds, "outputs": len(acc)}
    if sizes:
        tic = time.perf_counter()
        out["cse_count_ops"] = cse_size(acc[a] for a in sorted(acc, key=str))
        out["cse_seconds"] = time.perf_counter() - tic
    return out


def work_lagranges(N: int, sizes: bool) -> dict:
    from sympy.physics.mechanics import LagrangesMethod

    J, L, cons, dep = ntrailer(N)
    Ld = J.to_dynamic(L)
    qs = [J.to_dynamic(q) for q in J.q]
    nh = [J.to_dynamic(f) for f in cons]
    tic = time.perf_counter()
    lm = LagrangesMethod(Ld, qs, nonhol_coneqs=nh)
    lm.form_lagranges_equations()
    rhs = lm.rhs()
    seconds = time.perf_counter() - tic
    n = J.n
    out = {"seconds": seconds, "outputs": rhs.rows}
    if sizes:
        tic = time.perf_counter()
        out["cse_count_ops"] = cse_size(rhs[n:2 * n])
        out["cse_seconds"] = time.perf_counter() - tic
    return out


def measure(spec: dict, timeout: float, sizes: bool, size_timeout: float) -> dict:
    """The timing run, then (separately, so that a slow ``cse`` cannot hide the timing)
    the size run; each in a fresh interpreter."""
    r = run_worker({**spec, "sizes": False}, timeout)
    if sizes and "seconds" in r:
        s = run_worker({**spec, "sizes": True}, size_timeout)
        if "cse_count_ops" in s:
            r["cse_count_ops"], r["cse_seconds"] = s["cse_count_ops"], s["cse_seconds"]
        else:
            r["cse_count_ops"] = None
            r["size_note"] = ("cse/count_ops ran out of time" if s.get("timeout")
                              else "cse/count_ops failed")
    return r


def run_worker(spec: dict, timeout: float) -> dict:
    """Run one measurement in a fresh interpreter; {"timeout": True} when it runs out."""
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", json.dumps(spec)]
    tic = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"timeout": True, "seconds_lower_bound": timeout}
    if proc.returncode != 0:
        return {"error": proc.stderr.strip().splitlines()[-1:] or ["?"],
                "wall": time.perf_counter() - tic}
    return json.loads(proc.stdout.strip().splitlines()[-1])


# ---------------------------------------------------------------------- driver
def machine() -> dict:
    import sympy

    return {"platform": platform.platform(), "processor": platform.processor(),
            "cpus": os.cpu_count(), "python": platform.python_version(),
            "sympy": sympy.__version__, "loadavg": list(os.getloadavg())}


def fmt(r):
    if not r:
        return "-"
    if r.get("timeout"):
        return f">{r['seconds_lower_bound']:.0f}"
    if "error" in r:
        return "error"
    return f"{r['seconds']:.2f}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--max-n", type=int, default=16)
    ap.add_argument("--ns", type=str, default=None, help="comma-separated N values")
    ap.add_argument("--lm-budget", type=float, default=60.0)
    ap.add_argument("--lm-timeout", type=float, default=900.0)
    ap.add_argument("--jetnh-timeout", type=float, default=900.0)
    ap.add_argument("--also-patched", action="store_true")
    ap.add_argument("--principles", default=",".join(PRINCIPLES),
                    help="comma-separated subset of " + ",".join(PRINCIPLES))
    ap.add_argument("--variants", default=None,
                    help="comma-separated subset of asis,patched (default: asis, plus "
                         "patched with --also-patched)")
    ap.add_argument("--no-lm", action="store_true", help="skip LagrangesMethod")
    ap.add_argument("--no-sizes", action="store_true")
    ap.add_argument("--size-timeout", type=float, default=300.0,
                    help="time-out of the separate cse/count_ops run")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                   "results", "derive_ntrailer.json"))
    ap.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)

    if args.worker:
        spec = json.loads(args.worker)
        if spec["kind"] == "jetnh":
            res = work_jetnh(spec["N"], spec["principle"], spec["patched"], spec["sizes"])
        else:
            res = work_lagranges(spec["N"], spec["sizes"])
        print(json.dumps(res))
        return 0

    ns = ([int(s) for s in args.ns.split(",")] if args.ns else list(range(1, args.max_n + 1)))
    sizes = not args.no_sizes
    if args.variants:
        variants = [{"asis": False, "patched": True}[v] for v in args.variants.split(",")]
    else:
        variants = [False, True] if args.also_patched else [False]
    principles = tuple(args.principles.split(","))
    rows = []
    lm_stopped = False
    jetnh_stopped = {(p, v): False for p in PRINCIPLES for v in variants}
    result = {"benchmark": "derive_ntrailer",
              "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
              "command": " ".join([os.path.relpath(sys.executable)] + sys.argv),
              "machine": machine(),
              "model": "car with N on-axle trailers (Murray-Sastry 1993), m=1, I=1/3, d=1; "
                       "dependent y, th1..thN",
              "lm_budget_s": args.lm_budget, "rows": rows}
    print(f"{'N':>3} {'n':>3} {'k':>3} | " + " ".join(f"{p:>10}" for p in PRINCIPLES)
          + f" | {'LM':>8} | ratio(chetaev)", flush=True)
    for N in ns:
        row = {"N": N, "n": N + 3, "k": N + 1, "jetnh": {}, "jetnh_patched": {}}
        for patched in variants:
            key = "jetnh_patched" if patched else "jetnh"
            for p in principles:
                if jetnh_stopped[(p, patched)]:
                    continue
                r = measure({"kind": "jetnh", "N": N, "principle": p, "patched": patched},
                            args.jetnh_timeout, sizes, args.size_timeout)
                row[key][p] = r
                if r.get("timeout") or "error" in r:
                    jetnh_stopped[(p, patched)] = True
        for key in ("jetnh", "jetnh_patched"):
            if not row[key]:
                del row[key]
        if not args.no_lm and (not lm_stopped or N == 8):
            r = measure({"kind": "lm", "N": N}, args.lm_timeout, sizes, args.size_timeout)
            row["lagranges_method"] = r
            if r.get("timeout") or "error" in r or r["seconds"] > args.lm_budget:
                lm_stopped = True
        lm = row.get("lagranges_method")
        ch = row.get("jetnh", {}).get("chetaev")
        if lm and ch and "seconds" in ch and ("seconds" in lm or lm.get("timeout")):
            lm_s = lm.get("seconds", lm.get("seconds_lower_bound"))
            row["speedup_chetaev"] = lm_s / ch["seconds"]
            row["speedup_is_lower_bound"] = bool(lm.get("timeout"))
        rows.append(row)
        ratio = row.get("speedup_chetaev")
        print(f"{N:>3} {N + 3:>3} {N + 1:>3} | "
              + " ".join(f"{fmt(row.get('jetnh', {}).get(p)):>10}" for p in PRINCIPLES)
              + f" | {fmt(lm):>8} | " + (f"{ratio:.1f}x" if ratio else "-"), flush=True)
        if "jetnh_patched" in row:
            print("    patched | " + " ".join(f"{fmt(row['jetnh_patched'].get(p)):>10}"
                                             for p in PRINCIPLES), flush=True)
        os.makedirs(os.path.dirname(args.out), exist_ok=True)
        with open(args.out, "w") as fh:
            json.dump(result, fh, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
