"""Extreme parameter ratios (1e-6 .. 1e6) and stiff regimes: the error of every method as
a ratio goes to its extremes, and where the explicit methods stop being usable (against
scipy's implicit Radau, BDF and LSODA on the same compiled right-hand side).

    .venv/bin/python benchmarks/stress_ratios.py [--quick] [--out PATH]

Families (one compiled scene each: the ratio is a runtime parameter):

- scale: the vertical rolling disk with wheel radius R = 1e-6 .. 1e6 (closed form);
  relative error of the displacement, with atol fixed (1e-12) and with atol scaled by R;
- inertia: the Chaplygin sleigh with I / (m a^2) = 1e-6 .. 1e6 (closed form);
- frequency: the nonholonomic oscillator with spring constant k = 1e-6 .. 1e6 on x
  (reference: dop853 at rtol 1e-13); cost grows like sqrt(k);
- stiff: the Chaplygin sleigh with I = m a^2 and a = 1 .. 1e-6: the turning rate decays
  at the rate lambda = m a V / (I + m a^2) = V / (2a), and the straight motion it decays
  to is stiff for explicit methods (lambda T up to ~1e6).
Output: benchmarks/results/stress_ratios.json, stress_ratios_error.png (error against the
ratio), stress_ratios_stiff.png (steps and error against lambda T).
"""

import time

import numpy as np
import sympy as sp

from _common import parser, write
from stress_common import OSC0, fmt, oscillator, pyplot, save

from jetnh import models
from jetnh.errors import JetnhError
from jetnh.numeric import Scene

TOL = dict(rtol=1e-10, atol=1e-12)
VERBOSE = False
BUDGET = 10.0
SPENT = {}


def attempt(scene, method, p, **kw):
    """(trajectory or None, wall time, note); a method whose run took more than BUDGET
    seconds is not run again for the rest of its family (``SPENT``)."""
    key = (id(scene), method, tuple(sorted((k, str(v)) for k, v in kw.items())))
    if SPENT.get(key, 0.0) > BUDGET:
        return None, 0.0, f"skipped: a smaller ratio took {SPENT[key]:.0f} s"
    tic = time.perf_counter()
    try:
        tr = scene.run(method=method, params=p, **kw)
    except JetnhError as e:
        tr, note = None, str(e).split(";")[0][:160]
    else:
        note = tr.stop_reason
    wall = time.perf_counter() - tic
    SPENT[key] = wall
    if VERBOSE:
        print(f"  {method} {p} {wall:.2f}s {note[:60]}", flush=True)
    return tr, wall, note


def label(method, kw):
    extra = ", atol=1e-12 R" if kw.get("scaled") else ""
    return method + extra


def scale_family(values, n_fixed):
    s = models.get("rolling_disk")
    ini = dict(x=0.0, y=0.0, phi=0.3, psi=0.4, phi_t=1.0, psi_t=0.7)
    T = 10.0
    scene = Scene(s, "chetaev", params=dict(R=1.0, I1=0.5, I2=0.25), initial=ini,
                  t_span=(0.0, T), runtime_params=["R"])
    rows = []
    for R in values:
        p = np.array([R])
        psi = 0.4 + 0.7 * T
        dx = R / 0.7 * (np.sin(psi) - np.sin(0.4))
        dy = -R / 0.7 * (np.cos(psi) - np.cos(0.4))
        scale = R / 0.7
        plan = [("dop853", TOL), ("dop853", dict(rtol=1e-10, atol=1e-12 * R, scaled=True)),
                ("dopri5", TOL), ("rk4", dict(n_steps=n_fixed)), ("dla", dict(n_steps=n_fixed)),
                ("scipy-Radau", TOL), ("scipy-LSODA", TOL)]
        for method, kw in plan:
            run_kw = {k: v for k, v in kw.items() if k != "scaled"}
            tr, wall, note = attempt(scene, method, p, save="final", **run_kw)
            err = (max(abs(tr["x"][-1] - dx), abs(tr["y"][-1] - dy)) / scale
                   if tr is not None else float("nan"))
            rows.append(dict(family="scale", ratio=R, method=label(method, kw),
                             relative_error=err, status=note, wall_s=wall))
    return rows


