"""Stiff nonholonomic systems: jetnh's radau against scipy's Radau, BDF, LSODA and dop853.

    .venv/bin/python benchmarks/stiff.py --before PATH [--quick] [--cost-only] [--out PATH]

(default output: benchmarks/results/stiff.json)

1. Stiffness family: the Chaplygin sleigh with its centre of mass a distance a ahead of
   the blade, m = 1, I = a^2 / 4, from v0 = 0.5, w0 = 1: the turning rate decays at
   lambda = m a V / (I + m a^2) (V the speed the sleigh ends with), so a -> 0 makes it
   stiff (a = 1 .. 1e-4: lambda from about 1 to 4000).  Every method runs on the
   same compiled right-hand side (scipy's through ``method="scipy-<M>"``) to T = 5 at
   rtol = 1e-4 .. 1e-10 (atol = 1e-3 rtol); the error is the largest deviation of
   theta, theta_t and the forward speed at T from the closed form (the catalogue's
   docstring).  "Speed-up at equal error": scipy's time interpolated (log-log, over its
   tolerances) at radau's error, divided by radau's time.
2. The refactor of the explicit methods into one loop (``integrators.loop``), before
   (the hand-written per-method loops of commit a6430f6, a worktree at ``--before PATH``)
   and after (this tree), each in a fresh process with empty numba and kernel caches,
   two alternating pairs of processes (``--cost-only``: this part alone, the family kept
   from the output file): the first run of dop853, dopri5 and rk4 (their loops
   compiled), the fixed cost of a run (T = 1e-6, ``save="final"``) and the cost per rhs
   evaluation (T = 100 minus the fixed cost) of each method on the rolling disk (rk4:
   2000 steps).

Wall times are best of several repetitions (``_common.best``); ratios are within this run.
"""

import json
import math
import os
import subprocess
import sys
import tempfile
import warnings

import numpy as np

from _common import ROOT, best, parser, write

FAMILY = (1.0, 0.1, 0.01, 1e-3, 1e-4)
METHODS = ("radau", "scipy-Radau", "scipy-BDF", "scipy-LSODA", "dop853")
V0, W0, T_END = 0.5, 1.0, 5.0


def sleigh_exact(m, I, a, t):
    """v, w, theta at t (theta0 = 0): the catalogue's closed form."""
    K = I + m * a * a
    V = math.sqrt((m * V0**2 + K * W0**2) / m)
    s0 = math.atanh(V0 / V)
    s = m * a * V * t / K + s0
    sech = 2 * math.exp(-s) / (1 + math.exp(-2 * s))
    gd = lambda u: 2 * math.atan(math.tanh(u / 2))  # noqa: E731
    return (V * math.tanh(s), W0 * math.cosh(s0) * sech,
            W0 * math.cosh(s0) * K / (m * a * V) * (gd(s) - gd(s0)), m * a * V / K)


def family_case(a, tols, reps):
    from jetnh.models import chaplygin_sleigh
    from jetnh.numeric import Scene

    m, I = 1.0, a * a / 4
    sc = Scene(chaplygin_sleigh(), "chetaev", params=dict(m=m, I=I, a=a),
               initial=dict(x=0.0, y=0.0, theta=0.0, x_t=V0, theta_t=W0),
               t_span=(0.0, T_END)).compile()
    v, w, th, lam = sleigh_exact(m, I, a, T_END)
    rows = []
    for method in METHODS:
        for rtol in tols:
            def go():
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    return sc.run(method=method, rtol=rtol, atol=1e-3 * rtol, save="final",
                                  max_steps=2_000_000)
            tr = go()
            budget = 1.0 if method.startswith("scipy") else 3.0
            t, tr = best(go, reps, budget=budget)
            ct, st = math.cos(tr["theta"][-1]), math.sin(tr["theta"][-1])
            speed = tr["x_t"][-1] * ct + tr["y_t"][-1] * st
            err = max(abs(tr["theta"][-1] - th), abs(tr["theta_t"][-1] - w), abs(speed - v))
            d = tr.diagnostics
            rows.append(dict(a=a, stiffness=lam, method=method, rtol=rtol, status=int(d.status),
                             steps=d.steps, nfev=d.rhs_evaluations, seconds=t, error=err))
            print(f"a = {a:g} (lambda {lam:.3g}) {method:12s} rtol {rtol:.0e}: "
                  f"{t * 1e3:8.3f} ms, {d.rhs_evaluations:7d} evals, error {err:.2e}")
    return rows


