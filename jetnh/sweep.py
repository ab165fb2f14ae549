"""Sweeps: one scene over a grid of parameters and initial values, on this machine or on
a Dask cluster, as a pandas DataFrame with one row per grid point.

Example::

    import jetnh as jn
    df = jn.sweep(scene, {R: [0.5, 1.0, 2.0], phi_t: np.linspace(0.1, 1.0, 10)})
    df = jn.sweep(scene, [{"R": 1.0, "phi_t": 0.3}, {"R": 2.0, "phi_t": 0.1}])  # points
    df = jn.sweep(scene, grid, times=[1.0, 5.0], outputs=["x", "y"], rtol=1e-10)
    df = jn.sweep(scene, grid, client=dask_client)        # or client="tcp://host:8786"

    from jetnh.sweep import plot_map, separation
    gap = separation(df_chetaev, df_vakonomic, ["x", "y"])
    plot_map(df_chetaev, "R", "phi_t(t0)", gap, path="gap.png", log=True)

``grid``: a mapping name or Symbol -> values (the Cartesian product, the last key
varying fastest), or a list of points (mappings with the same keys), or a DataFrame (one
point per row).  Keys are parameters of the scene or its states (coordinates,
independent velocities, multipliers); the rest comes from the scene.

Columns, in this order:

- the grid: a parameter under its name (``R``), an initial value as ``phi_t(t0)``;
- the outputs (``outputs``: names, default every state, dependent velocity and first
  integral): at the final time under their names (``x``; NaN when the run stopped
  before it: its last values are never shown as final ones), or with ``times`` at each
  time as ``x(t=2.5)`` (NaN after a run's stop);
- the diagnostics over the output rows: ``status``, ``success``, ``stop_reason``,
  ``t_final``, ``steps``, ``rejected``, ``rhs_evaluations``, ``residual_max``
  (``max |f^a|``), ``energy_drift`` and ``drift[I]`` (``max |I - I(t0)|`` of each first
  integral ``I`` of the scene), and ``events[E]``/``first[E]`` for user events.  NaN in
  ``energy_drift`` (or ``drift[I]``) of a successful row is no drift: the energy could
  not be evaluated there (it overflows, or leaves the domain of an expression, at the
  start); the row's other columns stay valid.  ``residual_max``, ``energy_drift``,
  ``drift[I]`` (and ``holonomic_residual_max`` with holonomic constraints) have one
  definition whatever the method: they are taken over a point's output rows, its final
  row or its rows at ``times``, against E and I at its initial state, never over its
  steps; so without ``times`` ``energy_drift`` is ``|E(t_final) - E(t0)|``, which can be
  smaller than the same run's ``Trajectory.diagnostics.energy_drift`` (the largest over
  the rows it stored).  dla and dvi give their own discrete energy, residual and
  velocities there, as their trajectories do.  A run stopped at a singular
  configuration leaves out the row of its stop (next to the singular set its dependent
  velocities are a near 0/0, as ``Diagnostics.stop_row`` reports): NaN in these
  columns where that row is the one stored.  ``steps`` and ``rejected`` are
  integers, except with ``scipy-<M>``, whose counts scipy does not report
  (``Diagnostics.steps`` None): NaN there, in a float column.

A point that fails (a singular configuration, NaN, too many steps) keeps its row, with
its ``status`` and ``stop_reason``; the sweep goes on.  Options (``rtol``, ``atol``,
``method``, ``n_steps``, ``events``, ...) are those of ``Scene.run``.  Every method of
``Scene.run`` works: dop853, dopri5, rk4 and radau run as a compiled ensemble; dla, dvi and
``scipy-<M>`` run ``Scene.run`` point by point (``times`` needs dense output: dop853, radau,
dopri5 or scipy).

Every point is the scene's compiled single-trajectory loop (``run_ensemble``), so the
result does not depend on where it ran: ``client=None`` runs the grid here on all cores
(the ensemble's thread pool); with a ``dask.distributed`` Client (or a scheduler
address) the grid is split into chunks (``chunk_size`` points), the scene with its
compiled kernels' source is scattered once to every worker, each chunk is one task, and
the rows are gathered in grid order.  A worker that dies loses no rows: Dask recomputes
its chunks elsewhere, and the DataFrame equals the local one to the last bit.
``chunk_size`` defaults to 4 tasks per worker thread on Dask, and here to the whole grid
(20 chunks when ``progress`` is given: ``progress(done, total)`` is called as chunks
finish; ``progress=True`` shows a tqdm bar on stderr).
``df.attrs["grid"]`` names the grid columns.  Measured in ``benchmarks/sweep_dask.py``.

``jetnh.sweep`` is this module, and calling it calls its function ``sweep``: so
``jn.sweep(scene, grid)`` runs a sweep while ``import jetnh.sweep`` gives the module
(``jetnh.sweep.plot_map``, ``jetnh.sweep.sweep``), as any module of the package.
"""