def sleigh_exact(t, I, m=1.0, a=0.5, v0=0.2, w0=1.0):
    K = I + m * a**2
    V = np.sqrt(v0**2 + K * w0**2 / m)
    c = np.arctanh(v0 / V)
    s = m * a * V * t / K + c
    return V * np.tanh(s), w0 * np.cosh(c) / np.cosh(s)


def sleigh_errors(tr, I, a, v0):
    th = tr["theta"]
    v = tr["x_t"] * np.cos(th) + tr["y_t"] * np.sin(th)
    with np.errstate(over="ignore"):
        v_ex, w_ex = sleigh_exact(tr.t, I, a=a, v0=v0)
    return float(max(np.max(np.abs(v - v_ex)) / max(np.max(np.abs(v_ex)), 1e-300),
                     np.max(np.abs(tr["theta_t"] - w_ex)) / max(np.max(np.abs(w_ex)), 1e-300)))


def sleigh_scene(T, v0):
    """Heading theta stays below pi/2 (where the y-split is singular) for the ratios used."""
    return Scene(models.get("chaplygin_sleigh"), "chetaev", params=dict(m=1.0, I=0.2, a=0.5),
                 initial=dict(x=0.0, y=0.0, theta=0.0, x_t=v0, theta_t=1.0),
                 t_span=(0.0, T), runtime_params=["I", "a"])


def inertia_family(values, n_fixed):
    T = 1.2                                # theta <= t < pi/2
    scene = sleigh_scene(T, 0.2)
    rows = []
    for mu in values:
        a = 0.5
        I = mu * a**2
        p = np.array([I, a])
        for method, kw in (("dop853", TOL), ("dopri5", TOL), ("rk4", dict(n_steps=n_fixed)),
                           ("dla", dict(n_steps=n_fixed)), ("scipy-Radau", TOL)):
            tr, wall, note = attempt(scene, method, p, **kw)
            rows.append(dict(family="inertia", ratio=mu, method=method, status=note,
                             relative_error=sleigh_errors(tr, I, a, 0.2) if tr
                             else float("nan"), wall_s=wall))
    return rows


def frequency_family(values, h):
    T = 10.0
    k = sp.Symbol("k")
    scene = Scene(oscillator(k), "chetaev", params={k: 1.0}, initial=OSC0, t_span=(0.0, T),
                  runtime_params=["k"])
    rows = []
    for kv in values:
        p = np.array([kv])
        ref = scene.run(params=p, rtol=1e-13, atol=1e-15, save="final")
        amp = max(abs(ref["x"][-1]), abs(ref["x_t"][-1]), OSC0["x"])
        for method, kw in (("dop853", TOL), ("dopri5", TOL), ("rk4", dict(h=h)),
                           ("dla", dict(h=h)), ("scipy-Radau", TOL), ("scipy-LSODA", TOL)):
            tr, wall, note = attempt(scene, method, p, save="steps", **kw)
            if tr is not None:
                err = max(abs(tr[s][-1] - ref[s][-1]) for s in ("x", "x_t")) / amp
                E = tr.energy
                edrift = float(np.max(np.abs(E - E[0])) / abs(E[0]))
                steps = tr.diagnostics.steps or len(tr) - 1
            else:
                err, edrift, steps = float("nan"), float("nan"), None
            rows.append(dict(family="frequency", ratio=kv, method=method, status=note,
                             relative_error=err, energy_drift_relative=edrift, steps=steps,
                             rhs_evaluations=tr.diagnostics.rhs_evaluations if tr else None,
                             wall_s=wall))
    return rows


