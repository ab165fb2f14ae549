"""Ensembles: many initial conditions or parameter sets in one call, on all cores::

    ens = scene.ensemble(initial={"phi_t": np.linspace(0.1, 1, 100)},
                         params={"R": np.full(100, 2.0)}, rtol=1e-10, atol=1e-12,
                         t_eval=np.linspace(0, 10, 51))          # or save="final"
    ens.y                      # [n_runs, n_times, n_states]
    ens.to_dataframe()         # one row per run and time (a pandas DataFrame)
    ens["x"], ens["x_t"]       # [n_runs, n_times] (dependent velocities, integrals too)
    ens.final["x"]             # [n_runs]; NaN for runs that stopped before the end
    ens.status, ens.steps, ens.nfev, ens.t_final, ens.residual_max, ens.energy_drift

``run_ensemble(scene, initial, params, ...)`` is a plain function of the scene and
arrays (``Scene.ensemble`` calls it), so a later ``jetnh.sweep`` can hand it chunks.

- ``initial``: an array ``[n_runs, n_states]`` in ``scene.state_names`` order (or one
  state ``[n_states]``), or a dict name/Symbol -> number or array ``[n_runs]`` that
  overrides the scene's initial values.  Dependent velocities are not states: if given
  they are checked against the constraints (``ConstraintError``, or ``project=True``).
- ``params``: dict name/Symbol -> number or array ``[n_runs]``.  Parameters that vary
  must be run-time inputs of the kernels: if the scene compiled them in, an equal scene
  with them as ``runtime_params`` is built (compiled once, then cached on disk); a
  number for a compiled-in parameter builds a scene with that number compiled in.
- Every run is the scene's compiled single-trajectory loop, unchanged, so each
  trajectory is bit-for-bit the one ``scene.run`` gives for the same input.
- ``parallel``: "threads" (default: ``workers`` threads, the calling one and those of
  a pool kept between calls, each running the compiled serial driver on the next chunk
  of runs with the GIL released), "prange"
  (numba threads in one compiled driver, each taking the next run until none is left:
  runs of uneven cost keep every thread busy), or "serial" (one compiled loop).
  ``workers`` defaults to the number of cores numba sees.  Measured in
  ``benchmarks/numeric_ensemble.py``: both parallel modes give the same bits; the
  thread pool needs no extra compiled driver, hence the default.  A Python loop of
  ``scene.run`` pays ~0.1 ms of dispatch per run, which the drivers do not.
- ``sensitivities=True``: every run integrates its variational equations as
  ``Scene.run(sensitivities=True)`` does; ``ens.sensitivities`` is ``[n_runs, n_times,
  n_states, n_columns]`` (columns ``ens.sensitivity_columns``: the initial states, then
  the runtime parameters), ``ens.sensitivity(of, to)`` one entry over runs and times;
  each run's bits are the single run's.
- Every array an ensemble holds or hands out is read-only.  An ensemble pickles (its
  arrays, its scene by its kernels' key: evaluated again in another process); of one
  run it holds the single-run loop's rows as they came, no copies.
- Output: ``t_eval`` points (runs that stop early are NaN after their stop), or
  ``save="final"`` (one row per run, its final state).  Every accepted step is not
  available (ragged); use ``scene.run`` for that.
- Diagnostics per run: status and stop reason, steps, rejected steps, right-hand-side
  evaluations, final time, max constraint residual and energy drift over the output
  rows (and against the initial state: with ``save="final"`` an end-point difference,
  not the largest over the steps; a singular stop's row left out), event counts and
  first times.
- A run whose right-hand side becomes NaN/inf with no singularity to explain it raises
  ``IntegrationError`` naming the run (``on_error="record"`` keeps it as status 3).
"""

from __future__ import annotations

import math
import numbers
import time
import warnings
from functools import cached_property

import numba
import numpy as np

from ..errors import ConstraintError, IntegrationError, JetnhError, JetnhWarning
from ..frozen import Frozen, FrozenDict, memo, readonly
from ..mechanics import holonomic
from . import arguments, atlas, diagnosis, interrupt, loops, regular, solve
from .events import as_events
from .methods import STATUS_TEXT, Solver
from .methods._common import AT_T_EVAL, ENDPOINTS, EVENT, FINISHED, NONFINITE, SINGULAR
from .options import options

PARALLEL = ("prange", "threads", "serial")
_new = object.__new__
_setattr = object.__setattr__
_FLOAT64 = np.dtype(np.float64)
_NO_SWITCHES = FrozenDict()
_NO_GIVEN = FrozenDict()        # (no dependent velocity given: ``resolve``)
#: the quick plans of a scene that kept none (``run_ensemble``: its key is hashed all the
#: same)
_NONE_KEPT: dict = {}
#: the event columns of an ensemble of one (``_of_one``: its plan watches no events)
_NO_EV_N, _NO_EV_T = readonly((np.zeros((1, 0), dtype=np.int64), np.zeros((1, 0))))
#: what an ensemble of one run has of no events, switches or sensitivities (``_fill``)
_ONE_RUN = dict(event_names=(), switches=_NO_SWITCHES, switching=False,
                _pieces=_NO_SWITCHES, _reasons=_NO_SWITCHES, sensitivity_columns=())


def _name(key) -> str:
    return arguments.name_of(key, "ensemble inputs")


def _column(value, what) -> np.ndarray:
    a = np.asarray(value)
    if a.ndim > 1:
        raise JetnhError(f"{what} must be a number or a 1-d array (one value per run), "
                         f"got shape {a.shape}")
    return arguments.real_array(a, what, a.ndim)


def _n_runs(columns: dict, n_from_array: int | None) -> int:
    sizes = {k: v.shape[0] for k, v in columns.items() if v.ndim == 1}
    n = set(sizes.values())
    if n_from_array is not None:
        n.add(n_from_array)
    if len(n) > 1:
        listing = ", ".join(f"{k}: {v}" for k, v in sizes.items())
        raise JetnhError(f"ensemble inputs have different numbers of runs ({listing}"
                         + (f", initial array: {n_from_array}" if n_from_array else "")
                         + "); give arrays of one length (or numbers, which are broadcast)")
    return n.pop() if n else 1