def speedup(rows, method, against="radau"):
    """Per stiffness: median over radau's points of (method's time at radau's error) /
    (radau's time), interpolating the method's log time over log error."""
    out = {}
    for lam in sorted({r["stiffness"] for r in rows}):
        ours = [r for r in rows if r["stiffness"] == lam and r["method"] == against]
        theirs = sorted((r for r in rows if r["stiffness"] == lam and r["method"] == method),
                        key=lambda r: r["error"])
        le = np.log([max(r["error"], 1e-300) for r in theirs])
        lt = np.log([r["seconds"] for r in theirs])
        ratios = []
        for r in ours:
            e = math.log(max(r["error"], 1e-300))
            if le.size >= 2 and le[0] <= e <= le[-1]:
                ratios.append(math.exp(np.interp(e, le, lt)) / r["seconds"])
        out[lam] = float(np.median(ratios)) if ratios else None
    return out


COST = r"""
import json, time, numpy as np
import jetnh.models as models
from jetnh.numeric import Scene
sc = Scene(models.get("rolling_disk"), "chetaev", initial=models.initial("rolling_disk"),
           t_span=(0.0, 10.0)).compile()
out = {}
for m, kw in (("dop853", {}), ("dopri5", {}), ("rk4", {"n_steps": 100})):
    tic = time.perf_counter()
    sc.run(method=m, save="final", **kw)
    out["first_" + m] = time.perf_counter() - tic
def best(f, n):
    b = 1e9
    for _ in range(n):
        tic = time.perf_counter(); f(); b = min(b, time.perf_counter() - tic)
    return b
for m in ("dop853", "dopri5", "rk4"):
    kw = dict(rtol=1e-9, atol=1e-12) if m != "rk4" else {}
    short = lambda: sc.run(method=m, t_span=(0.0, 1e-6), save="final",
                           **(kw or {"n_steps": 1}))
    long = lambda: sc.run(method=m, t_span=(0.0, 100.0), save="final",
                          **(kw or {"n_steps": 2000}))
    n0 = short().diagnostics.rhs_evaluations
    n1 = long().diagnostics.rhs_evaluations
    fs, gs = [], []
    for _ in range(3):
        fs.append(best(short, REPS_SHORT))
        gs.append(best(long, REPS_LONG))
    out["fixed_s_" + m] = min(fs)
    out["per_eval_s_" + m] = (min(gs) - min(fs)) / (n1 - n0)
print(json.dumps(out))
"""


