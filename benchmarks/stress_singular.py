"""Near-singular configurations: does every method stop where it must, with the right
reason, and how large is the error up to there?

    .venv/bin/python benchmarks/stress_singular.py [--quick] [--out PATH]

1. The knife edge (``models.knife_edge``, dependent y: ydot = tan(phi) xdot) running into
   cos(phi) = 0, where its split is singular: stop time, indicator, the error of every
   state up to the stop against the closed form, and the error of the dependent velocity
   as a function of |cos(phi)| (figure); then the two ways past it -- the split the stop
   reason proposes (dependent x) and dla, which never uses the split.
2. Appell-Hamel (``models.appell_hamel``) as the horizontal speed v -> 0 (the constraint
   zdot = (b/a) |v| is not differentiable there): stop time against the closed form
   (v falls linearly to 0 at t*), error up to the stop; the same with singular="ignore".
3. A Lagrangian close to degenerate: the Chaplygin sleigh with I -> 0 (d^2L/dqdot^2 has
   det m^2 I, the motion on the constraints has inertia K = I + m a^2 > 0) and with
   I = a = 0 (degenerate on the constraints too).
Quick and full profiles differ in the tolerances and step counts only.
Output: benchmarks/results/stress_singular.json, stress_singular_knife_edge.png.
"""

import numpy as np

from _common import parser, write
from stress_common import fmt, pyplot, save

from jetnh import models
from jetnh.errors import JetnhError
from jetnh.numeric import Scene
from jetnh.mechanics.system import System

SING_TOL = 1e-10        # the default singular_tol


def knife_exact(t, w=1.0, v0=0.5, g=9.81, alpha=0.3):
    """Closed form of the knife edge from phi0 = 0 (``models.knife_edge``)."""
    c = g * np.sin(alpha) / w
    ph = w * t
    v = v0 + c * np.sin(ph)
    return dict(x=(v0 * np.sin(ph) + c * np.sin(ph) ** 2 / 2) / w,
                y=(v0 * (1 - np.cos(ph)) + c * (ph - np.sin(ph) * np.cos(ph)) / 2) / w,
                x_t=v * np.cos(ph), y_t=v * np.sin(ph), phi=ph)


def setting(kw) -> str:
    return ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                     for k, v in kw.items())


def run_row(scene, method, kw):
    tr = scene.run(method=method, **kw)
    s = tr.singularity or {}
    return tr, dict(method=tr.method, setting=setting(kw), status=tr.stop_reason.split(":")[0],
                    indicator=s.get("indicator"), kind=s.get("kind"), t_stop=float(tr.t[-1]),
                    steps=tr.diagnostics.steps)