def resolve(scene, initial=None, params=None, project=False):
    """The scene to run (with the varying parameters as run-time inputs), the initial
    states Y0 [n_runs, n_states] and the run-time parameters P [n_runs, n_p]."""
    row = None if params is not None else _one_row(scene, initial)
    if row is not None:
        y, p = _of_row(scene, row, project)
        return scene, y[None, :], p[None, :]
    params = ({_name(k): _column(v, f"params[{_name(k)!r}]") for k, v in params.items()}
              if params else None)
    if params:
        unknown = sorted(set(params) - set(scene.params))
        if unknown:
            raise JetnhError(f"params has {', '.join(map(repr, unknown))}, not parameters of "
                             f"this system; its parameters are {sorted(scene.params) or 'none'}")
        varying = [k for k, v in params.items() if v.ndim == 1 or k in scene.runtime_params]
        fixed = {k: float(v) for k, v in params.items() if k not in varying}
        need = [k for k in varying if k not in scene.runtime_params]
        if need or fixed:
            scene = scene.replace(params={**scene.params, **fixed},
                                  runtime_params=tuple(scene.runtime_params) + tuple(need))
    columns, arr, n_arr = {}, None, None
    if isinstance(initial, dict):
        columns = {_name(k): _column(v, f"initial[{_name(k)!r}]") for k, v in initial.items()}
        allowed = set(scene.state_names) | set(scene.dependent_velocities)
        bad = sorted(set(columns) - allowed)
        if bad:
            raise JetnhError(f"initial has {', '.join(map(repr, bad))}, not states of this "
                             f"{scene.principle} scene; the states are "
                             f"{', '.join(scene.state_names)}")
    elif initial is not None:
        arr = np.asarray(initial)
        if arr.ndim == 1:
            arr = arr[None, :]
        if arr.ndim != 2 or arr.shape[1] != len(scene.state_names):
            raise JetnhError(f"initial as an array must have shape [n_runs, "
                             f"{len(scene.state_names)}] (states {', '.join(scene.state_names)})"
                             f", got {np.shape(initial)}")
        if arr.dtype is _FLOAT64 and arguments.all_finite(arr):
            arr = arr.copy()        # (what ``real_array`` makes of it, sooner)
        else:
            arr = arguments.real_array(arr, "initial", 2)
        n_arr = arr.shape[0]
    n_runs = (_n_runs({**columns, **(params or {})}, n_arr) if columns or params
              else 1 if n_arr is None else n_arr)
    if arr is not None and n_runs == n_arr:
        Y0 = arr                    # (real_array's own copy)
    else:
        Y0 = np.empty((n_runs, len(scene.state_names)))
        Y0[:] = scene.y0 if arr is None else arr
    if columns:
        for j, s in enumerate(scene.state_names):
            if s in columns:
                Y0[:, j] = columns[s]
    if n_runs == 1:
        P = scene._p[None, :].copy()
    else:
        P = np.empty((n_runs, len(scene.runtime_params)))
        P[:] = scene._p
    if params:
        for j, s in enumerate(scene.runtime_params):
            if s in params:
                P[:, j] = params[s]
    dep = ({k: v for k, v in columns.items() if k in scene.dependent_velocities}
           if columns else columns)
    if scene.system.holonomic:     # (first, as a single run: ``Scene._run_state``)
        _check_holonomic(scene, Y0, P)
    if scene.dependent_velocities:
        _check_split(scene, Y0, P, dep, project)
    if dep:
        _check_dependent(scene, Y0, P, dep, project)
    return scene, Y0, P          # (C-contiguous: made so here)


def _one_row(scene, initial) -> np.ndarray | None:
    """The row of ``initial`` where it is one finite float64 row of states (an ensemble
    of one, checked at once: ``_of_row``), else None; a NaN or an infinity makes the sum
    not finite, an overflow of finite values takes the general route, which looks at
    each entry."""
    if (type(initial) is np.ndarray and initial.dtype is _FLOAT64
            and initial.shape == (1, len(scene.state_names))):
        row = initial[0]
        if math.isfinite(sum(row.tolist())):
            return row
    return None


def _of_row(scene, row, project) -> tuple[np.ndarray, np.ndarray]:
    """The state and the parameters (1-d) of the one row ``row`` (``_one_row``),
    checked: a copy of the caller's row, the scene's parameters (never written)."""
    y, p = row.copy(), scene._p
    if scene.system.holonomic:
        _check_holonomic(scene, y[None, :], p[None, :])
    if scene.dependent_velocities and not scene._regular_at(y, scene.t_span[0], p):
        _check_split(scene, y[None, :], p[None, :], _NO_GIVEN, project)
    return y, p


def _check_holonomic(scene, Y0, P):
    """Refuse runs whose initial configuration is off the holonomic constraints g = 0,
    each g_i judged against its own scale at the run's point (``holonomic.bound_rows``:
    the size of its terms, never an absolute number, so the verdict is the same in every
    unit of length), or where dg/dq has not full rank (no smooth configuration manifold
    there), as a single run refuses them (``holonomic.check``, which judges a run whose
    compiled dg/dq is of lower rank again at 30 digits and words the refusal); g and dg/dq
    from the compiled kernel ``hol``, the bounds and ranks of all runs in one pass each."""
    kern = scene.kernels
    system = scene.system
    m, nq = len(system.holonomic), system.J.n
    t0 = scene.t_span[0]
    out = np.empty((Y0.shape[0], kern.hol.sizes[2]))
    for r in range(Y0.shape[0]):
        kern.hol(t0, Y0[r], P[r], out[r])
    g, G = out[:, :m], out[:, m:m + m * nq].reshape(-1, m, nq)
    if np.any(g):
        point = dict(zip(scene.state_names, Y0.T))
        point.update(zip(scene.runtime_params, P.T))
        point = scene._holonomic_point(point, t0, point)
        ok = np.abs(g.T) <= holonomic.bound_rows(system, point)
        if not ok.all():
            r = int(np.argmin(ok.all(axis=0)))
            raise ConstraintError(
                f"run {r}: the initial configuration is off the holonomic constraints "
                f"{list(system.holonomic)} (g = {g[r].tolist()}); give configurations "
                "with g = 0 (an ensemble does not complete them: build one Scene per start "
                "with complete=True)")
    full = np.isfinite(G).all(axis=(1, 2))
    full[full] = np.linalg.matrix_rank(G[full]) == m
    for r in np.flatnonzero(~full).tolist():
        values = dict(zip(scene.state_names, Y0[r].tolist()))
        params = dict(zip(scene.runtime_params, P[r].tolist()))
        try:
            holonomic.check(system, scene._holonomic_point(values, t0, params))
        except ConstraintError as exc:
            raise ConstraintError(f"run {r}: {exc}") from None


