"""A trajectory as a table or a figure: pandas DataFrame, xarray Dataset, matplotlib Axes.

The series, in this order: ``t``; every coordinate; every velocity in the order of the
coordinates (the dependent ones from the constraints, or the integrator's own for dla
and dvi); every multiplier that is a state (vakonomic, Hoelder, Suslov; Chetaev's
reactions are not states); then, with ``diagnostics=True``, the user's first integrals
by name, ``energy`` and one ``residual[a]`` per constraint f^a (as written).
"""

from __future__ import annotations

import json

import numpy as np
import sympy as sp

from ..errors import ArgumentError, JetnhError
from ..geometry.jet import key_name

XARRAY_HINT = "pip install 'jetnh[xarray]'"


def kinds(traj, diagnostics=True) -> dict[str, str]:
    """Series name -> its kind ("coordinate", "velocity", ...), in table order."""
    if not isinstance(diagnostics, (bool, np.bool_)):
        raise ArgumentError(f"diagnostics must be True or False, not {diagnostics!r}")
    lay = traj.layout
    system = traj.scene.system
    dep = set(lay.dependent_velocities)
    out = {"t": "time"}

    def add(name, kind):
        if name in out:
            raise JetnhError(
                f"two series are named {name!r} (a {out[name]} and a {kind}); rename one"
                + (" or pass diagnostics=False" if kind in ("energy", "constraint residual",
                                                             "first integral") else ""))
        out[name] = kind

    for s in system.J.q:
        add(s.name, "coordinate")
    for v in system.J.qd:
        add(v.name, "dependent velocity" if v.name in dep else "velocity")
    for m in lay.multipliers:
        add(m, "multiplier")
    if diagnostics:
        for name in lay.integrals:
            add(name, "first integral")
        add("energy", "energy")
        for a in range(system.k):
            add(f"residual[{a}]", "constraint residual")
    return out


def columns(traj, diagnostics=True) -> dict[str, np.ndarray]:
    """Series name -> values at the output rows, in table order."""
    out = {}
    for name, kind in kinds(traj, diagnostics).items():
        if kind == "time":
            out[name] = traj.t
        elif kind == "energy":
            out[name] = traj.energy
        elif kind == "constraint residual":
            out[name] = traj.residual[:, int(name[9:-1])]
        else:
            out[name] = traj[name]
    return out


def attributes(traj) -> dict:
    """method, status, stop_reason, principle, parameters (a JSON object: name -> value)."""
    sc = traj.scene
    params = dict(sc.params)
    params.update(zip(sc.runtime_params, np.asarray(traj._p, dtype=float).tolist()))
    return {"method": traj.method, "status": int(traj.status),
            "stop_reason": traj.stop_reason, "principle": sc.principle,
            "parameters": json.dumps(params, sort_keys=True)}


def to_dataframe(traj, diagnostics=True):
    import pandas as pd

    df = pd.DataFrame(columns(traj, diagnostics))
    df.attrs.update(attributes(traj))
    return df


def to_xarray(traj, diagnostics=True):
    try:
        import xarray as xr
    except ImportError:
        raise JetnhError(f"to_xarray needs xarray, which is not installed: {XARRAY_HINT}"
                         ) from None
    cols = columns(traj, diagnostics)
    kind = kinds(traj, diagnostics)
    t = cols.pop("t")
    data = {name: ("t", np.asarray(v), {"kind": kind[name]}) for name, v in cols.items()}
    return xr.Dataset(data, coords={"t": ("t", t, {"kind": "time"})},
                      attrs=attributes(traj))


def _series(cols, keys, what) -> list[str]:
    """The names of the series ``keys`` (a name, a Symbol or a list of them), checked."""
    if isinstance(keys, (str, sp.Symbol)):
        keys = [keys]
    chosen = []
    for key in keys:
        name = key_name(key)
        if name is None:
            raise JetnhError(f"{what} must be Symbols or names, not {type(key).__name__}")
        if name not in cols:
            raise JetnhError(f"{name!r} is not a series of this trajectory; choose from "
                             f"{', '.join(n for n in cols if n != 't')}")
        chosen.append(name)
    return chosen


def plot(traj, names=None, ax=None, *, x="t", steps=False, smooth=True, path=False):
    """``names`` (Symbols or names of any series; default the coordinates) against the
    series ``x`` (default t) on ``ax``, or on the axes of a new figure.  ``smooth``: the
    curves through the method's dense output between the rows (``dense.resampled``);
    ``steps``: the stored rows marked; ``path``: equal scales on both axes."""
    from .dense import resampled

    cols = columns(traj)
    if names is None:
        names = [s.name for s in traj.scene.system.J.q]
    chosen = _series(cols, names, "plot names")
    (x,) = _series(cols, x, "x")
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(4.8, 4.8) if path else (6.4, 4.0),
                             layout="constrained")
    else:
        from matplotlib.axes import Axes

        if not isinstance(ax, Axes):
            raise ArgumentError(f"ax must be a matplotlib Axes (e.g. fig.subplots()), not "
                                f"{type(ax).__name__}")
    curve = columns(resampled(traj)) if smooth else cols
    for name in chosen:
        (line,) = ax.plot(curve[x], curve[name], label=name)
        if steps:
            ax.plot(cols[x], cols[name], ".", color=line.get_color(), ms=4,
                    label="_steps")
    if path:
        for name in chosen:
            ax.plot(cols[x][:1], cols[name][:1], "o", color="k", ms=4, label="_start")
        ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(x)
    ax.set_ylabel(chosen[0] if len(chosen) == 1 else "value")
    ax.set_title(f"{traj.scene.principle}, {traj.method}"
                 + (" (dots: the steps)" if steps else ""))
    if len(chosen) > 1:
        ax.legend()
    return ax


def ensemble_dataframe(ens):
    """An ensemble as one long table: ``run``, ``t``, then per row every state, dependent
    velocity and first integral (``ens.names``) and the run's run-time parameters; rows
    after a run's stop (NaN times) are left out."""
    import pandas as pd

    n_runs, n_times = ens.t.shape
    keep = np.isfinite(ens.t).ravel()
    cols = {"run": np.repeat(np.arange(n_runs), n_times)[keep], "t": ens.t.ravel()[keep]}
    for name in ens.names:
        cols[name] = ens[name].ravel()[keep]
    for j, name in enumerate(ens.param_names):
        if name in cols:
            raise JetnhError(f"the run-time parameter {name!r} has the name of a series")
        cols[name] = np.repeat(ens.params[:, j], n_times)[keep]
    df = pd.DataFrame(cols)
    df.attrs.update({"method": ens.method, "principle": ens.scene.principle,
                     "parameters": json.dumps(ens.scene.params, sort_keys=True)})
    return df