def knife_edge(quick, out):
    ke = models.get("knife_edge")
    ini = models.initial("knife_edge")
    scene = Scene(ke, "chetaev", initial=ini, t_span=(0.0, 2.0))
    t_thr = np.arccos(SING_TOL)                  # cos(phi) = 1e-10 cos(phi0), phi = t
    tols = [1e-6, 1e-9] if quick else [1e-6, 1e-9, 1e-12]
    plan = [("dop853", dict(rtol=r, atol=1e-2 * r)) for r in tols]
    plan += [("dopri5", dict(rtol=1e-9, atol=1e-11)), ("rk4", dict(n_steps=1000)),
             ("scipy-DOP853", dict(rtol=1e-9, atol=1e-11)),
             ("scipy-Radau", dict(rtol=1e-9, atol=1e-11)),
             ("scipy-LSODA", dict(rtol=1e-9, atol=1e-11))]
    rows, curves = [], []
    for method, kw in plan:
        tr, row = run_row(scene, method, kw)
        ex = knife_exact(tr.t)
        cos = np.abs(np.cos(tr.t))
        err = {k: np.abs(tr[k] - ex[k]) for k in ("x", "y", "x_t", "y_t")}
        far = cos > 1e-3
        row.update(case="knife edge, y-split", t_stop_minus_threshold=row["t_stop"] - t_thr,
                   cos_phi_at_stop=float(cos[-1]),
                   max_error_positions=float(max(err["x"].max(), err["y"].max())),
                   max_error_x_t=float(err["x_t"].max()),
                   error_y_t_at_stop=float(err["y_t"][-1]),
                   max_error_y_t_where_cos_gt_1em3=float(err["y_t"][far].max()),
                   energy_drift_relative_reported=tr.diagnostics.energy_drift_relative)
        rows.append(row)
        if method == "dop853":          # densely towards the stop, on the dense output
            te = np.arccos(np.geomspace(1.0, 1.01 * SING_TOL, 80))
            trd = scene.run(method=method, t_eval=te, **kw)
            exd = knife_exact(trd.t)
            curves.append(dict(label=f"dop853 rtol={kw['rtol']:g}",
                               cos=np.abs(np.cos(trd.t)).tolist(),
                               err_y_t=np.abs(trd["y_t"] - exd["y_t"]).tolist(),
                               err_x_t=np.abs(trd["x_t"] - exd["x_t"]).tolist()))
        print(f"knife edge {row['method']:14s} {kw}: stop t = {row['t_stop']:.15f} "
              f"({row['indicator']}), y_t error at stop {fmt(row['error_y_t_at_stop'])}, "
              f"where |cos| > 1e-3 {fmt(row['max_error_y_t_where_cos_gt_1em3'])}, positions "
              f"{fmt(row['max_error_positions'])}")
    # past the singularity: the other split, and dla
    J = ke.J
    other = System(J, ke.L, list(ke.constraints), dependent=[J.q[0]], defaults=ke.defaults)
    e1 = knife_exact(1.0)                         # x-split regular for 0 < phi < pi
    sc2 = Scene(other, "chetaev", initial=dict(x=e1["x"], y=e1["y"], phi=1.0, y_t=e1["y_t"],
                                               phi_t=1.0), t_span=(1.0, 3.0))
    for scn, method, kw, case in ((sc2, "dop853", dict(rtol=1e-10, atol=1e-12),
                                   "knife edge, x-split from t = 1 (past cos = 0)"),
                                  (scene.replace(t_span=(0.0, 4.0)), "dla",
                                   dict(n_steps=400 if quick else 4000),
                                   "knife edge, dla (no split)")):
        tr, row = run_row(scn, method, kw)
        ex = knife_exact(tr.t)
        row.update(case=case, max_error_positions=float(max(
            np.abs(tr["x"] - ex["x"]).max(), np.abs(tr["y"] - ex["y"]).max())),
            max_error_velocities=float(max(np.abs(tr["x_t"] - ex["x_t"]).max(),
                                           np.abs(tr["y_t"] - ex["y_t"]).max())))
        rows.append(row)
        print(f"{case}: stops at t = {row['t_stop']:.6f} ({row['status']}, "
              f"{row['indicator']}), errors {fmt(row['max_error_positions'])} / "
              f"{fmt(row['max_error_velocities'])}")
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 5))
    for i, c in enumerate(curves):
        cos, e = np.array(c["cos"]), np.array(c["err_y_t"])
        ex_ = np.array(c["err_x_t"])
        ax.loglog(cos, np.maximum(e, 1e-17), color=f"C{i}", ls="-",
                  label=f"{c['label']}: |error of y_t|")
        ax.loglog(cos, np.maximum(ex_ / cos, 1e-17), color=f"C{i}", ls="--", lw=0.8,
                  label=f"{c['label']}: |error of x_t| / |cos(phi)|")
        ax.loglog(cos, np.maximum(ex_, 1e-17), color=f"C{i}", ls=":", lw=1,
                  label=f"{c['label']}: |error of x_t|")
    ax.invert_xaxis()
    ax.set_xlabel("|cos(phi)|  (the split's determinant; 1 at t = 0, 1e-10 at the stop)")
    ax.set_ylabel("absolute error against the closed form")
    ax.set_title("Knife edge into cos(phi) = 0, dependent y: y_t = tan(phi) x_t\n"
                 "the dependent velocity's error grows like error(x_t) / |cos(phi)|",
                 fontsize=10)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=7)
    return rows, save(fig, out, "knife_edge")