def _check_split(scene, Y0, P, given, project):
    """Refuse runs whose initial point the split cannot hold (singular there, or past
    the edge of its chart and off the constraints: ``Scene._dependent_velocity_split``),
    checked for the runs where a singularity indicator comes near zero."""
    t0 = scene.t_span[0]
    for r in range(Y0.shape[0]):
        if scene._regular_at(Y0[r], t0, P[r]):
            continue
        values = dict(zip(scene.state_names, Y0[r].tolist()))
        prm = dict(zip(scene.runtime_params, P[r].tolist()))
        required = scene._dependent_velocity_values(values, t0, prm)
        values.update((k, float(np.broadcast_to(v, Y0.shape[:1])[r]))
                      for k, v in given.items())
        scene._dependent_velocity_split(values, required, t0, prm, f"initial of run {r}",
                                        project)


def _check_dependent(scene, Y0, P, given, project):
    """Refuse runs whose given dependent velocities (``given``: name -> a number or one
    per run) disagree with the constraints' values (the compiled kernel ``aux``), each
    judged against the size of the terms that make it (``regular.agree``); with
    ``project`` none is refused (they follow from the constraints)."""
    if project:
        return
    kern = scene.kernels
    aux = np.empty((Y0.shape[0], kern.layout.n_aux))
    for r in range(Y0.shape[0]):
        kern.aux(scene.t_span[0], Y0[r], P[r], aux[r])
    required = {name: aux[:, a] for a, name in enumerate(scene.dependent_velocities)}
    dep = {name: np.broadcast_to(given[name], Y0.shape[:1])
           for name in scene.dependent_velocities if name in given}
    point = dict(zip(scene.state_names, Y0.T))
    ok = regular.agree(scene.system, scene.t_span[0], point, dep, required,
                       {**scene.params, **dict(zip(scene.runtime_params, P.T))},
                       scene.consistency_tol)
    for name, g in dep.items():
        req = required[name]
        bad = np.nonzero(~ok[name])[0]
        if bad.size:
            r = int(bad[0])
            raise ConstraintError(
                f"initial {name} inconsistent with the constraints in {bad.size} run(s), "
                f"e.g. run {r}: {name} = {g[r]!r} but the constraints give {req[r]!r}. Omit "
                "it (it follows from the constraints) or pass project=True")


class _OfRun:
    """The ``_arrays`` of an ensemble of one run (``Ensemble._of_run``), made of its run
    (``_one_arrays``) on first read and kept in its ``__dict__`` (where the other
    ensembles hold theirs from the start)."""

    def __get__(self, obj, cls=None):
        if obj is None:
            return self
        arrays = obj.__dict__["_arrays"] = _one_arrays(*obj.__dict__["_run"])
        return arrays