def cost(root, reps_short, reps_long):
    """The COST script in a fresh process on the tree ``root`` with empty caches."""
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, PYTHONPATH=str(root), JETNH_CACHE=os.path.join(tmp, "jc"),
                   NUMBA_CACHE_DIR=os.path.join(tmp, "numba"))
        code = COST.replace("REPS_SHORT", str(reps_short)).replace("REPS_LONG", str(reps_long))
        res = subprocess.run([sys.executable, "-c", code], env=env, cwd=tmp,
                             capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def costs(before_root, after_root, rounds, reps_short, reps_long):
    """``cost`` of both trees in ``rounds`` alternating pairs of fresh processes (so that a
    change of the machine's load hits both alike); the best of each figure."""
    runs = {"before": [], "after": []}
    for _ in range(rounds):
        runs["before"].append(cost(before_root, reps_short, reps_long))
        runs["after"].append(cost(after_root, reps_short, reps_long))
    return tuple({k: min(r[k] for r in rs) for k in rs[0]} for rs in runs.values())


def main(argv=None):
    ap = parser(__doc__, "stiff")
    ap.add_argument("--before", required=True,
                    help="the tree of the per-method loops (git worktree add PATH a6430f6)")
    ap.add_argument("--cost-only", action="store_true",
                    help="measure only the explicit loop before/after; keep the stiffness "
                         "family of the existing output file")
    args = ap.parse_args(argv)
    quick = args.quick
    family = FAMILY[::2] if quick else FAMILY
    tols = (1e-4, 1e-7) if quick else (1e-4, 1e-6, 1e-8, 1e-10)
    reps = 2 if quick else 5
    if args.cost_only:
        old = json.loads(args.out.read_text())
        rows = old["rows"]
        speed = {m: {float(k): v for k, v in d.items()} for m, d in old["speedup"].items()}
    else:
        rows = []
        for a in family:
            rows += family_case(a, tols, reps)
        speed = {m: speedup(rows, m) for m in METHODS if m != "radau"}
    reps_short, reps_long = (50, 3) if quick else (2000, 7)
    before, after = costs(args.before, ROOT, 1 if quick else 2, reps_short, reps_long)
    stiff = max(r["stiffness"] for r in rows)
    summary = [
        "radau against scipy's Radau on the same compiled rhs at equal error: "
        + ", ".join(f"{speed['scipy-Radau'][lam]:.0f}x at lambda = {lam:.2g}"
                    for lam in sorted(speed["scipy-Radau"]) if speed["scipy-Radau"][lam]),
        f"against BDF at lambda = {stiff:.2g}: {speed['scipy-BDF'][stiff] or float('nan'):.0f}x,"
        f" LSODA: {speed['scipy-LSODA'][stiff] or float('nan'):.0f}x, dop853: "
        f"{speed['dop853'][stiff] or float('nan'):.1f}x",
        f"one compiled loop for dop853, dopri5 and rk4: first runs (loops compiled, fresh "
        f"caches) {sum(before[f'first_{m}'] for m in ('dop853', 'dopri5', 'rk4')):.1f} s "
        f"before, {sum(after[f'first_{m}'] for m in ('dop853', 'dopri5', 'rk4')):.1f} s after",
        "after / before: " + "; ".join(
            f"{m} fixed cost {after['fixed_s_' + m] / before['fixed_s_' + m]:.2f}, per "
            f"evaluation {after['per_eval_s_' + m] / before['per_eval_s_' + m]:.2f}"
            for m in ("dop853", "dopri5", "rk4")),
    ]
    for s in summary:
        print(s)
    tables = [
        dict(title="Speed-up of radau at equal error (time of the other method / radau's)",
             columns=["stiffness lambda"] + [m for m in METHODS if m != "radau"],
             rows=[[f"{lam:.3g}"] + [("-" if speed[m][lam] is None else f"{speed[m][lam]:.3g}")
                                    for m in METHODS if m != "radau"]
                   for lam in sorted(speed["scipy-Radau"])],
             note="median over radau's tolerances; '-' where the other method's errors do "
                  "not bracket radau's"),
        dict(title="The explicit methods' loop before and after the refactor (rolling "
                   "disk, fresh process, empty caches)",
             columns=["", "before", "after", "after / before"],
             rows=[[k, f"{before[k]:.4g}", f"{after[k]:.4g}", f"{after[k] / before[k]:.2f}"]
                   for k in ("first_dop853", "first_dopri5", "first_rk4", "fixed_s_dop853",
                             "per_eval_s_dop853", "fixed_s_dopri5", "per_eval_s_dopri5",
                             "fixed_s_rk4", "per_eval_s_rk4")],
             note="first_*: seconds of the first run of each method (its loop compiled); "
                  "fixed_s: a run to T = 1e-6; per_eval_s: (run to T = 100 - fixed) / "
                  "evaluations (rk4: 2000 steps)"),
    ]
    write("stiff", dict(summary=summary, columns=["stiffness", "method", "rtol", "status",
                                                  "steps", "nfev", "seconds", "error"],
                        rows=rows, tables=tables, speedup=speed, before=before, after=after),
          args.out, quick)


if __name__ == "__main__":
    main()