def stiff_family(values, h):
    T = 10.0
    scene = sleigh_scene(T, 1.0)         # total turning < 1.35 rad for every a <= 1
    rows = []
    for a in values:
        I = a**2                         # I = m a^2, m = 1
        p = np.array([I, a])
        V = np.sqrt(1.0 + 2 * a**2)
        lam = V / (2 * a)
        plan = [("dop853", dict(rtol=1e-8, atol=1e-10)), ("dopri5", dict(rtol=1e-8, atol=1e-10)),
                ("rk4", dict(h=h)), ("dla", dict(h=h)),
                ("scipy-Radau", dict(rtol=1e-8, atol=1e-10)),
                ("scipy-BDF", dict(rtol=1e-8, atol=1e-10)),
                ("scipy-LSODA", dict(rtol=1e-8, atol=1e-10))]
        for method, kw in plan:
            tr, wall, note = attempt(scene, method, p, save="steps", **kw)
            rows.append(dict(family="stiff", ratio=a, lambda_T=lam * T, method=method,
                             status=note, wall_s=wall,
                             steps=(tr.diagnostics.steps or len(tr) - 1) if tr else None,
                             rhs_evaluations=tr.diagnostics.rhs_evaluations if tr else None,
                             relative_error=sleigh_errors(tr, I, a, 1.0) if tr
                             else float("nan")))
        print(f"stiff a = {a:g} (lambda T = {lam * T:.3g}): " + "; ".join(
            f"{r['method']} {r['steps']} steps {fmt(r['relative_error'])}" for r in rows[-7:]))
    return rows


def finished(r):
    return r["status"].startswith(("reached the end", "The solver successfully"))


FAMILY_TITLE = {"scale": "rolling disk: radius R (state scale)",
                "inertia": "Chaplygin sleigh: I / (m a^2)",
                "frequency": "nonholonomic oscillator: spring constant k"}


def plot(rows, out):
    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8))
    for ax, fam in zip(axes, ("scale", "inertia", "frequency")):
        rs = [r for r in rows if r["family"] == fam]
        for i, m in enumerate(dict.fromkeys(r["method"] for r in rs)):
            pts = [(r["ratio"], r["relative_error"]) for r in rs if r["method"] == m]
            x, y = zip(*pts)
            ax.loglog(x, np.maximum(np.nan_to_num(y, nan=np.inf), 1e-17), marker="o", ms=3,
                      label=m, color=f"C{i}")
        ax.set_title(FAMILY_TITLE[fam], fontsize=10)
        ax.set_xlabel("ratio")
        ax.set_ylabel("relative error at T (rtol 1e-10; fixed steps as listed)")
        ax.set_ylim(1e-17, 1e2)
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7)
    f1 = save(fig, out, "error")
    fig, axes = plt.subplots(1, 3, figsize=(17, 4.8))
    rs = [r for r in rows if r["family"] == "stiff"]
    for i, m in enumerate(dict.fromkeys(r["method"] for r in rs)):
        pts = [(r["lambda_T"], r["steps"], r["wall_s"], r["relative_error"]) for r in rs
               if r["method"] == m and r["steps"] and finished(r)]
        if pts:
            x, st, wall, er = zip(*pts)
            axes[0].loglog(x, st, marker="o", ms=3, label=m, color=f"C{i}")
            axes[1].loglog(x, wall, marker="o", ms=3, label=m, color=f"C{i}")
            axes[2].loglog(x, np.maximum(er, 1e-17), marker="o", ms=3, label=m,
                           color=f"C{i}")
    axes[0].set_ylabel("steps (runs that reached T)")
    axes[1].set_ylabel("wall time [s] (same run; scipy steps are Python calls)")
    axes[1].set_title("wall time", fontsize=10)
    axes[2].set_ylabel("relative error of (v, w) against the closed form")
    for ax in axes:
        ax.set_xlabel("stiffness lambda T  (Chaplygin sleigh, I = m a^2, a = 1 .. 1e-6)")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_title("cost: explicit steps grow like lambda T, implicit ones do not",
                      fontsize=10)
    axes[2].set_title("accuracy (rtol 1e-8; rk4 and dla with h = 1e-2)", fontsize=10)
    return [f1, save(fig, out, "stiff")]