class Ensemble(Frozen):
    """The result of ``run_ensemble``: arrays over runs, with named access; immutable
    (``jetnh.frozen``; its arrays are read-only)."""

    def __init__(self, scene, method, t, y, info, t_last, y_last, ev_n, ev_t, Y0, P,
                 event_names, wall_time, parallel, workers, save, singular_tol, *,
                 switching=False, switches=None, pieces=None, reasons=None,
                 sensitivities=None, layout=None):
        self._fill(scene, method, t, y, info, t_last, y_last, ev_n, ev_t, Y0, P,
                   event_names, wall_time, parallel, workers, save, singular_tol,
                   switching, switches, pieces, reasons, sensitivities, layout)

    @classmethod
    def _of_run(cls, scene, method, run, arrays, wall_time, parallel, workers, save,
                singular_tol, layout) -> "Ensemble":
        """The ensemble of one run (``_of_one``: no events, sensitivities or changes of
        split), its attributes in one go (as ``_fill`` sets them) without the wrapper
        that freezes it after ``__init__`` (``jetnh.frozen``): a run's result.  Its
        ``_arrays`` as given, or (None) made of ``run`` (``_one_arrays``' arguments) on
        first read."""
        self = _new(cls)
        _setattr(self, "__dict__", {
            **_ONE_RUN, "scene": scene, "method": method,
            "param_names": scene.runtime_params, "wall_time": wall_time,
            "parallel": parallel, "workers": workers, "save": save,
            "_singular_tol": singular_tol, "layout": layout, "_memo": {},
            "_run" if arrays is None else "_arrays": run if arrays is None else arrays})
        return self

    #: an ensemble of ``_of_run``: its arrays made of its run when first read
    _arrays = _OfRun()

    def _fill(self, scene, method, t, y, info, t_last, y_last, ev_n, ev_t, Y0, P,
              event_names, wall_time, parallel, workers, save, singular_tol, switching,
              switches, pieces, reasons, sensitivities, layout):
        """The attributes in one go (``Frozen._set`` without its walk over every value);
        the arrays on first read (the memos below): read-only views, the caller's
        arrays stay as given (``info`` and ``t_last`` may be tuples: made arrays then)."""
        self.__dict__.update(
            _arrays=(info, t_last, y_last, ev_n, ev_t, Y0, P,
                     None if sensitivities is None else sensitivities[1], t, y),
            scene=scene, method=method,
            event_names=tuple(event_names), param_names=scene.runtime_params,
            wall_time=wall_time, parallel=parallel, workers=workers, save=save,
            _singular_tol=singular_tol,
            layout=scene.kernels.layout if layout is None else layout,
            #: runs that changed split (``numeric.atlas``): run -> [{"t", "from", "to"},
            #: ...]; ``switching``: whether the runs watched their chart's edge
            switches=FrozenDict(readonly(switches)) if switches else _NO_SWITCHES,
            switching=switching, _pieces=pieces or {}, _reasons=reasons or {},
            #: what ``sensitivities`` (``[n_runs, n_times, n_states, n_columns]``, with a
            #: run with ``sensitivities=True``) differentiate by: the initial states,
            #: then the runtime parameters
            sensitivity_columns=() if sensitivities is None else tuple(sensitivities[0]))

    # ------------------------------------------------------------------ pickling
    def __getstate__(self):
        """The data of the runs (their arrays as they are, the aux rows of runs that
        changed split computed now: their pieces hold other charts' compiled code);
        the scene by its kernels' key (``Scene._portable``), which loads them again
        where they are evaluated."""
        self._arrays            # (an ensemble of one run: made now, without the loop's)
        d = Frozen.__getstate__(self)
        d.pop("_run", None)
        if self._pieces:
            d.update(aux=self.aux, _pieces={})
        return d

    def __setstate__(self, state):
        """Read-only again: every array, as when run."""
        self.__dict__.update(state)
        readonly((state["_arrays"], state.get("aux"), state.get("aux_initial")))

    def __copy__(self):
        return self             # (immutable)

    @memo
    def t(self) -> np.ndarray:
        """[n_runs, n_times]"""
        return self._arrays[8].view()

    @memo
    def y(self) -> np.ndarray:
        """[n_runs, n_times, n_states]"""
        return self._arrays[9].view()

    @memo
    def _info(self) -> np.ndarray:
        """The runs' (status, steps, rejected, nfev, rows, indicator) as rows (one copy
        of the driver's columns)."""
        info = self._arrays[0]
        return (np.array(info, dtype=np.int64) if type(info) is tuple else info).T.copy()

    @memo
    def status(self) -> np.ndarray:
        return self._info[0].view()

    @memo
    def steps(self) -> np.ndarray:
        return self._info[1].view()

    @memo
    def rejected(self) -> np.ndarray:
        return self._info[2].view()

    @memo
    def nfev(self) -> np.ndarray:
        return self._info[3].view()

    @memo
    def rows(self) -> np.ndarray:
        return self._info[4].view()

    @property
    def _sing_index(self) -> np.ndarray:
        return self._info[5]

    @memo
    def t_final(self) -> np.ndarray:
        t_last = self._arrays[1]
        return np.array(t_last) if type(t_last) is tuple else t_last.view()

    @memo
    def y_final(self) -> np.ndarray:
        return self._arrays[2].view()

    @memo
    def event_counts(self) -> np.ndarray:
        """[n_runs, n_events]"""
        return self._arrays[3].view()

    @memo
    def event_first(self) -> np.ndarray:
        ev_n, ev_t = self._arrays[3], self._arrays[4]
        return np.where(ev_n > 0, ev_t, np.nan) if ev_t.size else ev_t.view()

    @memo
    def initial(self) -> np.ndarray:
        return self._arrays[5].view()

    @memo
    def params(self) -> np.ndarray:
        """[n_runs, n_runtime_params]"""
        return self._arrays[6].view()

    @memo
    def sensitivities(self) -> np.ndarray:
        S = self._arrays[7]
        if S is None:
            raise AttributeError("sensitivities")
        return S.view()

    # ------------------------------------------------------------------ shape and access
    @property
    def n_runs(self) -> int:
        return self._arrays[9].shape[0]

    def __len__(self):
        return self.n_runs

    @property
    def state_names(self) -> tuple[str, ...]:
        return self.layout.states

    @property
    def names(self) -> tuple[str, ...]:
        lay = self.layout
        return lay.states + lay.dependent_velocities + lay.integrals

    @property
    def success(self) -> np.ndarray:
        return (self.status == FINISHED) | (self.status == EVENT)

    def __getitem__(self, key) -> np.ndarray:
        """[n_runs, n_times] array of a state, dependent velocity or first integral."""
        name = _name(key)
        lay = self.layout
        if name in lay.states:
            return self.y[:, :, lay.states.index(name)]
        k = len(lay.dependent_velocities)
        if name in lay.dependent_velocities:
            return self.aux[:, :, lay.dependent_velocities.index(name)]
        if name in lay.integrals:
            return self.aux[:, :, 2 * k + 1 + lay.integrals.index(name)]
        raise JetnhError(f"{name!r} is not in this ensemble; it has {', '.join(self.names)}")

    @memo
    def _followers(self) -> frozenset:
        """The coordinates that follow from the holonomic constraints at the first
        run's start (``initial.followers``)."""
        if not self.scene.system.holonomic or not len(self.initial):
            return frozenset()
        from .initial import followers

        return followers(self.scene, self.scene.t_span[0], self.initial[0], self.params[0])

    def sensitivity(self, of, to) -> np.ndarray:
        """``d of(t) / d to`` over the runs and output times (``[n_runs, n_times]``,
        read-only): ``of`` a state, ``to`` an initial value of a state or a runtime
        parameter (``Trajectory.sensitivity``, along the holonomic constraints as
        there: a coordinate that follows from them at the first run's start is refused;
        an ensemble run with ``sensitivities=True``)."""
        if not self.sensitivity_columns:
            raise JetnhError("this ensemble carries no sensitivities; run it with "
                             "sensitivities=True")
        a, b = _name(of), _name(to)
        if a not in self.layout.states:
            raise JetnhError(f"sensitivity of {a!r}: not a state of this ensemble; the "
                             f"states are {', '.join(self.layout.states)}")
        if b not in self.sensitivity_columns:
            raise JetnhError(f"sensitivity to {b!r}: not an initial value of a state or a "
                             f"runtime parameter; choose one of "
                             f"{', '.join(self.sensitivity_columns)}")
        if self._followers:
            from .initial import check_column

            check_column(self.scene, b, self._followers)
        return self.sensitivities[:, :, self.layout.states.index(a),
                                  self.sensitivity_columns.index(b)]

    @cached_property
    def aux(self) -> np.ndarray:
        """[n_runs, n_times, n_aux]: dependent velocities, residuals, energy, integrals
        (NaN where the run has no row)."""
        kern = self.scene.kernels
        n_runs, n_times, _ = self.y.shape
        out = np.full((n_runs, n_times, self.layout.n_aux), np.nan)
        ok = np.isfinite(self.t)
        if self._one_p:         # every row in one compiled call (no loop over runs here)
            tmp = np.empty((int(ok.sum()), self.layout.n_aux))
            kern.aux_rows(np.ascontiguousarray(self.t[ok]), np.ascontiguousarray(self.y[ok]),
                          self.params[0].copy() if n_runs else np.zeros(0), tmp)
            out[ok] = tmp
        else:
            for r in range(n_runs):
                if ok[r].any():
                    tmp = np.empty((int(ok[r].sum()), self.layout.n_aux))
                    kern.aux_rows(np.ascontiguousarray(self.t[r][ok[r]]),
                                  np.ascontiguousarray(self.y[r][ok[r]]),
                                  self.params[r].copy(), tmp)
                    out[r][ok[r]] = tmp
        if self._pieces:
            own = atlas.atlas(self.scene).own
            for r, pieces in self._pieces.items():
                atlas.fill_aux(out[r], own, pieces, self.params[r].copy())
        return readonly(out)

    @cached_property
    def aux_initial(self) -> np.ndarray:
        kern = self.scene.kernels
        out = np.empty((self.n_runs, self.layout.n_aux))
        t0 = self.scene.t_span[0]
        if self._one_p:
            # compiled code takes writable arrays: copies of the read-only rows
            kern.aux_rows(np.full(self.n_runs, t0), self.initial.copy(),
                          self.params[0].copy(), out)
            return readonly(out)
        for r in range(self.n_runs):
            kern.aux(t0, self.initial[r].copy(), self.params[r].copy(), out[r])
        return readonly(out)

    @cached_property
    def _one_p(self) -> bool:
        """Whether every run has the same run-time parameters (its rows are then
        evaluated in one call)."""
        return self.n_runs > 0 and bool((self.params == self.params[0]).all())

    @property
    def final(self) -> dict[str, np.ndarray]:
        """Name -> [n_runs] (read-only) values at the requested end of each run: the
        final time, or a terminal event.  A run that stopped before (a singular
        configuration, NaN, the step budget; ``status``, ``stop_reasons``) has NaN there,
        never the values where it stopped, and a ``JetnhWarning`` says how many did."""
        out = self.final_values()
        bad = np.flatnonzero(~self.success)
        if bad.size:
            warnings.warn(
                f"{bad.size} of the {self.n_runs} runs did not reach the final time (run "
                f"{bad[0]}: {self.stop_reason(int(bad[0]))}); their final values are NaN. "
                "Their last rows are in ens[name] and ens.t_final", JetnhWarning,
                stacklevel=2)
        return out

    def final_values(self) -> dict[str, np.ndarray]:
        """``final`` without the warning (for tables that carry ``status`` alongside)."""
        last = np.maximum(np.sum(np.isfinite(self.t), axis=1) - 1, 0)
        idx = np.arange(self.n_runs)
        ok = self.success
        out = {}
        for name in self.names:
            v = np.where(ok, self[name][idx, last], np.nan)
            v.flags.writeable = False
            out[name] = v
        return out

    # ------------------------------------------------------------------ diagnostics
    @property
    def residual_max(self) -> np.ndarray:
        """Max ``|f^a|`` over each run's output rows (``energy_drift`` says which)."""
        k = len(self.layout.dependent_velocities)
        if not k:
            return np.zeros(self.n_runs)
        return _largest(np.abs(self._regular(self.aux[:, :, k:2 * k])))

    @property
    def holonomic_residual_max(self) -> np.ndarray:
        """Max ``|g_i|`` of the holonomic constraints over each run's output rows
        (``energy_drift`` says which)."""
        m = self.layout.holonomic
        if not m:
            return np.zeros(self.n_runs)
        return _largest(np.abs(self._regular(self.aux[:, :, self.layout.n_aux - m:])))

    @property
    def energy_drift(self) -> np.ndarray:
        """Max ``|E - E(t0)|`` over each run's output rows, not over its steps: with
        ``save="final"`` the one row is the final state, so this is ``|E(t_final) -
        E(t0)|``, an end-point difference that can be far below the largest drift the
        run had on the way (``scene.run(save="steps")`` gives that); with ``t_eval``, at
        those times.  A run stopped at a singular configuration leaves out the row of
        its stop (next to the singular set its dependent velocities are a near 0/0): NaN
        with ``save="final"``, whose one row that is."""
        i = self.layout.energy_index
        e = self._regular(self.aux[:, :, i:i + 1])
        return _largest(np.abs(e - self.aux_initial[:, i, None, None]))

    @property
    def integral_drift(self) -> dict[str, np.ndarray]:
        """First integral name -> max ``|I - I(t0)|`` over each run's output rows, the
        rows of ``energy_drift`` (a singular stop's left out)."""
        start = self.layout.energy_index + 1
        return {name: _largest(np.abs(self._regular(self.aux[:, :, start + j:start + j + 1])
                                      - self.aux_initial[:, start + j, None, None]))
                for j, name in enumerate(self.layout.integrals)}

    def _regular(self, a) -> np.ndarray:
        """``a`` ([n_runs, n_times, columns] of the aux rows) with NaN in the row of each
        run's singular stop, where it is one (``save="final"``: the run's one row)."""
        stopped = (self.status == SINGULAR) & np.isfinite(self.t_final)
        if not stopped.any():
            return a
        a = np.array(a)
        a[stopped[:, None] & (self.t == self.t_final[:, None])] = np.nan
        return a

    def stop_reason(self, r: int) -> str:
        if r in self._reasons:
            return self._reasons[r]
        s = int(self.status[r])
        if s == SINGULAR:
            sc = self.scene
            info = diagnosis.singularity(sc, sc.kernels, int(self._sing_index[r]),
                                         self.t_final[r], self.y_final[r].copy(),
                                         self.params[r].copy(), sc.t_span[0],
                                         self.initial[r].copy(), self._singular_tol)
            return info["reason"]
        if s == EVENT:
            hit = [k for k in range(len(self.event_names)) if self.event_counts[r, k]]
            return (f"terminal event at t = {self.t_final[r]:.17g} (events seen: "
                    f"{', '.join(self.event_names[k] for k in hit)})")
        return STATUS_TEXT[s]

    @property
    def stop_reasons(self) -> list[str]:
        """``stop_reason`` of every run (the status's text looked up once per run, the
        runs that stopped singular, at an event or past a chart's edge worded one by
        one)."""
        status = self.status
        out = [STATUS_TEXT[s] for s in status.tolist()]
        for r in {*self._reasons, *np.flatnonzero((status == SINGULAR)
                                                  | (status == EVENT)).tolist()}:
            out[r] = self.stop_reason(r)
        return out

    def diagnostics(self) -> dict[str, np.ndarray]:
        """Per-run diagnostics as arrays (for tables)."""
        out = dict(status=self.status, success=self.success, steps=self.steps,
                   rejected=self.rejected, rhs_evaluations=self.nfev, t_final=self.t_final,
                   residual_max=self.residual_max, energy_drift=self.energy_drift)
        if self.layout.holonomic:
            out["holonomic_residual_max"] = self.holonomic_residual_max
        if self.switching:
            out["switches"] = np.array([len(self.switches.get(r, ()))
                                        for r in range(self.n_runs)])
        out.update((f"drift[{name}]", v) for name, v in self.integral_drift.items())
        for k, name in enumerate(self.event_names):
            out[f"events[{name}]"] = self.event_counts[:, k]
            out[f"first[{name}]"] = self.event_first[:, k]
        return out

    def to_dataframe(self):
        """One row per run and output time: ``run``, ``t``, every state, dependent
        velocity and first integral, the run-time parameters (``numeric.export``)."""
        from .export import ensemble_dataframe

        return ensemble_dataframe(self)

    def _repr_html_(self):
        from ..display import ensemble_html

        return ensemble_html(self)

    def _repr_latex_(self):
        from ..display import ensemble_latex

        return ensemble_latex(self)

    def __repr__(self):
        ok = int(self.success.sum())
        return (f"<Ensemble {self.method}: {self.n_runs} runs x {self.y.shape[1]} rows, "
                f"{ok} succeeded, {self.wall_time * 1e3:.3g} ms ({self.parallel}, "
                f"{self.workers} workers)>")