def appell_hamel(quick):
    ah = models.get("appell_hamel")
    ini = models.initial("appell_hamel")
    v0, rate = np.sqrt(10.0), 0.5 * 9.81 / 1.25
    t_star = v0 / rate
    t_thr = t_star - np.sqrt(SING_TOL) * v0 / rate    # the indicator is v^2

    def exact(t):
        s = v0 * t - rate * t**2 / 2
        return dict(v=v0 - rate * t, z=0.5 * s, x=3 / v0 * s)
    che = Scene(ah, "chetaev", initial=ini, t_span=(0.0, 2.0))
    vak = Scene(ah, "vakonomic", initial=dict(ini, lambda_z=0.0), t_span=(0.0, 2.0))
    n = 200 if quick else 2000
    plan = [(che, "dop853", dict(rtol=1e-10, atol=1e-12)),
            (che, "dopri5", dict(rtol=1e-10, atol=1e-12)), (che, "rk4", dict(n_steps=n)),
            (che, "scipy-DOP853", dict(rtol=1e-10, atol=1e-12)),
            (che, "scipy-Radau", dict(rtol=1e-10, atol=1e-12)),
            (che, "scipy-LSODA", dict(rtol=1e-10, atol=1e-12)), (che, "dla", dict(n_steps=n)),
            (vak, "dop853", dict(rtol=1e-10, atol=1e-12)), (vak, "dvi", dict(n_steps=n))]
    rows = []
    for scene, method, kw in plan:
        tr, row = run_row(scene, method, kw)
        row.update(case=f"Appell-Hamel, {scene.principle}",
                   t_star_minus_t_stop=t_star - row["t_stop"],
                   t_stop_minus_threshold=row["t_stop"] - t_thr)
        if scene.principle == "chetaev":
            ex = exact(tr.t)
            v = np.hypot(tr["x_t"], tr["y_t"])
            row.update(v_at_stop=float(v[-1]),
                       max_error_v=float(np.max(np.abs(v - np.abs(ex["v"])))),
                       max_error_positions=float(max(np.abs(tr["z"] - ex["z"]).max(),
                                                     np.abs(tr["x"] - ex["x"]).max())))
        rows.append(row)
        print(f"Appell-Hamel {scene.principle:9s} {row['method']:14s}: stop t* - t = "
              f"{row['t_star_minus_t_stop']:.3g} ({row['kind']}: {row['indicator']}), "
              f"v error {fmt(row.get('max_error_v', float('nan')))}")
    # beyond t*: what the methods do with the checks off
    for method, kw in (("dop853", dict(rtol=1e-10, atol=1e-12, max_steps=100_000)),
                       ("rk4", dict(n_steps=n))):
        try:
            tr = che.run(method=method, singular="ignore", t_span=(0.0, 1.2), **kw)
            v = np.hypot(tr["x_t"], tr["y_t"])
            after = tr.t > t_star
            note = (f"reaches t = {tr.t[-1]:.4f} ({tr.stop_reason}, {tr.diagnostics.steps} "
                    f"steps); after t* the speed is in [{v[after].min():.2e}, "
                    f"{v[after].max():.2e}]") if after.any() else tr.stop_reason
        except JetnhError as e:
            note = str(e).split(". ")[0]
        rows.append(dict(case="Appell-Hamel, chetaev, singular='ignore'",
                         method=method, setting=setting(kw), status=note))
        print(f"Appell-Hamel singular='ignore' {method}: {note}")
    return rows


