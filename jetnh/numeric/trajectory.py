"""Trajectories: the output of ``Scene.run``, indexed by Symbol, by name or by dynamicsymbol.

``traj.t`` is the array of output times and ``traj[x]`` / ``traj["x"]`` the column of a
coordinate, an independent velocity, a multiplier, a dependent velocity (computed from
the constraints by the compiled ``aux`` kernel, on first access) or a user first
integral.  ``traj.diagnostics`` reports the constraint residual, the energy and its
drift, first integrals and their drift, steps, right-hand-side evaluations and why the
integration stopped (and the split switches of a run that changed split,
``numeric.atlas``).  Where the energy is not conserved by design (generalized forces,
whose power Q_s qdot^s is ``traj.power``; an explicit t; Chetaev reactions that work:
``mechanics.energy``), the diagnostics say why.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields

import numpy as np

from ..errors import ArgumentError, JetnhError
from ..geometry.jet import key_name
from ..frozen import Frozen, FrozenDict, memo, readonly
from .methods._common import AT_T_EVAL, ENDPOINTS, EVERY_STEP, SINGULAR


@dataclass(frozen=True)
class Diagnostics:
    """What happened during one integration, and how well the invariants held
    (immutable: its mappings are read-only)."""

    method: str
    status: int
    stop_reason: str
    success: bool
    steps: int | None
    rejected: int | None
    rhs_evaluations: int
    wall_time: float
    residual_max: float            # max |f^a| over the output rows (see ``rows``)
    energy_initial: float
    energy_drift: float            # max |E - E(t0)| over the output rows (see ``rows``)
    energy_drift_relative: float   # energy_drift / |E(t0)|; NaN where E(t0) = 0 and it moved
    integral_drift: dict = field(default_factory=dict)
    projected: dict = field(default_factory=dict)
    events: dict = field(default_factory=dict)        # event name -> occurrences
    singularity: dict | None = None                   # see Trajectory.singularity
    forced: bool = False              # generalized forces work: the energy drifts by design
    holonomic_residual_max: float = 0.0   # max |g_i| of the holonomic constraints
    completed: dict = field(default_factory=dict)     # see Scene.completed
    switches: list = field(default_factory=list)      # split changes: {"t", "from", "to"}
    #: why the energy is not conserved by design (``mechanics.energy.changes``): its
    #: drift is then the motion's, not the integration's error; () where it is conserved
    energy_changes: tuple = ()
    #: how many output rows ``residual_max``, ``energy_drift``, ``integral_drift`` and
    #: ``holonomic_residual_max`` were taken over, and which rows the run stored:
    #: "steps" (every accepted step), "t_eval" (the output times, from the dense
    #: output) or "final" (t0 and the end alone: the figures are then end-point
    #: differences, which can be far below the largest error the run had on the way)
    rows: int = 0
    saved: str = "steps"
    #: a run stopped at a singular configuration whose last row is its stop (next to the
    #: singular set, where the dependent velocities are a near 0/0): that row, kept in
    #: the trajectory, is left out of the figures above and reported here, {"t",
    #: "energy_drift", "residual_max"}; None otherwise
    stop_row: dict | None = None

    def __post_init__(self):
        for name in ("integral_drift", "projected", "events", "singularity", "stop_row"):
            value = getattr(self, name)
            if isinstance(value, dict) and not isinstance(value, FrozenDict):
                object.__setattr__(self, name, FrozenDict(readonly(value)))

    def as_dict(self) -> dict:
        return asdict(self)

    def drift_text(self) -> str:
        """The energy drift with its relative value, or why that has none (an energy 0
        at the start): one wording for the printed diagnostics and the notebook view."""
        return _drift_text(self.energy_initial, self.energy_drift, self.energy_drift_relative)

    def rows_note(self) -> str:
        """Over which rows the figures were taken, where that is not every step of the
        run ("" where it is): the printed summary's and the notebook view's line."""
        return _rows_text(self)

    def __str__(self):
        lines = [f"{self.method}: {self.stop_reason} ({'success' if self.success else 'failure'})",
                 f"  steps {self.steps} (rejected {self.rejected}), rhs evaluations "
                 f"{self.rhs_evaluations}, {self.wall_time * 1e3:.3g} ms",
                 f"  constraint residual max {self.residual_max:.3e}"
                 + (f", holonomic (position level) {self.holonomic_residual_max:.3e}"
                    if self.holonomic_residual_max else ""),
                 "  " + _energy_text(self.energy_initial, self.energy_drift,
                                     self.energy_drift_relative)
                 + ("; not conserved: " + "; ".join(self.energy_changes)
                    if self.energy_changes else "")]
        for k, v in self.integral_drift.items():
            lines.append(f"  integral {k}: drift {v:.3e}")
        rows = self.rows_note()
        if rows:
            lines.append(f"  {rows}")
        for k, v in self.events.items():
            lines.append(f"  event {k}: {v} occurrence(s)")
        if self.switches:
            lines.append(f"  {_switches_text(self.switches)}")
        return "\n".join(lines)

    def __repr__(self):
        """Every field as the dataclass prints it, the split switches (one entry per
        switch: any number) as their count, the first and the last."""
        parts = [f"{f.name}={getattr(self, f.name)!r}" for f in fields(self)
                 if f.name != "switches"]
        if self.switches:
            parts.append(f"switches=<{_switches_text(self.switches)}>")
        else:
            parts.append("switches=[]")
        return f"Diagnostics({', '.join(parts)})"


def _switch_text(s) -> str:
    """One split switch: its time and the dependent coordinates before and after."""
    return f"t = {s['t']:.6g} ({', '.join(s['from'])} -> {', '.join(s['to'])})"


def _energy_text(initial, drift, relative) -> str:
    """The energy line of a run's diagnostics: its initial value and drift, or that the
    energy could not be evaluated (it overflows, or leaves the domain of an expression:
    a NaN or an infinity there is no drift of the motion)."""
    if not np.isfinite(initial):
        return (f"energy not evaluated: it is {initial} at the start (an overflow, or an "
                "expression outside its domain), so its drift is unknown")
    if not np.isfinite(drift):
        return (f"energy {initial:.12g}, drift not evaluated: the energy became NaN or "
                "infinite on the way (an overflow, or an expression outside its domain)")
    return f"energy {initial:.12g}, drift {_drift_text(initial, drift, relative)}"


def _drift_text(initial, drift, relative) -> str:
    if initial == 0.0 and drift > 0.0:
        return f"{drift:.3e} (relative: undefined, the energy is 0 at the start)"
    return f"{drift:.3e} (relative {relative:.3e})"


def _relative(drift, initial) -> float:
    """The energy drift relative to the initial energy: NaN where that is 0 and the
    energy moved (no scale to compare with: a number such as drift / 1e-300 would read
    as an enormous drift)."""
    if initial == 0.0:
        return 0.0 if drift == 0.0 else float("nan")
    return drift / abs(initial)


def _rows_text(d) -> str:
    """Over which rows a run's residual, energy and integral figures were taken, where
    that is not every step of the run ("" where it is)."""
    n = f"{d.rows} row{'s' if d.rows != 1 else ''}"
    if d.saved == "final":
        steps = f" of its {d.steps} steps" if d.steps else ""
        text = (f"these figures are over {n} (save='final'): differences between the ends, "
                f"not the largest on the way{steps} (save='steps' gives that)")
    elif d.saved == "t_eval":
        text = f"these figures are over {n} (t_eval): at the output times, not at the steps"
    else:
        text = ""
    if d.stop_row:
        s = d.stop_row
        stop = (f"leave out the last row, the singular stop at t = {s['t']:.10g} (next to "
                "the singular set its dependent velocities are a near 0/0): energy drift "
                f"{s['energy_drift']:.3e}, constraint residual {s['residual_max']:.3e} there")
        text = f"{text}; they {stop}" if text else f"these figures {stop}"
    return text


def _largest(a) -> float:
    """The largest entry of ``a`` (0 for none; NaN if one is)."""
    return float(np.max(a)) if a.size else 0.0


_SAVED = {EVERY_STEP: "steps", AT_T_EVAL: "t_eval", ENDPOINTS: "final"}


def _switches_text(switches) -> str:
    """The split switches of a run in one bounded line: their count, the first and the
    last."""
    n = len(switches)
    text = f"{n} split switch{'es' if n != 1 else ''}, the first at {_switch_text(switches[0])}"
    if n > 1:
        text += f", the last at {_switch_text(switches[-1])}"
    return text


def _read_only(a) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


def _info(steps, rejected, nfev, wall_time, projected) -> dict:
    """A run's counts, wall-clock time and projected initial values (``diagnostics``)."""
    return {"steps": steps, "rejected": rejected, "nfev": nfev, "wall_time": wall_time,
            "projected": dict(projected) if projected else {}}