def _largest(a) -> np.ndarray:
    """The largest entry of each run's rows of ``a`` ([n_runs, n_times, columns]) that
    is not NaN (NaN for a run without one)."""
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)     # (a run without rows)
        return np.nanmax(a.reshape(a.shape[0], -1), axis=1)


def run_ensemble(scene, initial=None, params=None, *, t_eval=None, save="final",
                 method="dop853", events=None, parallel="threads", workers=None,
                 project=False, on_error="raise", timeout=None, step=None, singular="stop",
                 newton=None, sensitivities=False, sensitivity_error=True,
                 **keywords) -> Ensemble:
    """Integrate ``scene`` from many initial states / parameter sets: see the module
    docstring.  The run options as ``Scene.run`` (``numeric.options``: the values
    ``step``, ``singular``, ``newton`` or their keywords ``rtol``, ``atol``, ...;
    ``sensitivities`` and ``sensitivity_error`` as there);
    ``max_steps`` and ``timeout`` are budgets of each run and of the whole ensemble;
    Ctrl-C stops every run within one step."""
    quick = None
    if (params is None and t_eval is None and events is None and timeout is None
            and step is None and newton is None and sensitivities is False
            and sensitivity_error is True):
        row = _one_row(scene, initial)
        if row is not None:
            # an ensemble of one row with options that are numbers and strings (a loop
            # of such calls): the plan of its run kept in the scene's memo under them
            # and the type of ``workers`` and of the keywords' numbers (``True == 1``,
            # but a bool is refused where 1 is not), as ``Scene.run`` keeps its plans,
            # at once
            try:
                quick = (method, save, singular, parallel, workers, on_error, type(workers))
                for k, v in keywords.items():
                    quick += (k, v, type(v))
                one, n_workers = scene._memo.get("quick_one", _NONE_KEPT)[quick]
            except (KeyError, TypeError) as exc:     # not planned yet, or not hashable
                quick = quick if type(exc) is KeyError else None
            else:
                y, p = _of_row(scene, row, project)
                return _of_one(scene, one, y, p, on_error, parallel, n_workers, save)
    opts = options(step, singular, newton, **keywords)
    if parallel not in PARALLEL:
        raise JetnhError(f"parallel must be one of {PARALLEL}, not {parallel!r}")
    if on_error not in ("raise", "record"):
        raise JetnhError(f"on_error must be 'raise' or 'record', not {on_error!r}")
    scene, Y0, P = resolve(scene, initial, params, project)
    if quick is not None:
        one = _one_plan(scene, opts, None, save, method, None, None, False, True)
        kept = scene._memo.setdefault("quick_one", {})
        if one:
            solve.keep(kept, quick, (one, _workers(workers)))
    return run_resolved(scene, Y0, P, opts, t_eval=t_eval, save=save, method=method,
                        events=events, parallel=parallel, workers=workers,
                        on_error=on_error, timeout=timeout, sensitivities=sensitivities,
                        sensitivity_error=sensitivity_error)


