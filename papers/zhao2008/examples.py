"""The paper's two examples, simulated with jetnh's compiled scenes, and their figures.

Example 1 (vertical rolling disk): the Chetaev and Suslov motions, and vakonomic motions
with multipliers lambda_alpha = -p_alpha + C_alpha: for C = 0 they coincide with the
Suslov/Chetaev motion (condition (32)); for C != 0 the paths part.  Example 2
(Appell-Hamel): every principle gives the same motion, until the horizontal speed
reaches zero, where the constraint is singular.  Each trajectory reports its constraint
residual and the drift of its first integrals (energy; lambda + p for the disk).
"""

from __future__ import annotations

import pathlib

import numpy as np
import sympy as sp

from jetnh.models import appell_hamel, rolling_disk
from jetnh.numeric import Scene

RTOL, ATOL = 1e-10, 1e-12


def _pyplot():
    """pyplot on the Agg backend (the same pixels on every machine with the same fonts)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def save_figure(fig, path: pathlib.Path) -> None:
    """Write ``fig`` as a PNG whose bytes depend on the figure only: no Software
    (matplotlib version) text chunk, fixed dpi; the figure is closed."""
    plt = _pyplot()
    fig.tight_layout()
    fig.savefig(path, dpi=110, metadata={"Software": None})
    plt.close(fig)


def _style():
    """matplotlib's default style, whatever the user's matplotlibrc says."""
    return _pyplot().style.context("default")


def _disk(out: pathlib.Path, fast: bool) -> dict:
    s = rolling_disk()
    J = s.J
    x, y, phi, psi = J.q
    phid, psid = J.qd[2], J.qd[3]
    R, I1, I2 = (sp.Symbol(n) for n in ("R", "I1", "I2"))
    par = {R: 1.0, I1: 0.5, I2: 0.25}
    w_phi, w_psi = 1.0, 0.7
    init = {x: 0.0, y: 0.0, phi: 0.0, psi: 0.0, phid: w_phi, psid: w_psi}
    t_end = 10.0 if fast else 30.0
    t_eval = np.linspace(0.0, t_end, 601)
    p0 = {"lambda_x": -par[R] * w_phi, "lambda_y": 0.0}       # -p_alpha at t = 0
    runs = {}
    runs["chetaev"] = Scene(s, "chetaev", par, init, (0.0, t_end)).run(RTOL, ATOL, t_eval=t_eval)
    runs["suslov"] = Scene(s, "suslov", par, {**init, **p0}, (0.0, t_end)).run(
        RTOL, ATOL, t_eval=t_eval)
    for label, C in (("vakonomic C=0", (0.0, 0.0)), ("vakonomic C=(0.3,-0.2)", (0.3, -0.2))):
        lam = {"lambda_x": p0["lambda_x"] + C[0], "lambda_y": p0["lambda_y"] + C[1]}
        runs[label] = Scene(s, "vakonomic", par, {**init, **lam}, (0.0, t_end)).run(
            RTOL, ATOL, t_eval=t_eval)
    # closed form of the Chetaev motion
    tt = runs["chetaev"].t
    psi_t = w_psi * tt
    x_exact = par[R] * w_phi / w_psi * np.sin(psi_t)
    y_exact = -par[R] * w_phi / w_psi * (np.cos(psi_t) - 1.0)
    err_closed = float(max(np.max(np.abs(runs["chetaev"]["x"] - x_exact)),
                           np.max(np.abs(runs["chetaev"]["y"] - y_exact))))
    sep = {k: float(np.max(np.hypot(r["x"] - runs["chetaev"]["x"], r["y"] - runs["chetaev"]["y"])))
           for k, r in runs.items() if k != "chetaev"}
    # lambda + p conserved along the vakonomic motions (Chaplygin: derived in the claims)
    lp_drift = {}
    for k, r in runs.items():
        if "lambda_x" in r:
            cx = r["lambda_x"] + r["x_t"]
            cy = r["lambda_y"] + r["y_t"]
            lp_drift[k] = float(max(np.ptp(cx), np.ptp(cy)))
    merit = {
        "Chetaev vs closed form, max |error|": f"{err_closed:.2e}",
        **{f"max separation from Chetaev, {k}": f"{v:.2e}" for k, v in sep.items()},
        **{f"energy drift, {k}": f"{r.diagnostics.energy_drift_relative:.2e} (relative)"
           for k, r in runs.items()},
        **{f"constraint residual, {k}": f"{r.diagnostics.residual_max:.2e}" for k, r in runs.items()},
        **{f"drift of lambda + p, {k}": f"{v:.2e}" for k, v in lp_drift.items()},
    }
    # lambda + p drifts by ~3e-10 (rtol 1e-10); that drift acts as a small C, and C ~ 0.36
    # parts the paths by ~18 at t = 30, so the C = 0 run stays within ~1e-7 of the circle
    ok = (err_closed < 1e-7 and sep["suslov"] < 1e-7 and sep["vakonomic C=0"] < 1e-5
          and sep["vakonomic C=(0.3,-0.2)"] > 1e-2
          and all(r.diagnostics.residual_max < 1e-8 for r in runs.values())
          and all(v < 1e-8 for v in lp_drift.values()))
    figs = _figures_disk(out, runs)
    return {"title": "Example 1: vertical rolling disk", "ok": bool(ok), "figures": figs,
            "summary": ("Chetaev, Suslov and vakonomic motions from x = y = phi = psi = 0, "
                        f"phidot = {w_phi}, psidot = {w_psi} (R = 1, I1 = 0.5, I2 = 0.25), "
                        f"t in [0, {t_end}], DOP853 at rtol = {RTOL}. The vakonomic motion with "
                        "lambda = -p (C = 0) is the Suslov/Chetaev circle; with C != 0 it leaves it."),
            "figures_of_merit": merit}


def _figures_disk(out, runs) -> list[str]:
    with _style():
        return _figures_disk_default_style(out, runs)


def _figures_disk_default_style(out, runs) -> list[str]:
    plt = _pyplot()

    names = []
    fig, ax = plt.subplots(figsize=(5.5, 5))
    styles = {"chetaev": "-", "suslov": "--", "vakonomic C=0": ":", "vakonomic C=(0.3,-0.2)": "-"}
    for k, r in runs.items():
        ax.plot(r["x"], r["y"], styles.get(k, "-"), label=k, lw=2 if k == "chetaev" else 1.2)
    ax.set_xlabel("x"); ax.set_ylabel("y"); ax.set_aspect("equal"); ax.legend(fontsize=8)
    ax.set_title("Vertical disk: contact-point paths")
    save_figure(fig, out / "disk_paths.png")
    names.append("disk_paths.png")

    fig, axs = plt.subplots(2, 1, figsize=(6, 5), sharex=True)
    for k, r in runs.items():
        e = r.energy
        axs[0].semilogy(r.t, np.abs(e - e[0]) + 1e-18, label=k)
        axs[1].semilogy(r.t, np.max(np.abs(r.residual), axis=1) + 1e-18, label=k)
    axs[0].set_ylabel("|E(t) - E(0)|"); axs[1].set_ylabel("max |f^a|"); axs[1].set_xlabel("t")
    axs[0].legend(fontsize=7); axs[0].set_title("Vertical disk: energy drift and constraint residual")
    save_figure(fig, out / "disk_invariants.png")
    names.append("disk_invariants.png")
    return names


def _appell_hamel(out: pathlib.Path, fast: bool) -> dict:
    s = appell_hamel()
    J = s.J
    x, y, z = J.q
    xd, yd = J.qd[0], J.qd[1]
    m, g, a, b = (sp.Symbol(n) for n in ("m", "g", "a", "b"))
    par = {m: 1.0, g: 9.81, a: 1.0, b: 0.5}
    v0 = (1.0, 0.5)
    speed0 = float(np.hypot(*v0))
    decel = par[b] / par[a] * par[g] / (1 + par[b] ** 2 / par[a] ** 2)
    t_stop = speed0 / decel                      # where the constraint becomes singular
    t_end = 0.9 * t_stop
    t_eval = np.linspace(0.0, t_end, 301)
    init = {x: 0.0, y: 0.0, z: 0.0, xd: v0[0], yd: v0[1]}
    pz0 = par[m] * par[b] / par[a] * speed0
    runs = {"chetaev": Scene(s, "chetaev", par, init, (0.0, t_end)).run(RTOL, ATOL, t_eval=t_eval)}
    runs["suslov"] = Scene(s, "suslov", par, {**init, "lambda_z": -pz0}, (0.0, t_end)).run(
        RTOL, ATOL, t_eval=t_eval)
    for lam0 in (-pz0, 0.0, 2.0):
        runs[f"vakonomic lambda_z(0)={lam0:.3g}"] = Scene(
            s, "vakonomic", par, {**init, "lambda_z": lam0}, (0.0, t_end)).run(
            RTOL, ATOL, t_eval=t_eval)
    ref = runs["chetaev"]
    speed_exact = speed0 - decel * ref.t
    speed = np.hypot(ref["x_t"], ref["y_t"])
    err_speed = float(np.max(np.abs(speed - speed_exact)))
    sep = {k: float(np.max(np.abs(r["x"] - ref["x"]) + np.abs(r["y"] - ref["y"])
                           + np.abs(r["z"] - ref["z"]))) for k, r in runs.items() if k != "chetaev"}
    merit = {"Chetaev horizontal speed vs closed form, max |error|": f"{err_speed:.2e}",
             **{f"max separation from Chetaev, {k}": f"{v:.2e}" for k, v in sep.items()},
             **{f"energy drift, {k}": f"{r.diagnostics.energy_drift_relative:.2e} (relative)"
                for k, r in runs.items()},
             **{f"constraint residual, {k}": f"{r.diagnostics.residual_max:.2e}"
                for k, r in runs.items()}}
    ok = (err_speed < 1e-7 and all(v < 1e-6 for v in sep.values())
          and all(r.diagnostics.residual_max < 1e-8 for r in runs.values()))
    figs = _figures_ah(out, runs, t_stop)
    return {"title": "Example 2: Appell-Hamel system", "ok": bool(ok), "figures": figs,
            "summary": (f"From xdot = {v0[0]}, ydot = {v0[1]} (m = 1, g = 9.81, a = 1, b = 0.5) "
                        f"until t = {t_end:.4g}, 0.9 of the time {t_stop:.4g} at which the "
                        "horizontal speed reaches zero and the constraint is singular. Every "
                        "principle gives the same motion, for every initial multiplier: "
                        "T^3_mu vanishes along it, as the paper says."),
            "figures_of_merit": merit}


def _figures_ah(out, runs, t_stop) -> list[str]:
    with _style():
        return _figures_ah_default_style(out, runs, t_stop)


def _figures_ah_default_style(out, runs, t_stop) -> list[str]:
    plt = _pyplot()

    fig, axs = plt.subplots(1, 2, figsize=(10, 4))
    for k, r in runs.items():
        axs[0].plot(r["x"], r["z"], label=k)
        axs[1].semilogy(r.t, np.abs(r.energy - r.energy[0]) + 1e-18, label=k)
    axs[0].set_xlabel("x"); axs[0].set_ylabel("z"); axs[0].set_title("Appell-Hamel: x-z path")
    axs[1].set_xlabel("t"); axs[1].set_ylabel("|E(t) - E(0)|")
    axs[1].set_title(f"energy drift (singular at t = {t_stop:.3g})")
    axs[0].legend(fontsize=7)
    save_figure(fig, out / "appell_hamel.png")
    return ["appell_hamel.png"]


def run(out: pathlib.Path, fast: bool = False, log=print) -> dict:
    results = {}
    for name, fn in (("rolling_disk", _disk), ("appell_hamel", _appell_hamel)):
        results[name] = fn(out, fast)
        log(f"  {results[name]['title']}: {'ok' if results[name]['ok'] else 'CHECK FAILED'}")
    return results