def sleigh(quick):
    sys_ = models.get("chaplygin_sleigh")
    ini = dict(x=0.0, y=0.0, theta=0.0, x_t=0.2, theta_t=1.0)
    T = 2.0

    def exact(t, I, m=1.0, a=0.5, v0=0.2, w0=1.0):
        K = I + m * a**2
        V = np.sqrt(v0**2 + K * w0**2 / m)
        c = np.arctanh(v0 / V)
        s = m * a * V * t / K + c
        return V * np.tanh(s), w0 * np.cosh(c) / np.cosh(s)
    rows = []
    che = Scene(sys_, "chetaev", params=dict(m=1.0, I=0.2, a=0.5), initial=ini,
                t_span=(0.0, T), runtime_params=["I", "a"])
    vak = Scene(sys_, "vakonomic", params=dict(m=1.0, I=0.2, a=0.5),
                initial=dict(ini, lambda_y=0.1), t_span=(0.0, T), runtime_params=["I", "a"])
    n = 200 if quick else 1000
    values = [0.2, 1e-3, 1e-6, 1e-9, 1e-12, 0.0]
    for I in values:
        p = np.array([I, 0.5])
        for method, kw in (("dop853", dict(rtol=1e-10, atol=1e-12)), ("dla", dict(n_steps=n)),
                           ("scipy-Radau", dict(rtol=1e-10, atol=1e-12))):
            tr = che.run(method=method, params=p, **kw)
            th = tr["theta"]
            v = tr["x_t"] * np.cos(th) + tr["y_t"] * np.sin(th)
            v_ex, w_ex = exact(tr.t, I)
            rows.append(dict(case="Chaplygin sleigh, chetaev, I -> 0 (a = 0.5)", I=I,
                             method=tr.method, setting=setting(kw), status=tr.stop_reason,
                             t_stop=float(tr.t[-1]), steps=tr.diagnostics.steps,
                             max_error_v=float(np.max(np.abs(v - v_ex))),
                             max_error_w=float(np.max(np.abs(tr["theta_t"] - w_ex))),
                             residual_max=tr.diagnostics.residual_max))
        ref = vak.run(rtol=1e-12, atol=1e-14, params=p, save="final")
        for method, kw in (("dvi", dict(n_steps=n)),
                           ("scipy-Radau", dict(rtol=1e-10, atol=1e-12))):
            tr = vak.run(method=method, params=p, save="final", **kw)
            diff = max(abs(tr[s][-1] - ref[s][-1]) for s in ("x", "y", "theta", "theta_t"))
            rows.append(dict(case="Chaplygin sleigh, vakonomic, I -> 0 (a = 0.5)", I=I,
                             method=tr.method, setting=setting(kw), status=tr.stop_reason,
                             difference_from_dop853_1em12=float(diff)))
        print(f"sleigh I = {I:g}: " + "; ".join(
            f"{r['method']} v,w err {fmt(r['max_error_v'])}, {fmt(r['max_error_w'])}"
            for r in rows[-5:-2]) + "; vakonomic " + "; ".join(
            f"{r['method']} vs dop853 {fmt(r['difference_from_dop853_1em12'])}"
            for r in rows[-2:]))
    # I = a = 0: degenerate on the constraints as well
    try:
        Scene(sys_, "chetaev", params=dict(m=1.0, I=0.0, a=0.0), initial=ini).run()
        compiled = "ran"
    except JetnhError as e:
        compiled = f"{type(e).__name__}: {str(e)[:120]}..."
    p0 = np.array([0.0, 0.0])
    for method, kw in (("dop853", {}), ("dla", dict(n_steps=10))):
        tr = che.run(method=method, params=p0, **kw)
        rows.append(dict(case="Chaplygin sleigh, I = a = 0 (runtime parameters)",
                         method=method, status=tr.stop_reason,
                         kind=(tr.singularity or {}).get("kind")))
    rows.append(dict(case="Chaplygin sleigh, I = a = 0 (compiled in)", method="any",
                     status=compiled))
    print("sleigh I = a = 0:", compiled[:90], "|", rows[-3]["kind"], rows[-2]["kind"])
    return rows