def _workers(workers) -> int:
    """The number of threads asked for: a positive integer, None for numba's count."""
    if workers is None:
        return int(numba.config.NUMBA_NUM_THREADS)
    if isinstance(workers, bool) or not isinstance(workers, numbers.Integral) or workers < 1:
        raise JetnhError(f"workers must be a positive integer (or None: numba's "
                         f"{numba.config.NUMBA_NUM_THREADS} threads), not {workers!r}")
    return int(workers)


def run_resolved(scene, Y0, P, opts, *, t_eval=None, save="final", method="dop853",
                 events=None, parallel="threads", workers=None, on_error="raise",
                 timeout=None, sensitivities=False, sensitivity_error=True) -> Ensemble:
    """``run_ensemble`` of the runs ``resolve`` gave (``scene``, the rows of ``Y0`` and
    ``P``) with the run options ``opts`` (``numeric.options.Options``)."""
    workers = _workers(workers)
    if Y0.shape[0] == 1:            # an ensemble of one: a run, where it can be
        one = _one_plan(scene, opts, t_eval, save, method, events, timeout, sensitivities,
                        sensitivity_error)
        if one:
            return _of_one(scene, one, Y0[0], P[0], on_error, parallel, workers, save)
    plan = _batch_plan(scene, opts, t_eval, save, method, events, timeout, sensitivities,
                       sensitivity_error)
    method = plan.method.name
    sens = Y_A = None
    if plan.sens is None:
        (OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T), wall = solve.batch(
            scene, plan, Y0, P, parallel, workers)
        _on_constraints(plan, P, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST)
    else:       # the state augmented by S = dy/d(y0, p): S apart, as in a single run
        (OUT_T, OUT_A, INFO, T_LAST, Y_A, EV_N, EV_T), wall = solve.batch(
            scene, plan, solve.augmented(scene, plan, Y0, P), P, parallel, workers)
        _on_constraints(plan, P, OUT_T, OUT_A, INFO, T_LAST, Y_A)
        n = Y0.shape[1]
        OUT_Y, Y_LAST = np.ascontiguousarray(OUT_A[:, :, :n]), Y_A[:, :n].copy()
        sens = (scene._sensitivity_columns(), OUT_A[:, :, n:].reshape(
            OUT_A.shape[0], OUT_A.shape[1], n, plan.sens.layout.sensitivity_columns))
    n_runs = Y0.shape[0]
    ce, switching, checked, singular_tol = plan.ce, plan.switch, plan.checked, plan.singular_tol
    n_user = len(plan.watch.ev_dir) - (1 if switching else 0)
    pieces, reasons, switches = {}, {}, {}
    if switching:
        tic = time.perf_counter()
        t0, t1 = plan.t0, plan.t1
        ctl, te, mode, limit = plan.ctl, plan.te, plan.mode, plan.limit
        chart_atlas = atlas.atlas(scene)
        user = as_events(events)
        budget = ctl.max_steps
        edge = ce.python_funcs[-1]
        own, S_all = chart_atlas.own, None if sens is None else sens[1]
        ends = []           # each piece's loop result: its last time and state

        def build(*args, **kw):
            ends.append(args[2])
            return solve.trajectory(*args, **kw)

        # runs past the edge at the start, and runs that reached it (or stopped singular,
        # perhaps past it): run again as a single run goes on (``atlas.follow``: the
        # step that reached the edge not kept)
        on = (INFO[:, 0] == SINGULAR) | ((EV_N[:, n_user] > 0) & (INFO[:, 0] == EVENT)
                                         & (T_LAST == EV_T[:, n_user]))
        for r in range(n_runs):
            if not on[r] and not edge(t0, Y0[r], P[r]) < 0.0:
                continue
            chart, y, first = atlas.begin(chart_atlas, user, t0, Y0[r], P[r])
            if not first and not on[r]:
                continue
            if sens is not None:        # S(t0) in the chart the run starts in (atlas.run)
                S0 = solve.augmented(scene, plan, Y0[r:r + 1], P[r])[0, Y0.shape[1]:]
                S0 = S0.reshape(1, Y0.shape[1], -1)
                if chart is not own:
                    S0 = own.carry(chart, t0, Y0[r], S0, P[r])
                y = np.concatenate((y, S0.ravel()))
            parts, sw = atlas.follow(chart_atlas, method, chart, t0, y, t1, P[r], user,
                                     np.zeros(n_user, np.int64), ctl, budget, te, mode,
                                     None, checked, singular_tol, plan.newton, limit,
                                     build, sens=sens is not None)
            INFO[r, 1:5] = 0
            EV_N[r], EV_T[r], OUT_T[r], OUT_Y[r] = 0, np.nan, np.nan, np.nan
            if S_all is not None:
                S_all[r] = np.nan
            pieces[r] = _taken_on(own, r, parts, ends[-1], n_user, mode, P[r], OUT_T, OUT_Y,
                                  INFO, T_LAST, Y_LAST, EV_N, EV_T, S_all)
            reasons[r], switches[r] = parts[-1][1].stop_reason, first + sw
        wall += time.perf_counter() - tic
    # never a success with a NaN or infinite state
    if not arguments.all_finite(OUT_Y, Y_LAST):
        done = (INFO[:, 0] == FINISHED) | (INFO[:, 0] == EVENT)
        INFO[done & ~(np.all(np.isfinite(Y_LAST), axis=1)
                      & np.all(np.isfinite(OUT_Y) | np.isnan(OUT_T)[:, :, None],
                               axis=(1, 2))), 0] = NONFINITE
    _explain(scene, method, plan.kern, checked, singular_tol, on_error, INFO, T_LAST,
             Y_LAST, P, Y0)
    return Ensemble(scene, method, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N[:, :n_user],
                    EV_T[:, :n_user], Y0, P, ce.names[:n_user] if ce is not None else (),
                    wall, parallel, workers if parallel != "serial" else 1, save,
                    singular_tol, switching=switching, switches=switches, pieces=pieces,
                    reasons=reasons, sensitivities=sens, layout=plan.kern.layout)