def worst(rows, fam, method):
    ok = [r for r in rows if r["family"] == fam and r["method"] == method
          and finished(r) and np.isfinite(r["relative_error"])]
    return max(ok, key=lambda r: r["relative_error"]) if ok else None


def summarize(rows):
    out = []

    def w(fam, m):
        r = worst(rows, fam, m)
        return f"{m} {r['relative_error']:.0e}" if r else f"{m} -"
    sc = [r for r in rows if r["family"] == "scale"]
    if sc:
        out.append("scale, rolling disk R = 1e-6 .. 1e6, worst relative error: " + ", ".join(
            w("scale", m) for m in dict.fromkeys(r["method"] for r in sc))
            + "; with atol fixed at 1e-12 the adaptive methods lose accuracy as the states "
              "shrink (worst at R = 1e-6), with atol scaled by R they do not")
    ie = [r for r in rows if r["family"] == "inertia"]
    if ie:
        out.append("inertia, Chaplygin sleigh I / (m a^2) = 1e-6 .. 1e6, worst relative error: "
                   + ", ".join(w("inertia", m) for m in dict.fromkeys(r["method"] for r in ie))
                   + ": uniform in the ratio (dla: its O(h^2) error)")
    fr = [r for r in rows if r["family"] == "frequency"]
    if fr:
        hi = max(r["ratio"] for r in fr)
        steps = {r["method"]: r["steps"] for r in fr if r["ratio"] == hi and finished(r)}
        bad = {m: min(r["ratio"] for r in fr if r["method"] == m and
                      (not finished(r) or not r["relative_error"] < 1e-3))
               for m in ("rk4", "dla") if any(r["method"] == m and (
                   not finished(r) or not r["relative_error"] < 1e-3) for r in fr)}
        out.append("frequency, spring constant k = 1e-6 .. 1e6 (T = 10, h = 1e-2 for the fixed "
                   "steps): " + ", ".join(w("frequency", m) for m in ("dop853", "dopri5",
                                                                      "scipy-LSODA"))
                   + f"; steps at k = {hi:g}: " + ", ".join(f"{m} {n}" for m, n in
                                                           steps.items() if n)
                   + "; " + ", ".join(f"{m} error > 1e-3 from k = {k:g}" for m, k in
                                      bad.items()))
    rs = [r for r in rows if r["family"] == "stiff"]
    if rs:
        lo, hi = min(r["lambda_T"] for r in rs), max(r["lambda_T"] for r in rs)
        by = {(r["method"], r["lambda_T"]): r for r in rs}
        parts = []
        for m in ("dop853", "dopri5", "scipy-Radau", "scipy-BDF", "scipy-LSODA"):
            a, b = by.get((m, lo)), by.get((m, hi))
            if a and b and a["steps"] and b["steps"] and finished(b):
                parts.append(f"{m} {a['steps']} -> {b['steps']} steps ({b['wall_s']:.2f} s, "
                             f"error {b['relative_error']:.0e})")
        out.append(f"stiff sleigh, lambda T = {lo:.2g} -> {hi:.2g}: " + "; ".join(parts))
        unstable = [r for r in rs if r["method"] == "rk4" and not finished(r)]
        if unstable:
            out.append(f"rk4 with h = 1e-2 is unstable from lambda T = "
                       f"{min(r['lambda_T'] for r in unstable):.2g} (lambda h > 2.8): the state "
                       "explodes, and the run ends where the blown-up heading makes the split "
                       "singular")
        d = [r for r in rs if r["method"] == "dla"]
        if d:
            wd = max(d, key=lambda r: r["relative_error"])
            out.append(f"dla with h = 1e-2 stays bounded (A-stable) but is not L-stable: the "
                       f"decaying mode oscillates instead, error {wd['relative_error']:.0e} at "
                       f"lambda T = {wd['lambda_T']:.2g}; it needs lambda h < ~1")
    return out