from __future__ import annotations

import math
import operator
import sys
import time
import types
import warnings
from collections.abc import Mapping

from .errors import ArgumentError, JetnhError
from .geometry.jet import key_name

#: options that only ``Scene.run`` takes (methods run point by point)
POINT_OPTIONS = ("projection",)


def _options() -> tuple[str, ...]:
    """The options passed on to ``run_ensemble`` (or to ``Scene.run``): the method, the
    events and the run options (``numeric.options``, imported when a sweep runs)."""
    from .numeric.options import NAMES

    return ("method", "events") + NAMES


def sweep(scene, grid, client=None, *, times=None, outputs=None, chunk_size=None,
          progress=None, timeout=None, connect_timeout=10.0, **options):
    """Run ``scene`` at every point of ``grid``: a DataFrame, one row per point (the
    columns and the way a sweep is split: the module docstring).

    Parameters
    ----------
    scene : jetnh.numeric.scene.Scene
        The scene to run; what the grid does not set comes from it.
    grid : dict, list or DataFrame
        A mapping name or Symbol -> values (the Cartesian product, the last key varying
        fastest), a list of points (mappings with the same keys), or a DataFrame (one
        point per row); keys are parameters of the scene or its states.
    client : dask.distributed.Client or str, optional
        None runs the grid here on all cores; a Client or a scheduler address runs it
        on a Dask cluster.
    times : array_like, optional
        Output times (any order; the columns follow the direction of integration): the
        outputs at each as ``x(t=2.5)``; default the final values.
    outputs : list of str, optional
        The series to report; default every state, dependent velocity and first
        integral.
    chunk_size : int, optional
        Points per task (Dask: 4 tasks per worker thread; here: the whole grid, or 20
        chunks with ``progress``).
    progress : bool or callable, optional
        True: a tqdm bar on stderr; a callable ``progress(done, total)`` is called as
        chunks finish.
    timeout : float, optional
        Seconds the sweep may take, here or on Dask (None: no limit; past it the runs
        are stopped and a JetnhError says so).
    connect_timeout : float, default 10
        Seconds to reach a scheduler given by address.
    **options
        Those of ``Scene.run`` (``rtol``, ``atol``, ``method``, ``n_steps``,
        ``events``, ...).

    Returns
    -------
    pandas.DataFrame
        One row per grid point, a failed point with its ``status`` and
        ``stop_reason``; ``df.attrs["grid"]`` names the grid columns.
    """
    import numpy as np
    import pandas as pd

    from .numeric.ensemble import resolve
    from .numeric.scene import Scene

    if not isinstance(scene, Scene):
        raise ArgumentError(f"sweep needs a Scene (jn.Scene(system, principle, params=..., "
                            f"initial=..., t_span=...)), not {type(scene).__name__}")
    if timeout is not None:
        from .numeric import arguments

        timeout = arguments.timeout(timeout)
    if client is not None:
        from .numeric import arguments

        connect_timeout = arguments.positive(connect_timeout, "connect_timeout")
    known = _options() + POINT_OPTIONS
    bad = sorted(set(options) - set(known))
    if bad:
        raise ArgumentError(f"sweep has no option {', '.join(map(repr, bad))}; its options are "
                         f"{', '.join(known)} (output times: "
                         "times=[...])")
    method = _method(options.get("method", "dop853"))
    if not method.ensemble:
        if times is not None and not method.dense:
            raise ArgumentError(f"times needs dense output, which {options['method']} does not "
                             "have; use dop853, dopri5, radau or scipy-<M>, or omit times for the "
                             "final values")
    elif set(options) & set(POINT_OPTIONS):
        raise ArgumentError(f"{', '.join(sorted(set(options) & set(POINT_OPTIONS)))}: an option "
                         "of the dla method")
    if chunk_size is not None:
        chunk_size = _positive_int(chunk_size, "chunk_size")
    names, values = _points(grid)
    params, states = _classify(scene, names)
    scene, Y0, P = resolve(scene, {k: values[:, names.index(k)] for k in states},
                           {k: values[:, names.index(k)] for k in params})
    layout = scene.kernels.layout
    outputs = _outputs(layout, outputs)
    if times is not None:
        from .numeric import arguments

        t0, t1 = scene.t_span
        times = arguments.real_array(times, "times")
        if times.size and (times.min() < min(t0, t1) or times.max() > max(t0, t1)):
            raise ArgumentError(f"times must lie within t_span = ({t0}, {t1}); they span "
                                f"[{times.min()}, {times.max()}]")
        # in any order: the columns are labelled; the runs take them as integrated
        times = np.sort(times)[::1 if t1 >= t0 else -1]
        if times.size == 0:
            raise ArgumentError("times is empty; give output times, or omit it for the final "
                             "time")
        labels = {f"{t:.12g}" for t in times}
        if len(labels) != len(times):
            raise ArgumentError("times has values equal to 12 significant digits (their "
                             "column labels would clash); give distinct times")
    run = dict(options, t_eval=times, save="final")
    n = len(values)
    progress, close = _progress(progress, n)
    try:
        if client is None:
            size = chunk_size or (n if progress is None else math.ceil(n / 20))
            chunks = _chunks(n, size)
            parts = []
            start = time.monotonic()
            for a, b in chunks:
                left = None if timeout is None else timeout - (time.monotonic() - start)
                if left is not None and left <= 0:
                    raise JetnhError(f"the sweep did not finish within timeout={timeout:g} s "
                                     f"({a} of {n} points done); raise timeout or sweep "
                                     "fewer points")
                parts.append(_run_chunk(scene, Y0[a:b], P[a:b],
                                        run if left is None else {**run, "timeout": left},
                                        outputs, "threads"))
                if progress is not None:
                    progress(b, n)
            if timeout is not None and time.monotonic() - start > timeout:
                raise JetnhError(f"the sweep did not finish within timeout={timeout:g} s "
                                 "(its runs were stopped at the deadline); raise timeout "
                                 "or sweep fewer points")
        else:
            parts = _on_dask(client, CompiledScene(scene), Y0, P, run, outputs, chunk_size,
                             progress, timeout, connect_timeout)
    finally:
        close()
    columns = {(k if k in params else f"{k}(t0)"): values[:, j] for j, k in enumerate(names)}
    for key in parts[0]:
        columns[key] = np.concatenate([p[key] for p in parts])
    df = pd.DataFrame(columns)
    df.attrs["grid"] = list(columns)[:len(names)]
    return df