def _batch_key(scene, opts, t_eval, save, method, events, timeout, sensitivities,
               sensitivity_error) -> tuple:
    """The key of an ensemble's plan among the scene's plans (``solve.planned``)."""
    if (events is None and t_eval is None and timeout is None and sensitivities is False
            and sensitivity_error is True and type(method) is str and type(save) is str):
        return ("batch", scene.t_span, opts, method, save)     # the defaults, sooner
    key = ("batch", scene.t_span, opts, method, save, solve.hashable(events),
           solve.hashable(t_eval), timeout, sensitivities, sensitivity_error)
    return (key, tuple(map(type, key)))


def _batch_plan(scene, opts, t_eval, save, method, events, timeout, sensitivities,
                sensitivity_error) -> solve.Plan:
    """The plan of an ensemble's driver (``solve.plan(..., batch=True)``), kept."""
    key = _batch_key(scene, opts, t_eval, save, method, events, timeout, sensitivities,
                     sensitivity_error)
    return solve.planned(scene, key, lambda: solve.plan(
        scene, method, opts=opts, t_eval=t_eval, save=save, events=events, timeout=timeout,
        sensitivities=sensitivities, sensitivity_error=sensitivity_error, batch=True))


def _one_plan(scene, opts, *args):
    """The plan of the single run that gives an ensemble of one (``_single_plan``) of
    the ensemble's options (``_batch_plan``'s ``args``), kept with the plans under
    ``("one", key)`` of the ensemble's key; False where there is none."""
    key = ("one", _batch_key(scene, opts, *args))
    t_eval, save, timeout = args[0], args[1], args[4]
    return solve.planned(scene, key, lambda: _single_plan(
        scene, _batch_plan(scene, opts, *args), opts, t_eval, save, timeout))


def _single_plan(scene, plan, opts, t_eval, save, timeout):
    """The plan of a single run (``Scene.run``) that gives an ensemble of one of the
    ensemble's plan ``plan``, or False where the ensemble's driver must run it: with
    events, sensitivities or a chart's edge to watch, an implicit or fixed-step method,
    or holonomic constraints (whose rows ``_on_constraints`` moves)."""
    m = plan.method
    if (plan.ce is not None or plan.sens is not None or plan.switch or not m.adaptive
            or m.solver is not Solver.EXPLICIT or plan.ctl.n_hol):
        return False
    return solve.plan(scene, m, opts=opts, t_eval=t_eval, save=save, timeout=timeout)




def _of_one(scene, plan, y, p, on_error, parallel, workers, save) -> Ensemble:
    """The ensemble of the one run of the state ``y`` and the parameters ``p`` (1-d, rows
    of its Y0 and P) by the single-run loop of ``plan``
    (``_single_plan``): what the ensemble's driver stores of its run
    (``methods._common.collect``), the same steps.  Its arrays are views of the loop's
    own (no copies); the loop never reports a success with a NaN or an infinity in its
    rows or last state (``loop.finite_status``), as ``run_resolved`` makes sure of the
    driver's runs."""
    halt = solve._HALT.copy()
    tic = _clock()
    # (a direct plan's loop reads y0 into a copy of its own: the row itself)
    out = interrupt.call(plan.entry, halt, plan.limit, (*plan.head, y, p, *plan.suffix,
                                                        halt))
    wall = _clock() - tic
    endpoints = plan.mode == ENDPOINTS
    run = (out, endpoints, 1 if endpoints else plan.te.shape[0], y, p)
    arrays = None       # (made when read)
    if out[0] == NONFINITE:
        arrays = _one_arrays(*run)
        INFO, T_LAST = np.array(arrays[0], dtype=np.int64), np.array(arrays[1], dtype=float)
        _explain(scene, plan.method.name, plan.kern, plan.checked, plan.singular_tol,
                 on_error, INFO, T_LAST, arrays[2], arrays[6], arrays[5])
        arrays = (INFO, T_LAST, *arrays[2:])
    return Ensemble._of_run(scene, plan.method.name, run, arrays, wall, parallel,
                            workers if parallel != "serial" else 1, save, plan.singular_tol,
                            plan.kern.layout)