def main(argv=None):
    args = parser(__doc__, "stress_ratios").parse_args(argv)
    if args.quick:
        ratios, n_fixed, stiff_a = [1e-6, 1e-3, 1.0, 1e3, 1e6], 1000, [1.0, 1e-2, 1e-4]
    else:
        ratios, n_fixed = [10.0 ** k for k in range(-6, 7)], 1000
        stiff_a = [10.0 ** -k for k in range(0, 7)]
    rows = scale_family(ratios, n_fixed)
    rows += inertia_family(ratios, n_fixed)
    rows += frequency_family(ratios, h=1e-2)
    rows += stiff_family(stiff_a, h=1e-2)
    figures = plot(rows, args.out)
    summary = summarize(rows)
    for s in summary:
        print("-", s)
    write("stress_ratios", dict(
        title="Stress: extreme parameter ratios and stiffness", summary=summary,
        limits=limits(rows), rows=table(rows), runs=rows, figures=figures,
        method=dict(tolerance=TOL, fixed_steps=n_fixed, budget_s=BUDGET)),
        args.out, args.quick)


def table(rows):
    """One row per family and method: the worst error over the ratios and where it fails
    (every run is in "runs")."""
    out = []
    for fam in ("scale", "inertia", "frequency", "stiff"):
        rs = [r for r in rows if r["family"] == fam]
        for m in dict.fromkeys(r["method"] for r in rs):
            mr = [r for r in rs if r["method"] == m]
            ok = [r for r in mr if finished(r) and np.isfinite(r["relative_error"])]
            w = max(ok, key=lambda r: r["relative_error"]) if ok else {}
            row = dict(family=fam, method=m,
                       ratios=f"{mr[0]['ratio']:g} .. {mr[-1]['ratio']:g}",
                       worst_error=w.get("relative_error"), at_ratio=w.get("ratio"),
                       not_finished=", ".join(f"{r['ratio']:g}" for r in mr if not finished(r))
                       or None)
            if fam in ("frequency", "stiff"):
                last = mr[-1]
                row.update(steps_at_largest=last.get("steps") if finished(last) else None,
                           wall_s_at_largest=last["wall_s"] if finished(last) else None)
            out.append(row)
    return out


def limits(rows):
    out = []
    sc = {r["method"]: r for r in rows if r["family"] == "scale" and r["ratio"] == min(
        x["ratio"] for x in rows if x["family"] == "scale")}
    if "dop853" in sc and "dop853, atol=1e-12 R" in sc:
        out.append(f"atol is absolute: with states of size {min(sc['dop853']['ratio'], 1):g} "
                   f"and atol = 1e-12 the relative error is {sc['dop853']['relative_error']:.0e}"
                   f" (rtol 1e-10); scaled with the states (atol = 1e-12 R) "
                   f"{sc['dop853, atol=1e-12 R']['relative_error']:.0e}")
    out.append("Oscillatory stiffness (spring constant k): every method needs steps ~ sqrt(k); "
               "rk4 and dla with a fixed h lose accuracy for sqrt(k) h > ~0.1 and rk4 blows up "
               "for sqrt(k) h > 2.8; implicit scipy methods do not help here")
    st = [r for r in rows if r["family"] == "stiff"]
    if st:
        hi = max(r["lambda_T"] for r in st)
        d8 = [r for r in st if r["method"] == "dop853" and r["lambda_T"] == hi]
        rad = [r for r in st if r["method"] == "scipy-Radau" and r["lambda_T"] == hi]
        if d8 and rad and d8[0]["steps"] and rad[0]["steps"]:
            out.append(f"Dissipative stiffness (sleigh, lambda T up to {hi:.0e}): explicit "
                       f"steps grow like lambda T (dop853 {d8[0]['steps']} steps, "
                       f"{d8[0]['wall_s']:.2f} s) against ~{rad[0]['steps']} for scipy Radau "
                       f"({rad[0]['wall_s']:.2f} s) on the compiled rhs; for such problems use "
                       "scene.run(method='radau'), jetnh's Radau IIA with the Jacobian from "
                       "the derivation (see the stiff benchmark)")
    return out


if __name__ == "__main__":
    main()
