"""Helpers of the numerical stress tests (``benchmarks/stress_*.py``): the test systems
that are not in the catalogue, drift curves and their growth law, figures.

The record (machine, date, command), ``--quick``/``--out`` and the JSON writer come from
``benchmarks/_common.py``; every stress JSON has ``summary`` (a list of short findings),
``rows`` (one dict per case) and ``figures`` (PNG file names next to the JSON).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import sympy as sp

import jetnh as jn


def oscillator(k=None):
    """The nonholonomic particle zdot = y xdot in the harmonic potential (k x^2 + y^2)/2
    (McLachlan & Perlmutter 2006): bounded, quasi-periodic motion.  Chetaev first
    integrals: the energy and the y oscillator's (ydot^2 + y^2)/2 (y decouples);
    vakonomic: the energy and p_z = zdot + lambda_z (z is cyclic).  ``k`` None: k = 1;
    a Symbol: a parameter."""
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    kk = 1 if k is None else k
    L = (xd**2 + yd**2 + zd**2) / 2 - (kk * x**2 + y**2) / 2
    return jn.System(J, L, [zd - y * xd], dependent=[z])


OSC0 = dict(x=1.0, y=0.5, z=0.0, x_t=0.0, y_t=0.3)


def oscillator_integrals(principle):
    J = oscillator().J
    _, y, _ = J.q
    _, yd, zd = J.qd
    if principle == "chetaev":
        return {"y_oscillator": (yd**2 + y**2) / 2}
    return {"p_z": zd + sp.Symbol("lambda_z")}


def drift_curve(t, values, n_points=60):
    """Running maximum of |values - values[0]| sampled at log-spaced times: ``(times,
    drift)`` (times from the first step to the end)."""
    t = np.asarray(t, dtype=float)
    d = np.maximum.accumulate(np.abs(np.asarray(values, dtype=float) - values[0]))
    t0 = t[1] if len(t) > 1 else t[0]
    grid = np.unique(np.geomspace(max(t0 - t[0], 1e-300), t[-1] - t[0], n_points))
    idx = np.clip(np.searchsorted(t - t[0], grid, side="right") - 1, 0, len(t) - 1)
    return (t[idx] - t[0]), d[idx]


def growth(times, drift, start_fraction=1e-3):
    """Least-squares slope of log(drift) against log(t) over the last three decades of
    the run, and its reading: bounded (< 0.2), like sqrt(t) (0.2 .. 0.7), linear
    (0.7 .. 1.3), faster.  Drifts at the level of rounding (< 1e-15) are 'rounding'."""
    times, drift = np.asarray(times), np.asarray(drift)
    sel = (times >= start_fraction * times[-1]) & (drift > 0)
    if sel.sum() < 3 or drift[-1] < 1e-15:
        return 0.0, "rounding"
    slope = float(np.polyfit(np.log(times[sel]), np.log(drift[sel]), 1)[0])
    law = ("bounded" if slope < 0.2 else "~sqrt(t)" if slope < 0.7 else
           "linear" if slope < 1.3 else "faster than linear")
    return slope, law


def pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(fig, out: Path, suffix: str) -> str:
    """Save next to the JSON ``out`` as ``<stem>_<suffix>.png``; returns the file name."""
    path = out.with_name(f"{out.stem}_{suffix}.png")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    import matplotlib.pyplot as plt

    plt.close(fig)
    print("wrote", path.name)
    return path.name


def fmt(x, digits=2) -> str:
    return f"{x:.{digits}e}" if isinstance(x, float) and np.isfinite(x) else str(x)