def _one_arrays(out, endpoints, n_times, y, p) -> tuple:
    """An ensemble's ``_arrays`` of the one run of ``y``, ``p`` whose loop returned
    ``out`` (``_of_one``; ``endpoints``: its first and last rows saved, else ``n_times``
    rows at ``t_eval``): views of the loop's own arrays and of ``y``, ``p`` (no
    copies)."""
    status, ts, ys, n_out, stats = out[:5]
    n = y.shape[0]
    # (a loop that watched nothing keeps its last time and state in row n_out)
    if len(out) == 6 or out[6] is None:     # (or a watching loop that finished)
        T_LAST, Y_LAST = ts[n_out:n_out + 1], ys[n_out:n_out + 1, :n]
    else:
        T_LAST, Y_LAST = (out[5],), out[6][None, :n]
    if endpoints:
        first, filled = n_out - 1, 1 if n_out > 0 else 0
    else:
        first, filled = 0, min(n_out, n_times)
    if filled == n_times:
        OUT_T, OUT_Y = ts[None, first:first + n_times], ys[None, first:first + n_times, :n]
    else:
        OUT_T, OUT_Y = np.full((1, n_times), np.nan), np.full((1, n_times, n), np.nan)
        OUT_T[0, :filled] = ts[first:first + filled]
        OUT_Y[0, :filled] = ys[first:first + filled, :n]
    # (status, steps, rejected, nfev, rows, indicator): an array on first read
    INFO = ((status, *stats, n_out, out[-1]),)
    return (INFO, T_LAST, Y_LAST, _NO_EV_N, _NO_EV_T, y[None, :], p[None, :], None, OUT_T,
            OUT_Y)


_clock = time.perf_counter


def _on_constraints(plan, P, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST):
    """The rows of an ensemble's runs that the dense output gave, moved onto the
    holonomic constraints g = 0 in place as a single run's are (``loops.on_constraints``,
    the same rows and the same bits): the rows at ``t_eval`` and the last state of a run
    stopped inside a step (a terminal event, a singular stop) with its row; with
    sensitivities (``OUT_Y``, ``Y_LAST`` the augmented states) S with them, rows at the
    start left."""
    ctl = plan.ctl
    if not ctl.n_hol:
        return
    kern, n_sens = (plan.kern, 0) if plan.sens is None else (plan.sens, ctl.n_sens)
    n_runs, n_times = OUT_T.shape
    t0 = plan.t0
    if plan.mode == AT_T_EVAL:
        ts, ys = OUT_T.reshape(-1), OUT_Y.reshape(n_runs * n_times, -1)
        pick = np.flatnonzero(np.isfinite(ts) & (ts != t0) if n_sens else np.isfinite(ts))
        rows = ys[pick]           # (the times are NaN after a run's stop)
        loops.onto_constraints(kern, ts[pick], rows, P[pick // n_times], n_sens)
        ys[pick] = rows
    stop = np.flatnonzero(((INFO[:, 0] == EVENT) | (INFO[:, 0] == SINGULAR))
                          & (T_LAST != t0))
    if stop.size:
        rows = Y_LAST[stop]
        loops.onto_constraints(kern, T_LAST[stop], rows, P[stop], n_sens)
        Y_LAST[stop] = rows
        if plan.mode == ENDPOINTS:          # the run's one row is its last state
            OUT_Y[stop, 0] = rows


def _taken_on(own, r, parts, end, n_user, mode, p, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N,
              EV_T, S=None):
    """Run ``r`` of an ensemble taken on past its chart's edge (``atlas.follow``): its
    rows, counts and events filled in after the edge, with ``S`` (the ensemble's
    sensitivities) its sensitivities in the scene's states (``Chart.carry``), as
    ``atlas.stitch`` gives a single run's; its last time and state from ``end``, the
    loop result of its last piece (which may have no rows at ``t_eval``); returns the
    pieces of its rows that other charts ran (``atlas.fill_aux``)."""
    row = 0 if mode == ENDPOINTS else int(INFO[r, 4])
    pieces = []
    for chart, seg, _ in parts:
        if mode == ENDPOINTS:
            a, b, row = len(seg.t) - 1, len(seg.t), 0
        else:
            a, b = 0, len(seg.t)
        if b > a:
            OUT_T[r, row:row + b - a] = seg.t[a:b]
            OUT_Y[r, row:row + b - a] = atlas.to_home(own, chart, seg.t[a:b], seg.y[a:b], p)
            if S is not None:
                Sc = seg.sensitivities[a:b]
                S[r, row:row + b - a] = (Sc if chart is own else
                                         chart.carry(own, seg.t[a:b], seg.y[a:b], Sc, p))
            pieces.append((row, row + b - a, chart, seg, a))
            row += b - a
        info = seg._info
        INFO[r, 1] += info["steps"]
        INFO[r, 2] += info["rejected"]
        INFO[r, 3] += info["nfev"]
        for i in range(n_user):
            if len(seg.t_events[i]):
                if not EV_N[r, i]:
                    EV_T[r, i] = seg.t_events[i][0]
                EV_N[r, i] += len(seg.t_events[i])
    if mode == ENDPOINTS:
        pieces = pieces[-1:]
    last_chart, last = parts[-1][0], parts[-1][1]
    INFO[r, 0] = last.status
    INFO[r, 4] = row if mode != ENDPOINTS else 1
    INFO[r, 5] = -1
    if len(last.t) and last.t[-1] == end.t:     # its last row: the last state
        T_LAST[r] = last.t[-1]
        Y_LAST[r] = atlas.to_home(own, last_chart, last.t[-1:], last.y[-1:], p)[0]
    else:
        n = len(last_chart.scene.state_names)
        T_LAST[r] = end.t
        Y_LAST[r] = atlas.to_home(own, last_chart, np.array([float(end.t)]),
                                  np.asarray(end.y)[:n].reshape(1, n), p)[0]
    return pieces


def _explain(scene, method, kern, checked, tol, on_error, INFO, T_LAST, Y_LAST, P, Y0):
    """Runs that hit NaN/inf: a singular stop when an indicator explains it, else an
    error (or status 3 with ``on_error="record"``).  Works on the run's own arrays
    (``INFO[:, 0]`` status, ``INFO[:, 5]`` the indicator), before the Ensemble freezes
    them."""
    status = INFO[:, 0]
    if status.shape[0] == 1:        # (an ensemble of one: no array test)
        bad = () if status[0] != NONFINITE else (0,)
    else:
        bad = np.flatnonzero(status == NONFINITE)
    t0 = scene.t_span[0]
    for r in bad:
        idx = (diagnosis.explain_nonfinite(scene, kern, T_LAST[r], Y_LAST[r], P[r], t0,
                                           Y0[r], tol)
               if checked else -1)
        if idx >= 0:
            INFO[r, 0] = SINGULAR
            INFO[r, 5] = idx
        elif on_error == "raise":
            try:
                diagnosis.raise_nonfinite(scene, f"{method} (ensemble run {r})", T_LAST[r],
                                          Y_LAST[r], kern, P[r], checked=checked)
            except IntegrationError as exc:
                raise IntegrationError(
                    f"{exc} [pass on_error='record' to keep the other runs; run {r} will "
                    "have status 3]") from None