def summarize(rows):
    out = []
    ke = [r for r in rows if r.get("case") == "knife edge, y-split"]
    if ke:
        stops = [r for r in ke if r.get("indicator") == "cos(phi)"]
        out.append(f"knife edge into cos(phi) = 0 (y-split): {len(stops)}/{len(ke)} runs stop "
                   f"with the indicator cos(phi), within "
                   f"{max(abs(r['t_stop_minus_threshold']) for r in stops):.1e} of the "
                   "threshold time; positions stay accurate (max error "
                   f"{max(r['max_error_positions'] for r in ke):.1e})")
        worst = max(ke, key=lambda r: r["error_y_t_at_stop"])
        out.append("limit: the dependent velocity y_t = tan(phi) x_t has error ~ error(x_t) / "
                   f"|cos(phi)|: up to {worst['error_y_t_at_stop']:.1e} at the stop "
                   f"({worst['method']} {worst['setting']}), and the energy computed from it "
                   f"drifts by {worst['energy_drift_relative_reported']:.1e} (relative) in the "
                   "last row; trust dependent velocities only where |cos(phi)| >> error(x_t)"
                   " / |y_t|, or switch the split (the stop reason names a regular one)")
    for r in rows:
        if r.get("case", "").startswith("knife edge, x-split") or \
                r.get("case", "").startswith("knife edge, dla"):
            out.append(f"{r['case']}: runs to t = {r['t_stop']:.4f} ({r['status']}), max "
                       f"error {r['max_error_positions']:.1e} (positions), "
                       f"{r['max_error_velocities']:.1e} (velocities)")
    ah = [r for r in rows if r.get("case", "").startswith("Appell-Hamel, ") and "kind" in r]
    if ah:
        ok = [r for r in ah if r["kind"] == "constraint"]
        adaptive = [r for r in ok if r["method"] not in ("rk4", "dla", "dvi")]
        out.append(f"Appell-Hamel as v -> 0: {len(ok)}/{len(ah)} runs stop with the constraint "
                   "indicator x_t**2 + y_t**2; adaptive and scipy methods within "
                   f"{max(abs(r['t_stop_minus_threshold']) for r in adaptive):.1e}"
                   " of the threshold time (v = 1e-5 v0: the indicator is quadratic, so the "
                   "threshold 1e-10 is 1e-5 in v); the fixed-step methods stop within a step "
                   "of t* (dla, dvi: the step after which Newton fails is reported as the "
                   "singular stop); the velocity error up to the stop is at most "
                   f"{max(r.get('max_error_v', 0) for r in ok):.1e}")
    ig = [r for r in rows if r.get("case", "").endswith("singular='ignore'")]
    for r in ig:
        out.append(f"Appell-Hamel with singular='ignore', {r['method']}: {r['status']}")
    sl = [r for r in rows if r.get("case", "").startswith("Chaplygin sleigh, chetaev")]
    if sl:
        worst = {m: max(r["max_error_v"] + r["max_error_w"] for r in sl if r["method"] == m)
                 for m in sorted({r["method"] for r in sl})}
        out.append("Chaplygin sleigh with I -> 0 (d^2L/dqdot^2 singular at I = 0, motion "
                   "regular): worst velocity error over I in [0, 0.2]: " + ", ".join(
                       f"{m} {e:.1e}" for m, e in worst.items()) + " (dla's node velocities "
                   "come from the constrained Legendre transform here)")
    sv = [r for r in rows if r.get("case", "").startswith("Chaplygin sleigh, vakonomic")]
    if sv:
        out.append("vakonomic sleigh with I -> 0: largest difference from dop853 (rtol 1e-12): "
                   + ", ".join(f"{m} {d:.1e}" for m, d in sorted(
                       {m: max(r["difference_from_dop853_1em12"] for r in sv if r["method"] == m)
                        for m in {r["method"] for r in sv}}.items())))
    dg = [r for r in rows if r.get("case", "").startswith("Chaplygin sleigh, I = a = 0")]
    if dg:
        out.append("I = a = 0 (degenerate on the constraints): compiled in -> a clear "
                   "JetnhError naming the parameters; as runtime parameters -> dop853 stops "
                   f"at t0 ({dg[0]['kind']} indicator), dla stops at t0 ({dg[1]['kind']})")
    return out


def main(argv=None):
    args = parser(__doc__, "stress_singular").parse_args(argv)
    rows, fig = knife_edge(args.quick, args.out)
    rows += appell_hamel(args.quick)
    rows += sleigh(args.quick)
    summary = summarize(rows)
    for s in summary:
        print("-", s)
    write("stress_singular", dict(
        title="Stress: near-singular configurations", summary=summary, limits=limits(rows),
        rows=rows, columns=["case", "method", "setting", "I", "kind", "indicator", "t_stop",
                            "t_stop_minus_threshold", "max_error_positions", "max_error_v",
                            "max_error_w", "error_y_t_at_stop", "status"],
        figures=[fig], method=dict(singular_tol=SING_TOL)), args.out, args.quick)


def limits(rows):
    out = ["A singular split (knife edge, dependent y at cos(phi) = 0): the dependent "
           "velocity's error is error(x_t) / |cos(phi)| -- up to "
           f"{max(r.get('error_y_t_at_stop', 0) for r in rows):.0e} at the default stop "
           "(singular_tol = 1e-10); positions are unaffected. Use the split the stop reason "
           "proposes, or dla, to go through",
           "Appell-Hamel at zero horizontal speed: every method stops; past the singularity "
           "(singular='ignore') dop853 stalls at t* and rk4 continues with a wrong speed",
           "singular_tol is relative to an indicator's initial size: for a quadratic indicator "
           "(x_t**2 + y_t**2) the stop is at sqrt(singular_tol) in the speed",
           "fixed-step methods locate a stop to within a step (rk4 on its Hermite interpolant "
           "across the kink, dla / dvi at the last regular node)"]
    d = [r for r in rows if r.get("case", "").startswith("Chaplygin sleigh, chetaev")
         and r["method"] == "dla"]
    if d:
        out.append("A Lagrangian degenerate off the constraints (sleigh, I -> 0): every method "
                   "stays accurate; dla takes its node velocities from the constrained "
                   f"Legendre transform there (error {max(r['max_error_v'] for r in d):.0e})")
    return out


if __name__ == "__main__":
    main()