def _columns(layout) -> tuple[dict, dict]:
    """Name -> column of the states and of the aux rows (dependent velocities, first
    integrals) of ``layout``; built once per layout."""
    hit = _COLUMNS.get(id(layout))
    if hit is None or hit[0] is not layout:
        k = len(layout.dependent_velocities)
        aux = {name: a for a, name in enumerate(layout.dependent_velocities)}
        aux.update({name: 2 * k + 1 + i for i, name in enumerate(layout.integrals)})
        hit = _COLUMNS[id(layout)] = (layout, {n: i for i, n in enumerate(layout.states)},
                                      aux)
    return hit[1], hit[2]


_COLUMNS: dict = {}
_new = object.__new__
_setattr = object.__setattr__


def _output(a, n) -> np.ndarray:
    """The first ``n`` rows of ``a`` (``memo`` makes them read-only)."""
    return a if a.shape[0] == n else a[:n]


class _Unloaded:
    """In an unpickled trajectory, the compiled kernels it was run with: their
    ``layout`` at once, anything else from the kernels loaded on first use (from the
    scene's disk cache, else generated: ``load`` names the scene's attribute, or
    "sensitivities"; None where the trajectory's kernels are none of the scene's)."""

    def __init__(self, scene, load, layout):
        self.scene, self.load, self.layout, self._kernels = scene, load, layout, None

    def __getstate__(self):
        return {"scene": self.scene, "load": self.load, "layout": self.layout,
                "_kernels": None}

    def __getattr__(self, name):
        if name.startswith("__") or name == "_kernels":
            raise AttributeError(name)
        if self._kernels is None:
            if self.load is None:
                raise JetnhError("this unpickled trajectory's compiled kernels are not "
                                 "its scene's, so they cannot be loaded here; evaluate it "
                                 "(traj.at, plots) before pickling it")
            if self.load == "sensitivities":
                from .kernels import sensitivity_kernels

                self._kernels = sensitivity_kernels(self.scene)
            else:
                self._kernels = getattr(self.scene, self.load)
        return getattr(self._kernels, name)

    @classmethod
    def of(cls, kernels, scene, method):
        """The stand-in of ``kernels``, a trajectory's of ``scene`` run by ``method``."""
        if isinstance(kernels, cls):
            return kernels
        load = {"dla": "dla_kernels", "dvi": "dvi_kernels"}.get(method, "kernels")
        return cls(scene, load if getattr(scene, load) is kernels else None,
                   kernels.layout)


