"""Stiff nonholonomic systems: jetnh's radau against scipy's Radau, BDF, LSODA and dop853.

    .venv/bin/python benchmarks/stiff.py [--quick] [--out PATH]

(default output: benchmarks/results/stiff.json)

The stiffness family: the Chaplygin sleigh with its centre of mass a distance a ahead of
the blade, m = 1, I = a^2 / 4, from v0 = 0.5, w0 = 1: the turning rate decays at lambda =
m a V / (I + m a^2) (V the speed the sleigh ends with), so a -> 0 makes it stiff (a = 1
.. 1e-4: lambda from about 1 to 4000). Every method runs on the same compiled right-hand
side (scipy's through ``method="scipy-<M>"``) to T = 5 at rtol = 1e-4 .. 1e-10 (atol =
1e-3 rtol; dop853 stops with status STIFF where Hairer's stiffness test fires, and such
runs count in no speed-up); the error is the largest deviation of theta, theta_t and the
forward speed at T from the closed form (the catalogue's docstring). "Speed-up at equal
error": scipy's time interpolated (log-log, over its tolerances) at radau's error, divided
by radau's time.

(The first run, the fixed cost and the cost per evaluation of a run, before and after
the one compiled loop of the explicit methods: ``benchmarks/overhead.py``.)

Wall times are best of several repetitions (``_common.best``); ratios are within this run.
"""

import math
import warnings

import numpy as np

from _common import best, parser, write

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
        theirs = sorted((r for r in rows if r["stiffness"] == lam and r["method"] == method
                         and r["status"] == 0), key=lambda r: r["error"])
        le = np.log([max(r["error"], 1e-300) for r in theirs])
        lt = np.log([r["seconds"] for r in theirs])
        ratios = []
        for r in ours:
            e = math.log(max(r["error"], 1e-300))
            if le.size >= 2 and le[0] <= e <= le[-1]:
                ratios.append(math.exp(np.interp(e, le, lt)) / r["seconds"])
        out[lam] = float(np.median(ratios)) if ratios else None
    return out


def main(argv=None):
    ap = parser(__doc__, "stiff")
    args = ap.parse_args(argv)
    quick = args.quick
    family = FAMILY[::2] if quick else FAMILY
    tols = (1e-4, 1e-7) if quick else (1e-4, 1e-6, 1e-8, 1e-10)
    reps = 2 if quick else 5
    rows = []
    for a in family:
        rows += family_case(a, tols, reps)
    speed = {m: speedup(rows, m) for m in METHODS if m != "radau"}
    stiff = max(r["stiffness"] for r in rows)
    stopped = [r for r in rows if r["method"] == "dop853" and r["stiffness"] == stiff
               and r["status"] != 0]
    summary = [
        "radau against scipy's Radau on the same compiled rhs at equal error: "
        + ", ".join(f"{speed['scipy-Radau'][lam]:.0f}x at lambda = {lam:.2g}"
                    for lam in sorted(speed["scipy-Radau"]) if speed["scipy-Radau"][lam]),
        f"against BDF at lambda = {stiff:.2g}: {speed['scipy-BDF'][stiff] or float('nan'):.0f}x,"
        f" LSODA: {speed['scipy-LSODA'][stiff] or float('nan'):.0f}x, dop853: "
        + (f"stops as stiff after {max(r['steps'] for r in stopped)} steps (status "
           f"{stopped[0]['status']})" if stopped else
           f"{speed['dop853'][stiff] or float('nan'):.1f}x"),
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
    ]
    write("stiff", dict(summary=summary, columns=["stiffness", "method", "rtol", "status",
                                                  "steps", "nfev", "seconds", "error"],
                        rows=rows, tables=tables, speedup=speed),
          args.out, quick)


if __name__ == "__main__":
    main()