# ---------------------------------------------------------------------- the grid
def _key(k) -> str:
    name = key_name(k)
    if name is not None:
        return name
    raise ArgumentError(f"grid keys are parameter or state names, Symbols or dynamicsymbols, not "
                     f"{type(k).__name__} ({k!r})")


def _numbers(value, what):
    """A number or a 1-d sequence of numbers as a float array: strings, booleans and
    complex values are refused (never parsed), as are non-finite values."""
    import numpy as np

    raw = list(value) if isinstance(value, (list, tuple)) else [value]
    _no_strings(raw, what)
    _no_booleans(raw, what)         # before numpy turns [True, 2.0] into [1.0, 2.0]
    try:
        a = np.asarray(value)
    except ValueError:                          # ragged nesting
        raise ArgumentError(f"{what} must be a number or a 1-d sequence of numbers, got "
                            f"{value!r}") from None
    if a.ndim > 1:
        raise ArgumentError(f"{what} must be a number or a 1-d sequence, got shape "
                            f"{a.shape}")
    items = a.reshape(-1).tolist() if a.dtype.kind in "OUSb" else []
    _no_strings(items, what)
    _no_booleans(items, what)
    if a.dtype.kind == "c" or any(isinstance(v, complex) for v in items):
        raise ArgumentError(f"{what} must be real numbers, got {value!r}")
    try:
        a = np.asarray(a, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ArgumentError(f"{what} must be numbers, got {value!r}") from None
    if not np.all(np.isfinite(a)):
        raise ArgumentError(f"{what} has non-finite values ({a[~np.isfinite(a)][0]}); give "
                            "finite numbers")
    return a


def _no_booleans(items, what):
    """Booleans refused as numbers, with the error of ``Scene`` and ``linearize``."""
    import numpy as np

    flags = [v for v in items if isinstance(v, (bool, np.bool_))]
    if flags:
        raise ArgumentError(f"{what} must be a number, got {bool(flags[0])!r}")


def _no_strings(items, what):
    import numpy as np

    text = [v for v in items if isinstance(v, (str, bytes, np.str_, np.bytes_))
            or (isinstance(v, np.ndarray) and v.dtype.kind in "US")]
    if text:
        raise ArgumentError(f"{what} must be numbers: it holds the string {text[0]!r}, "
                            "and strings are never parsed; give numbers (12.0, not '12')")


def _unique(keys) -> list[str]:
    names = [_key(k) for k in keys]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ArgumentError(f"the grid gives {', '.join(twice)} twice (as a Symbol and as a "
                         "name?); give each once")
    return names


def _points(grid):
    """Names and the values [n_points, n_names] of every grid point."""
    import numpy as np
    import pandas as pd

    if isinstance(grid, pd.DataFrame):      # its columns checked as columns
        names = _unique(grid.columns)
        if not names or not len(grid):
            raise ArgumentError(f"the grid has no {'points' if names else 'columns'}; give a "
                                "DataFrame with a column for each parameter or initial "
                                "value and a row for each point")
        return names, np.stack([_numbers(grid.iloc[:, j].to_numpy(),
                                         f"grid values of {name!r}")
                                for j, name in enumerate(names)], axis=1)
    if isinstance(grid, Mapping):
        names = _unique(grid)
        if not names:
            raise ArgumentError("the grid is empty; give at least one parameter or initial "
                             "value with its values, e.g. {'R': [0.5, 1.0]}")
        axes = []
        for name, v in zip(names, grid.values()):
            a = _numbers(v, f"grid values of {name!r}")
            if a.size == 0:
                raise ArgumentError(f"grid values of {name!r} are empty; give at least one")
            axes.append(a)
        # the Cartesian product, the last axis varying fastest
        return names, np.stack([g.reshape(-1) for g in np.meshgrid(*axes, indexing="ij")],
                               axis=1)
    if isinstance(grid, (list, tuple)):
        if not grid:
            raise ArgumentError("the grid has no points; give a list of points such as "
                             "[{'R': 1.0, 'phi_t': 0.5}, ...]")
        if not all(isinstance(p, Mapping) for p in grid):
            raise ArgumentError("a grid given as a list holds points: mappings name -> value")
        names = _unique(grid[0])
        if not names:
            raise ArgumentError("the grid's points are empty; give each point its values")
        rows = []
        for i, point in enumerate(grid):
            have = _unique(point)
            if set(have) != set(names):
                raise ArgumentError(f"grid point {i} has keys {sorted(have)} but point 0 has "
                                 f"{sorted(names)}; give every point the same keys")
            row = dict(zip(have, point.values()))
            rows.append(_numbers([row[k] for k in names], f"grid point {i}"))
        return names, np.array(rows, dtype=float)
    raise ArgumentError(f"the grid is a mapping name -> values, a list of points or a "
                     f"DataFrame, not {type(grid).__name__}")


def _classify(scene, names):
    """The grid's parameters and states (initial values), checked against the scene."""
    params = [k for k in names if k in scene.params]
    states = [k for k in names if k in scene.state_names]
    for k in names:
        if k in scene.dependent_velocities:
            raise ArgumentError(
                f"the grid has {k!r}, a dependent velocity: it follows from the constraints. "
                f"Sweep the states instead ({', '.join(scene.state_names)})")
        if k not in params and k not in states:
            raise ArgumentError(
                f"the grid has {k!r}, which is neither a parameter "
                f"({', '.join(scene.params) or 'none'}) nor a state "
                f"({', '.join(scene.state_names)}) of this {scene.principle} scene")
    return params, states


def _outputs(layout, outputs):
    names = layout.states + layout.dependent_velocities + layout.integrals
    if outputs is None:
        return names
    out = tuple(_key(k) for k in outputs)
    bad = [k for k in out if k not in names]
    if bad or not out:
        raise ArgumentError(f"outputs {bad or 'empty'}: choose among {', '.join(names)}")
    return out


def _positive_int(value, what) -> int:
    try:
        v = operator.index(value)
    except TypeError:
        v = 0
    if v < 1:
        raise ArgumentError(f"{what} must be a positive integer, not {value!r}")
    return v


def _chunks(n, size):
    return [(a, min(a + size, n)) for a in range(0, n, size)]


def _progress(progress, total):
    """The ``progress(done, total)`` callback and a function that ends it: ``True`` is a
    tqdm bar on stderr, a callable is used as it is."""
    if progress is None or progress is False:
        return None, lambda: None
    if progress is not True:
        if not callable(progress):
            raise ArgumentError(f"progress is None, True or a callable progress(done, total), "
                             f"not {type(progress).__name__}")
        return progress, lambda: None
    from tqdm import tqdm

    bar = tqdm(total=total, desc="sweep", unit="point")

    def show(done, _total):
        bar.update(done - bar.n)
    return show, bar.close


def _method(name):
    """The ``numeric.methods.Method`` called ``name``: one that runs as a compiled
    ensemble (``ensemble``), or else ``Scene.run`` point by point."""
    from .numeric import methods

    return methods.method(name)


# ---------------------------------------------------------------------- one chunk
def _run_chunk(scene, Y0, P, run, outputs, parallel) -> dict:
    """The output and diagnostic columns of the points Y0, P (rows) of ``scene`` (or of
    a ``CompiledScene``, on a worker)."""
    import numpy as np

    from .numeric.ensemble import run_resolved
    from .numeric.options import NAMES, options

    if isinstance(scene, CompiledScene):
        scene = scene.load()
    if not _method(run.get("method", "dop853")).ensemble:
        return _run_points(scene, Y0, P, run, outputs)
    ens = run_resolved(scene, Y0, P, options(**{k: v for k, v in run.items() if k in NAMES}),
                       parallel=parallel, on_error="record",
                       **{k: v for k, v in run.items() if k not in NAMES})
    times = run["t_eval"]
    if times is None:
        final = ens.final_values()
        cols = {name: final[name] for name in outputs}
    else:
        cols = {f"{name}(t={t:.12g})": ens[name][:, j]
                for name in outputs for j, t in enumerate(times)}
    with warnings.catch_warnings():      # a run that stopped at t0 has only NaN rows
        warnings.filterwarnings("ignore", "All-NaN slice", RuntimeWarning)
        diag = ens.diagnostics()
    for key in ("status", "success"):
        cols[key] = diag.pop(key)
    cols["stop_reason"] = np.array(ens.stop_reasons, dtype=object)
    cols["t_final"] = diag.pop("t_final")
    events = {k: diag.pop(k) for k in list(diag) if k.startswith(("events[", "first["))}
    cols.update(diag)
    cols.update(events)
    return cols


def _run_points(scene, Y0, P, run, outputs) -> dict:
    """The columns of ``_run_chunk`` from ``Scene.run`` at each point: for the methods
    that have no compiled ensemble (dla, dvi, scipy-<M>).  A run that ends in NaN keeps
    its row (status 3)."""
    import numpy as np

    from .errors import IntegrationError
    from .numeric.methods._common import NONFINITE

    times = run["t_eval"]
    opts = {k: v for k, v in run.items() if k != "t_eval"}
    lay = scene.kernels.layout
    labels = ([(name, None) for name in outputs] if times is None else
              [(f"{name}(t={t:.12g})", (name, j)) for name in outputs
               for j, t in enumerate(times)])
    n = len(Y0)
    cols = {label: np.full(n, np.nan) for label, _ in labels}
    diag = {"status": np.zeros(n, dtype=np.int64), "success": np.zeros(n, dtype=bool),
            "stop_reason": np.empty(n, dtype=object), "t_final": np.full(n, np.nan),
            "steps": np.zeros(n), "rejected": np.zeros(n),
            "rhs_evaluations": np.zeros(n, dtype=np.int64),
            "residual_max": np.full(n, np.nan), "energy_drift": np.full(n, np.nan)}
    if lay.holonomic:
        diag["holonomic_residual_max"] = np.full(n, np.nan)
    drift = {f"drift[{name}]": np.full(n, np.nan) for name in lay.integrals}
    events = {}
    for i in range(n):
        params = P[i] if len(scene.runtime_params) else None
        try:
            traj = scene.run(y0=Y0[i], params=params, t_eval=times, **opts)
        except IntegrationError as exc:     # its counts up to the stop, where known
            diag["status"][i], diag["stop_reason"][i] = NONFINITE, str(exc)
            stop = exc.stop or {}
            diag["t_final"][i] = stop.get("t", np.nan)
            for key in ("steps", "rejected"):       # None: not known (scipy's), NaN
                diag[key][i] = np.nan if stop.get(key) is None else stop[key]
            diag["rhs_evaluations"][i] = stop.get("rhs_evaluations") or 0
            continue
        for label, where in labels:
            if where is None:
                if traj.diagnostics.success:    # else NaN: not the final value
                    cols[label][i] = traj[label][-1]
            else:
                name, j = where
                if j < len(traj):
                    cols[label][i] = traj[name][j]
        d = traj.diagnostics
        diag["status"][i], diag["success"][i] = d.status, d.success
        diag["stop_reason"][i], diag["t_final"][i] = d.stop_reason, traj.t_final
        for key, v in (("steps", d.steps), ("rejected", d.rejected)):
            diag[key][i] = np.nan if v is None else v       # None: scipy's, unknown
        diag["rhs_evaluations"][i] = d.rhs_evaluations
        figures = _figures(scene, traj, times, Y0[i], P[i])
        for key in figures:
            (diag if key in diag else drift)[key][i] = figures[key]
        for name, te in zip(traj.event_names, traj.t_events):
            events.setdefault(f"events[{name}]", np.zeros(n, dtype=np.int64))[i] = len(te)
            events.setdefault(f"first[{name}]", np.full(n, np.nan))[i] = (
                te[0] if len(te) else np.nan)
    for key in ("steps", "rejected"):       # integers when every count is known
        if not np.isnan(diag[key]).any():
            diag[key] = diag[key].astype(np.int64)
    return {**cols, **diag, **drift, **events}


def _figures(scene, traj, times, y0, p) -> dict:
    """``residual_max``, ``energy_drift``, ``drift[I]`` (and ``holonomic_residual_max``)
    of a point's run ``traj`` as the compiled ensemble gives them
    (``Ensemble.diagnostics``), whatever rows the method stored: over its output rows
    (its final row, or its rows at ``times``), a singular stop's row left out, against E
    and I at the initial state ``y0`` (the run's first row when that is t0)."""
    import numpy as np

    from .numeric.methods._common import SINGULAR

    lay = scene.kernels.layout
    keep = (np.arange(len(traj))[-1:] if times is None else
            np.flatnonzero(np.isin(traj.t, times)))
    if traj.status == SINGULAR:
        keep = keep[traj.t[keep] != traj.t_final]
    e = lay.energy_index
    if len(traj) and traj.t[0] == scene.t_span[0]:
        start = {"energy": traj.energy[0], **{name: traj[name][0] for name in lay.integrals}}
    else:               # (rows at times after t0 alone: E and I at y0 by the kernels)
        aux0 = np.empty(lay.n_aux)
        scene.kernels.aux(scene.t_span[0], y0.copy(), p.copy(), aux0)
        start = {"energy": aux0[e], **{name: aux0[e + 1 + j]
                                       for j, name in enumerate(lay.integrals)}}

    def largest(a):
        """The largest entry that is not NaN (NaN for none, as the ensemble's)."""
        a = np.asarray(a)[~np.isnan(a)]
        return float(a.max()) if a.size else np.nan

    out = {"residual_max": (largest(np.abs(traj.residual[keep]))
                            if lay.dependent_velocities else 0.0),
           "energy_drift": largest(np.abs(traj.energy[keep] - start["energy"]))}
    if lay.holonomic:
        out["holonomic_residual_max"] = largest(np.abs(traj.holonomic_residual[keep]))
    for name in lay.integrals:
        out[f"drift[{name}]"] = largest(np.abs(traj[name][keep] - start[name]))
    return out


class CompiledScene:
    """A scene with the source of its compiled kernels: what a worker needs, shipped once
    per worker.  ``load()`` installs the kernels in the worker's cache (unless there)
    without deriving anything, and returns the scene."""

    def __init__(self, scene):
        kern = scene.kernels
        self.scene = scene.replace()      # a copy without compiled events (they don't pickle)
        self.key = self.scene.key         # computed here: it travels with the scene
        self.layout = kern.layout
        self.source = kern.source                # the text the cache verified and compiled

    def load(self):
        from .numeric.codegen import KernelSource
        from .numeric.kernels import load

        load(self.key, lambda: KernelSource(self.key, self.layout, self.source),
             persistent=self.scene.cache)
        return self.scene


# ---------------------------------------------------------------------- Dask
def _distributed():
    """The ``distributed`` module; a JetnhError naming the extra when it is missing."""
    try:
        import distributed
    except ImportError:
        raise JetnhError("sweeps on a Dask cluster (client=, jetnh sweep --scheduler) need "
                         "dask.distributed: pip install 'jetnh[cluster]'; or run the sweep "
                         "on this machine (client=None, no --scheduler)") from None
    return distributed


def _connect(address, timeout):
    """A Client of the scheduler at ``address``, within ``timeout`` seconds whatever the
    scheduler does (one that accepts connections and never answers, or answers garbage,
    is given up on: the connection runs in a daemon thread with a hard deadline)."""
    import threading

    Client = _distributed().Client
    fix = ("start one (`dask scheduler`, then `dask worker ADDRESS` on each machine) or "
           "check the address")
    box = {}

    def connect():
        try:
            box["client"] = Client(address, timeout=timeout, set_as_default=False)
        except BaseException as exc:                   # reported below, in this thread
            box["error"] = exc

    worker = threading.Thread(target=connect, name="jetnh-dask-connect", daemon=True)
    worker.start()
    worker.join(timeout + 1.0)
    if worker.is_alive() or not box:
        raise JetnhError(f"cannot reach a Dask scheduler at {address!r}: it did not "
                         f"answer within {timeout:g} s (connect_timeout); {fix}")
    if "error" in box:
        exc = box["error"]
        if isinstance(exc, KeyboardInterrupt):
            raise exc
        raise JetnhError(f"cannot reach a Dask scheduler at {address!r} within {timeout:g} "
                         f"s ({type(exc).__name__}: {exc}); {fix}") from None
    return box["client"]


def _on_dask(client, shipped, Y0, P, run, outputs, chunk_size, progress, timeout,
             connect_timeout):
    """The chunks' columns, computed as Dask tasks, in grid order."""
    distributed = _distributed()
    Client, KilledWorker = distributed.Client, distributed.KilledWorker
    as_completed = distributed.as_completed

    own = not isinstance(client, Client)
    if own:
        if not isinstance(client, str):
            raise ArgumentError(f"client is None, a dask.distributed Client or a scheduler "
                             f"address, not {type(client).__name__}")
        client = _connect(client, connect_timeout)
    shipped_future, futures = None, []
    try:
        try:
            client.wait_for_workers(1, timeout=connect_timeout)
        except TimeoutError:
            raise JetnhError(f"the Dask scheduler {client.scheduler.address} has no workers "
                             f"(waited {connect_timeout:g} s); start some with `dask "
                             "worker ADDRESS`") from None
        n = len(Y0)
        threads = sum(client.nthreads().values())
        chunks = _chunks(n, chunk_size or math.ceil(n / (4 * threads)))
        shipped_future = client.scatter(shipped, broadcast=True, hash=False)
        futures = [client.submit(_run_chunk, shipped_future, Y0[a:b], P[a:b], run, outputs,
                                 "serial", pure=False) for a, b in chunks]
        where = {f.key: i for i, f in enumerate(futures)}
        parts, done = [None] * len(chunks), 0
        try:
            for fut in as_completed(futures, timeout=timeout):
                i = where[fut.key]
                parts[i] = fut.result()
                done += chunks[i][1] - chunks[i][0]
                if progress is not None:
                    progress(done, n)
        except TimeoutError:
            raise JetnhError(f"the sweep did not finish within timeout={timeout:g} s ({done} "
                             f"of {n} points done); allow more time or add workers") from None
        except KilledWorker as exc:
            raise JetnhError(f"Dask workers died again and again running a chunk of the "
                             f"sweep ({exc}); the chunk may exhaust a worker's memory: give "
                             "a smaller chunk_size") from None
        return parts
    finally:
        client.cancel(futures + ([shipped_future] if shipped_future is not None else []))
        if own:
            client.close()


# ---------------------------------------------------------------------- results
def separation(a, b, names):
    """The Euclidean distance between the ``names`` columns of two sweeps of one grid
    (e.g. the final positions under two principles), as a Series."""
    import numpy as np

    grid = a.attrs.get("grid", [])
    if len(a) != len(b) or any(not np.array_equal(a[c], b[c]) for c in grid if c in b):
        raise ArgumentError("separation compares two sweeps of the same grid; these differ "
                         f"({len(a)} and {len(b)} rows, grid columns {grid})")
    names = [_key(k) for k in names]
    missing = [k for k in names if k not in a or k not in b]
    if missing:
        raise ArgumentError(f"separation: no column {', '.join(missing)} in both sweeps")
    return np.sqrt(sum((a[k] - b[k]) ** 2 for k in names)).rename("separation")


def plot_map(df, x, y, value, path=None, *, log=False, title=None, mask_failed=True):
    """The map of ``value`` (a column name, or a Series/array aligned with ``df``, e.g.
    ``separation(...)``) over the two grid columns ``x`` and ``y``, as a matplotlib
    Figure (saved to ``path``, PNG or any matplotlib format, when given).  Points that
    failed (``success`` false) are grey unless ``mask_failed=False``; ``log``: a
    logarithmic colour scale (non-positive values grey)."""
    import matplotlib
    import numpy as np
    import pandas as pd
    from matplotlib.colors import LogNorm
    from matplotlib.figure import Figure

    for c in (x, y):
        if c not in df:
            raise ArgumentError(f"plot_map: no column {c!r}; the grid columns are "
                             f"{df.attrs.get('grid', list(df.columns))}")
    label = value if isinstance(value, str) else getattr(value, "name", None) or "value"
    if isinstance(value, str):
        if value not in df:
            raise ArgumentError(f"plot_map: no column {value!r}; choose among "
                             f"{', '.join(df.columns)}")
        value = df[value]
    v = np.array(value, dtype=float)
    if v.shape != (len(df),):
        raise ArgumentError(f"plot_map: value has shape {v.shape}, the sweep {len(df)} rows")
    if mask_failed and "success" in df:
        v[~df["success"].to_numpy(dtype=bool)] = np.nan
    if log:
        v[v <= 0] = np.nan
    table = pd.DataFrame({"x": df[x].to_numpy(), "y": df[y].to_numpy(), "v": v})
    if table.duplicated(["x", "y"]).any():
        raise ArgumentError(f"plot_map: several rows share a point ({x}, {y}); the map needs "
                         "a grid over exactly these two columns (fix the others)")
    grid = table.pivot(index="y", columns="x", values="v")
    fig = Figure(figsize=(6.4, 4.8), layout="constrained")
    ax = fig.add_subplot()
    data = np.ma.masked_invalid(grid.to_numpy())
    cmap = matplotlib.colormaps["viridis"].with_extremes(bad="0.8")
    finite = data.compressed()
    norm = (LogNorm(finite.min(), finite.max()) if log and finite.size else None)
    mesh = ax.pcolormesh(grid.columns.to_numpy(), grid.index.to_numpy(), data,
                         shading="nearest", cmap=cmap, norm=norm)
    fig.colorbar(mesh, ax=ax, label=label)
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    if title:
        ax.set_title(title)
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig


class _CallableModule(types.ModuleType):
    """The class of this module: calling ``jetnh.sweep`` calls ``sweep`` (module
    docstring)."""

    def __call__(self, *args, **kwargs):
        return sweep(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