class _Charts:
    """In an unpickled trajectory that changed split, its pieces (``atlas.Stitched``),
    whose charts' compiled code stays with the process that ran it: its aux rows came
    with it, evaluation between its rows is refused."""

    def _refuse(self, *args, **kwargs):
        raise JetnhError("this trajectory changed split and was unpickled: its charts' "
                         "compiled code stayed with the process that ran it, so it is "
                         "not evaluated between its rows here; call traj.at(...) before "
                         "pickling it, or pass the times as t_eval= to the run")

    aux = at = evaluate = stop = _refuse


class _EventList:
    """A trajectory's ``t_events`` or ``y_events`` where it recorded no event: one empty
    array (read-only) per event it watched (``event_names``; none: an empty list), made
    on first read (kept in its ``_memo``), not with every run."""

    def __set_name__(self, owner, name):
        self.name = name

    def __get__(self, obj, cls=None):
        if obj is None:
            return self
        found = obj._memo.get(self.name)
        if found is None:
            k = len(obj.event_names)
            shape = (0,) if self.name == "t_events" else (0, obj._rows[1].shape[1])
            found = obj._memo[self.name] = readonly([np.empty(shape) for _ in range(k)])
        return found


class _OfLoop:
    """An attribute of a trajectory made by ``_of_loop``, computed from its loop's result
    when read (the other trajectories hold it in ``__dict__``, which takes precedence)."""

    def __init__(self, fget):
        self.fget = fget

    def __get__(self, obj, cls=None):
        return self if obj is None else self.fget(obj)


class Trajectory(Frozen):
    """Output times ``t`` and states ``y`` (rows) of one run, with named access.

    Array orientation: ``traj.y`` is ``[n_times, n_states]`` (columns in the order
    ``scene.state_names``), ``traj[name]`` is ``[n_times]``; an ensemble's ``ens.y`` is
    ``[n_runs, n_times, n_states]``.  ``to_dataframe()``, ``to_xarray()`` and ``plot()``
    give every series by name (``jetnh.numeric.export``; ``plot`` and ``plot_path`` draw
    smooth curves through the dense output); ``at(times)`` evaluates the run between its
    rows, as a DataFrame (``jetnh.numeric.dense``).  Immutable (``jetnh.frozen``); the
    derived columns are computed on first access.  Picklable (results sent through
    multiprocessing or dask): the data travel, read-only again when unpickled, and the
    compiled kernels are loaded from the scene's cache on first use there (a run that
    changed split is then not evaluated between its rows: its charts stayed behind).
    """

    #: the stop at a singular configuration: {"indicator", "kind", "index", "t", "value",
    #: "initial", "reason"}, or None
    singularity = None
    event_names: tuple = ()
    #: methods that carry their own velocities, residuals, energy and first integrals (the
    #: discrete integrators dla, dvi): {"velocities": {name: col}, "residual", "energy",
    #: "integrals": {name: col}}
    _own = FrozenDict()
    #: a run that changed split: its pieces (``numeric.atlas.Stitched``, which gives its aux
    #: rows and dense output) and switches {"t", "from", "to"}
    _segments = None
    switches: tuple = ()
    #: a run with sensitivities: (column names, S [n_times, n_states, n_columns])
    _sens = None
    #: a run stopped after its last row (``t_eval``): the time and state where it stopped
    #: (``_stopped``; ``final``)
    _last = None
    #: ``_dense``: what re-taking a step (radau: re-solving it) needs (tolerances, output
    #: mode; numeric.dense)
    _dense = None
    #: which rows a run without ``_dense`` stored (scipy's methods, dla, dvi, rows
    #: sampled from another run): "steps", "t_eval" or "final" (``Diagnostics.saved``)
    _saved_rows = "steps"
    status = 0
    #: scipy's lists of event times and states (one per event), made on first read where
    #: the run had no events
    t_events = _EventList()
    y_events = _EventList()
    #: a trajectory of ``_of_loop``: the loop's result (status, ts, ys, n, stats, ...) and
    #: its wall-clock time, of which ``_rows`` and ``_counts`` are made when read
    _rows = _OfLoop(lambda self: self._loop[1:4])
    _counts = _OfLoop(lambda self: (self._loop[4], self._wall, self.scene.projected))

    def __init__(self, scene, t, y, p, *, method, status, stop_reason, steps, rejected,
                 nfev, wall_time, kernels, projected=None, own=None, events=None,
                 singularity=None, dense=None, segments=None, switches=(),
                 sensitivities=None, saved="steps"):
        t, y = np.ascontiguousarray(t, dtype=float), np.ascontiguousarray(y, dtype=float)
        t.setflags(write=False)         # (now: the caller's arrays may be these)
        y.setflags(write=False)
        self._fill(scene, (t, y, t.shape[0]), p, method, status, stop_reason,
                   ((steps, rejected, nfev), wall_time, projected), kernels, events,
                   singularity, dense, sensitivities, own, segments, switches)
        if saved != "steps":
            if saved not in _SAVED.values():
                raise ArgumentError(f"saved must be one of {tuple(_SAVED.values())}, "
                                    f"not {saved!r}")
            self.__dict__["_saved_rows"] = saved

    @classmethod
    def _of_run(cls, scene, rows, p, method, status, stop_reason, counts, kernels, events,
                singularity, dense, sensitivities, segments=None, switches=()
                ) -> "Trajectory":
        """What ``Trajectory(...)`` makes of ``rows = (t, y, n)`` (float64, C-contiguous
        and nobody else's: the arrays a compiled loop returned, of which the first ``n``
        rows are the output) and ``counts = ((steps, rejected, nfev), wall_time,
        projected)``, without converting them: a trajectory is made on every run
        (``segments``, ``switches``: a run that changed split, ``numeric.atlas``; its
        ``rows`` None, made on first read, its switches a tuple of records without
        arrays, taken as it is)."""
        self = object.__new__(cls)
        self._fill(scene, rows, p, method, status, stop_reason, counts, kernels, events,
                   singularity, dense, sensitivities, None, segments)
        if switches:
            self.__dict__["switches"] = switches
        self.__dict__["_memo"] = {}
        return self

    @classmethod
    def _finished(cls, scene, rows, p, method, stop_reason, counts, kernels, dense
                  ) -> "Trajectory":
        """``_of_run`` of a run that finished (status 0) without events, singularity or
        sensitivities (most runs), in one step."""
        self = object.__new__(cls)
        self.__dict__.update(scene=scene, _rows=rows, _p=p, _kernels=kernels, method=method,
                             status=0, stop_reason=stop_reason, t_events=[], y_events=[],
                             _dense=dense, _counts=counts, _memo={})
        return self

    @classmethod
    def _switched(cls, scene, p, method, stop_reason, counts, kernels, dense, segments,
                  switches) -> "Trajectory":
        """``_of_run`` of a run that changed split and finished (status 0) without
        events or sensitivities, in one step: its rows made from ``segments`` when first
        read (``numeric.atlas``), ``switches`` a tuple of records without arrays."""
        self = object.__new__(cls)
        self.__dict__.update(scene=scene, _rows=None, _p=p, _kernels=kernels, method=method,
                             status=0, stop_reason=stop_reason, t_events=[], y_events=[],
                             _dense=dense, _counts=counts, _segments=segments,
                             switches=switches, _memo={})
        return self

    @classmethod
    def _of_loop(cls, scene, out, p, method, stop_reason, wall, kernels, dense,
                 event_names=()) -> "Trajectory":
        """``_finished`` of the tuple ``out`` a compiled loop returned (finished, status
        0: the 6-tuple of a loop that watched nothing, or the 12 entries of one that
        watched and recorded no event) and the call's wall-clock time ``wall``: the tuple
        kept as it is (``_rows``, ``_counts`` made of it when read), the other attributes
        their class defaults, so that the most common run makes the fewest objects;
        ``event_names``: the events it watched (a tuple), each with no occurrence."""
        return cls._of_made(cls._made(kernels, method, stop_reason, dense, event_names),
                            scene, out, p, wall)

    @staticmethod
    def _made(kernels, method, stop_reason, dense, event_names=()) -> dict:
        """The ``__dict__`` of an ``_of_loop`` trajectory but for what differs from run to
        run (the scene, the loop's result, the parameters, the wall-clock time, the memo):
        made once per plan of runs (``solve.Plan.made``), copied by ``_of_made``."""
        d = {"scene": None, "_loop": None, "_p": None, "_kernels": kernels, "method": method,
             "stop_reason": stop_reason, "_wall": 0.0, "_dense": dense, "_memo": None}
        if event_names:
            d["event_names"] = event_names
        return d

    @classmethod
    def _of_made(cls, made, scene, out, p, wall) -> "Trajectory":
        """``_of_loop`` from ``made`` (``_made``): a copy of it with the run's own values
        (copying a dict of nine entries costs a fraction of building one)."""
        d = made.copy()
        d["scene"] = scene
        d["_loop"] = out
        d["_p"] = p
        d["_wall"] = wall
        d["_memo"] = {}
        self = _new(cls)
        _setattr(self, "__dict__", d)
        return self

    def _fill(self, scene, rows, p, method, status, stop_reason, counts, kernels, events,
              singularity, dense, sensitivities, own=None, segments=None, switches=()):
        """The attributes, each public array read-only (``Frozen._set``, without its walk
        over every value); ``t``, ``y`` and ``_info`` made on first access (``memo``: a
        run whose output is never read pays neither the slices nor the flags)."""
        d = self.__dict__
        d.update(scene=scene, _rows=rows, _p=p, _kernels=kernels, method=method,
                 status=status, stop_reason=stop_reason, t_events=[], y_events=[],
                 _dense=dense, _counts=counts)
        # the others where they differ from their defaults (the class attributes)
        if own:
            d["_own"] = own
        if segments is not None:
            d["_segments"] = segments
        if switches:
            d["switches"] = readonly(tuple(switches))
        if singularity is not None:
            d["singularity"] = FrozenDict(readonly(singularity))
        if events is not None:
            names, t_ev, y_ev = events
            d["event_names"] = tuple(names)
            if t_ev:
                d["t_events"] = readonly(list(t_ev))
            if y_ev:
                d["y_events"] = readonly(list(y_ev))
        if sensitivities is not None:
            d["_sens"] = (tuple(sensitivities[0]), _read_only(sensitivities[1]))

    # ------------------------------------------------------------------ pickling
    def __getstate__(self):
        """The data of the run (the output rows alone, the aux rows computed now), its
        compiled code replaced by what reloads it in another process (``_Unloaded``)
        or refuses what needs it there (``_Charts``)."""
        d = dict(self.__dict__)
        t, y = self.t, self.y
        d["_rows"] = (t, y, t.shape[0])
        if d.pop("_loop", None) is not None:        # (its buffers may hold more rows)
            d["_counts"] = self._counts
            del d["_wall"]
        d["_memo"] = {} if self._own else {"aux": self.aux}
        if self._segments is not None:      # (its last piece stays here)
            d["_memo"]["_stop"] = self._stop
        d["_kernels"] = _Unloaded.of(self._kernels, self.scene, self.method)
        if self._segments is not None:
            d["_segments"] = _Charts()
        dense = d.get("_dense")
        if dense is not None and "rhs" in dense and not isinstance(dense["rhs"], _Unloaded):
            d["_dense"] = {**dense, "rhs": _Unloaded(self.scene, "sensitivities",
                                                     dense["rhs"].layout)}
        return d

    def __setstate__(self, state):
        """Read-only again: every public array (and the output rows), as when run."""
        self.__dict__.update(state)
        t, y, _ = state["_rows"]
        readonly((t, y))
        for name in ("t_events", "y_events", "switches", "_own", "_memo"):
            if name in state:
                readonly(state[name])
        if "singularity" in state:
            self.__dict__["singularity"] = FrozenDict(readonly(dict(state["singularity"])))
        if "_sens" in state:
            readonly(state["_sens"][1])

    def __copy__(self):
        return self             # (immutable)

    @memo
    def t(self) -> np.ndarray:
        """The output times (read-only)."""
        rows = self._rows or self._stitched_rows()
        return _output(rows[0], rows[2])

    @memo
    def y(self) -> np.ndarray:
        """The states at the output times, ``[n_times, n_states]`` (read-only)."""
        rows = self._rows or self._stitched_rows()
        return _output(rows[1], rows[2])

    def _stitched_rows(self):
        """The output rows of a run that changed split (``_rows`` None until then),
        mapped to the scene's chart on first read (``numeric.atlas.Stitched.rows``)."""
        rows = self.__dict__["_rows"] = self._segments.rows(self._p)
        return rows

    @memo
    def _info(self) -> dict:
        counts, wall_time, projected = self._counts
        return _info(counts[0], counts[1], counts[2], wall_time, projected)

    @property
    def layout(self):
        return self._kernels.layout

    @property
    def success(self) -> bool:
        """scipy's convention: a terminal event is a success; a singular stop is not."""
        return self.status in (0, 5)

    # ------------------------------------------------------------------ access
    @property
    def names(self) -> tuple[str, ...]:
        lay = self.layout
        return lay.states + lay.dependent_velocities + lay.integrals

    def _name(self, key) -> str:
        name = key_name(key)
        if name is not None:
            return name
        raise JetnhError(f"index a trajectory by a Symbol, a name or a dynamicsymbol x(t) "
                         f"(x(t).diff() for x_t), not {type(key).__name__}")

    def __getitem__(self, key) -> np.ndarray:
        name = self._name(key)
        states, aux = _columns(self.layout)
        if name in states:
            return self.y[:, states[name]]
        own = self._own.get("velocities")
        if own is not None and name in own:
            return own[name]
        if name in self._own.get("integrals", {}):
            return self._own["integrals"][name]
        if name in aux:
            return self.aux[:, aux[name]]
        raise JetnhError(
            f"{name!r} is not in this trajectory; it has {', '.join(self.names)}")

    def __contains__(self, key) -> bool:
        return self._name(key) in self.names

    def __len__(self):
        return self.t.shape[0]

    @property
    def final(self) -> dict[str, float]:
        """Every coordinate, velocity, multiplier and integral where the run ended, at
        ``t_final``: the last row, or, for a run with ``t_eval`` that stopped early (a
        terminal event, a singular configuration, a step or time budget) after its last
        row, the state where it stopped, which the run keeps (in the chart of the scene's
        split for a run that changed split).  A stop whose state is not finite keeps
        none: ``final`` is then the last row, and ``stop_reason`` says where it stopped.
        A run that finished with ``t_eval`` ends at its last output time."""
        stop = self._stop
        if stop is None:
            return {name: float(self[name][-1]) for name in self.names} if len(self) else {}
        _, y, aux = stop
        states, columns = _columns(self.layout)
        out = {name: float(y[i]) for name, i in states.items()}
        out.update((name, float(aux[i])) for name, i in columns.items())
        return {name: out[name] for name in self.names}

    @property
    def t_final(self) -> float:
        """The time of ``final``: the last row's, or that of the state where a run with
        ``t_eval`` stopped after its last row (NaN: no rows, no such state)."""
        stop = self._stop
        if stop is not None:
            return stop[0]
        return float(self.t[-1]) if len(self) else math.nan

    def _stopped(self, t, y) -> None:
        """Keep ``(t, y)``, the state where the run stopped (the compiled loop's last
        time and state), for ``final``; a state that is not finite is not kept."""
        y = np.array(y, dtype=float)
        if math.isfinite(t) and np.isfinite(y).all():
            y.setflags(write=False)
            self.__dict__["_last"] = (float(t), y)

    @memo
    def _stop(self):
        """``(t, state, aux row)`` where the run stopped, in this trajectory's layout, or
        None where that is its last row (``final``); a run that changed split takes it
        from its last piece, mapped to the scene's chart (``atlas.Stitched.stop``)."""
        if self._segments is not None:
            return self._segments.stop(self._p)
        if self._last is None or self._own:     # (discrete methods: no t_eval)
            return None
        t, y = self._last
        aux = np.empty((1, self.layout.n_aux))
        self._kernels.aux_rows(np.array([t]), y[None, :], self._p, aux)
        return t, y, aux[0]

    def as_dict(self) -> dict[str, np.ndarray]:
        out = {"t": self.t}
        out.update({name: self[name] for name in self.names})
        return out

    @property
    def events(self) -> dict[str, dict[str, np.ndarray]]:
        """Event name -> {"t": times, state name: values} of its occurrences."""
        out = {}
        for name, te, ye in zip(self.event_names, self.t_events, self.y_events):
            d = {"t": te}
            ye = ye.reshape(-1, len(self.layout.states))
            d.update({s: ye[:, i] for i, s in enumerate(self.layout.states)})
            out[name] = d
        return out

    def sensitivity(self, of, to) -> np.ndarray:
        """``d of(t) / d to`` over ``t`` (read-only): ``of`` a state (coordinate,
        independent velocity or multiplier), ``to`` an initial value of a state (at t0)
        or a runtime parameter, by Symbol or by name; from the variational equations
        integrated with the run (``scene.run(sensitivities=True)``).

        With holonomic constraints g = 0 the initial configuration varies along g = 0 in
        the split's chart (``numeric.initial``): the coordinates that follow from g at
        the start (the split's dependent ones where dg/dq over them is regular, as
        ``linearize`` and ``complete=True`` take them) move with the independent
        coordinate or runtime parameter differentiated by, ``dq^D/dq^I = -(dg/dq^D)^{-1}
        dg/dq^I``, so ``dg/dq S + dg/dp = 0`` from t0 on; a sensitivity to one of those
        coordinates is refused (a ``JetnhError`` naming the independent ones)."""
        if self._sens is None:
            raise JetnhError("this trajectory carries no sensitivities; run the scene with "
                             "sensitivities=True")
        columns, S = self._sens
        states = self.layout.states
        a, b = self._name(of), self._name(to)
        if a not in states:
            raise JetnhError(f"sensitivity of {a!r}: not a state of this trajectory; the "
                             f"states are {', '.join(states)}")
        if b not in columns:
            raise JetnhError(f"sensitivity to {b!r}: not an initial value of a state or a "
                             f"runtime parameter; choose one of {', '.join(columns)} (a "
                             "compiled-in parameter needs runtime_params=[...] on the scene)")
        if self._followers:
            from .initial import check_column

            check_column(self.scene, b, self._followers)
        return S[:, states.index(a), columns.index(b)]

    @memo
    def _followers(self) -> frozenset:
        """The coordinates that follow from the holonomic constraints at the first row
        (``initial.followers``): no column of sensitivities of their own."""
        if not self.scene.system.holonomic or not len(self.t):
            return frozenset()
        from .initial import followers

        return followers(self.scene, self.t[0], self.y[0], self._p)

    @property
    def sensitivities(self) -> np.ndarray:
        """S = dy(t)/d(y(t0), p) at every row: ``[n_times, n_states, n_columns]``, columns
        ``sensitivity_columns`` (read-only)."""
        if self._sens is None:
            raise JetnhError("this trajectory carries no sensitivities; run the scene with "
                             "sensitivities=True")
        return self._sens[1]

    @property
    def sensitivity_columns(self) -> tuple[str, ...]:
        """What the columns of ``sensitivities`` differentiate by: the initial states,
        then the runtime parameters."""
        return () if self._sens is None else self._sens[0]

    # ------------------------------------------------------------------ derived columns
    @memo
    def aux(self) -> np.ndarray:
        """Rows of (dependent velocities, constraint residuals, energy, integrals)."""
        if self._own:
            raise JetnhError(f"{self.method} trajectories carry their own velocities, "
                             "residuals, energy and first integrals (no aux rows)")
        if self._segments is not None:
            return self._segments.aux(self)
        out = np.empty((len(self), self.layout.n_aux))
        if len(self):
            self._kernels.aux_rows(self.t, self.y, self._p, out)
        return out

    @property
    def energy(self) -> np.ndarray:
        """E = qdot^s dF/dqdot^s - F, F = L + lambda_a f^a, on the constraints."""
        if "energy" in self._own:
            return self._own["energy"]
        return self.aux[:, self.layout.energy_index]

    @property
    def power(self) -> np.ndarray:
        """P = Q_s qdot^s, the power of the generalized forces (zeros without forces)."""
        lay = self.layout
        if lay.power:
            return self.aux[:, lay.n_aux - 1 - lay.holonomic]
        if self.scene.system.forced:
            raise JetnhError(f"{self.method} trajectories carry no power column; run the "
                             "scene with an adaptive or rk4 method for traj.power")
        return np.zeros(len(self))

    @property
    def residual(self) -> np.ndarray:
        """The constraints f^a as written by the user, at every output row (columns: a)."""
        if "residual" in self._own:
            return self._own["residual"]
        k = len(self.layout.dependent_velocities)
        return self.aux[:, k:2 * k]

    @property
    def holonomic_residual(self) -> np.ndarray:
        """The holonomic constraints g_i(t, q) at every output row (columns: i; none
        without holonomic constraints)."""
        system = self.scene.system
        m = len(system.holonomic)
        if not m:
            return np.zeros((len(self), 0))
        if not self._own:
            return self.aux[:, self.layout.n_aux - m:]
        # the discrete methods carry no aux rows: g evaluated on the coordinates
        from ..algebra import dag

        J = system.J
        point = {J.t: self.t, **{q: self.y[:, i] for i, q in enumerate(J.q)}}
        values = {**self.scene.params, **dict(zip(self.scene.runtime_params,
                                                   np.asarray(self._p).tolist()))}
        point.update((s, values[s.name]) for s in system.parameters)
        cols = dag.evaluate_numpy(list(system.holonomic), point)
        return np.column_stack([np.broadcast_to(c, self.t.shape) for c in cols])

    def integral(self, name) -> np.ndarray:
        return self[name]

    @memo
    def diagnostics(self) -> Diagnostics:
        n = len(self)
        # a run stopped at a singular configuration keeps as its last row its stop, next
        # to the singular set, where the dependent velocities are a near 0/0: that row is
        # left out of the figures and reported apart (``Diagnostics.stop_row``)
        sing = self.singularity
        cut = (self.status == SINGULAR and n > 1 and not self._own and sing is not None
               and sing["t"] == float(self.t[-1]))
        rows = slice(0, n - 1 if cut else n)
        res = self.residual
        rmax = _largest(np.abs(res[rows]))
        hol = self.holonomic_residual
        hmax = _largest(np.abs(hol[rows]))
        E = self.energy
        e0 = float(E[0]) if E.size else float("nan")
        drift = _largest(np.abs(E[rows] - e0))
        idrift = {}
        for name in self.layout.integrals:
            col = self[name]
            idrift[name] = _largest(np.abs(col[rows] - col[0])) if col.size else 0.0
        stop_row = None
        if cut:
            stop_row = {"t": float(self.t[-1]), "energy_drift": float(abs(E[-1] - e0)),
                        "residual_max": _largest(np.abs(res[-1]))}
        i = self._info
        return Diagnostics(
            method=self.method, status=self.status, stop_reason=self.stop_reason,
            success=self.success, steps=i["steps"], rejected=i["rejected"],
            rhs_evaluations=i["nfev"], wall_time=i["wall_time"], residual_max=rmax,
            energy_initial=e0, energy_drift=drift,
            energy_drift_relative=_relative(drift, e0) if E.size else 0.0,
            integral_drift=idrift, projected=i["projected"],
            events={n: len(te) for n, te in zip(self.event_names, self.t_events)},
            singularity=self.singularity, forced=self.scene.system.forced,
            holonomic_residual_max=hmax, completed=dict(self.scene.completed),
            switches=[dict(s) for s in self.switches],
            energy_changes=self.scene.energy_changes,
            rows=rows.stop, saved=self._saved(), stop_row=stop_row)

    def _saved(self) -> str:
        """Which rows the run stored: "steps" (every accepted step), "t_eval" (the
        output times) or "final" (t0 and the end alone), as the run was made: the
        output mode of its dense output, or what a run without one said
        (``saved=``)."""
        d = self._dense
        return self._saved_rows if d is None else _SAVED[d["mode"]]

    # ------------------------------------------------------------------ tables, figures
    def to_dataframe(self, diagnostics=True):
        """A pandas DataFrame: ``t``, the coordinates, every velocity, the multipliers
        (then first integrals, ``energy``, ``residual[a]``); ``attrs`` hold method,
        status, stop_reason, principle and parameters (see ``numeric.export``)."""
        from .export import to_dataframe

        return to_dataframe(self, diagnostics)

    def to_xarray(self, diagnostics=True):
        """An xarray Dataset over ``t`` with the DataFrame's series and attributes
        (``parameters`` as a JSON object); needs ``pip install 'jetnh[xarray]'``."""
        from .export import to_xarray

        return to_xarray(self, diagnostics)

    def plot(self, names=None, ax=None, *, x="t", y=None, steps=False, smooth=True):
        """Plot series of the run; returns the matplotlib Axes.

        Parameters
        ----------
        names, y : str, Symbol or list, optional
            The series on the vertical axis (``y`` is another spelling of ``names``);
            default: the coordinates.
        ax : matplotlib Axes, optional
            Where to draw; default: the axes of a new figure.
        x : str or Symbol, default "t"
            The series on the horizontal axis: ``traj.plot(x="x", y="y")`` is a phase or
            path plot (``plot_path`` also gives both axes one scale).
        steps : bool, default False
            Mark the stored rows (the accepted steps) with dots.
        smooth : bool, default True
            Draw the curves through the method's dense output between the rows (dop853,
            dopri5, radau, rk4); the rows alone where there is none.
        """
        from .export import plot

        if y is not None:
            if names is not None:
                raise ArgumentError("give the vertical series once: names= or y=")
            names = y
        return plot(self, names, ax, x=x, steps=steps, smooth=smooth)

    def plot_path(self, x="x", y="y", ax=None, *, steps=False, smooth=True):
        """The path of the run in the plane of the series ``x`` and ``y`` (default: the
        coordinates named x and y), both axes on one scale, the start marked by a dot;
        see ``plot`` for the parameters.  Returns the matplotlib Axes."""
        from .export import plot

        return plot(self, y, ax, x=x, steps=steps, smooth=smooth, path=True)

    def at(self, times):
        """The states at ``times`` inside the span, from the method's dense output.

        dop853, dopri5: the covering step re-taken, bit for bit what ``t_eval`` gives;
        radau: the step's collocation polynomial, what ``t_eval`` gives to the run's
        ``newton_tol``; rk4: cubic Hermite.  Needs every step stored (no ``t_eval``,
        ``save="steps"``).
        A run that changed split is evaluated in the chart that ran at each time.

        Parameters
        ----------
        times : float or array_like
            In any order, inside the span.

        Returns
        -------
        pandas.DataFrame
            One row per time (the index, named ``t``), one column per state in the order
            ``scene.state_names``: ``traj.at([2.5])["x"]``; ``.to_numpy()`` is the
            ``[len(times), n_states]`` array.
        """
        import pandas as pd

        from .dense import evaluate

        y = (self._segments.at(self, times) if self._segments is not None
             else evaluate(self, times))
        return pd.DataFrame(y, columns=list(self.layout.states),
                            index=pd.Index(np.atleast_1d(np.asarray(times, dtype=float)),
                                           name="t"))

    def _repr_html_(self):
        from ..display import trajectory_html

        return trajectory_html(self)

    def _repr_latex_(self):
        from ..display import trajectory_latex

        return trajectory_latex(self)

    def __repr__(self):
        span = f"t in [{self.t[0]:.6g}, {self.t[-1]:.6g}]" if len(self) else "empty"
        n = len(self.switches)
        switches = f", {n} split switch{'es' if n != 1 else ''}" if n else ""
        return (f"<Trajectory {self.method}: {len(self)} rows, {span}{switches}, "
                f"{self.stop_reason}>")
