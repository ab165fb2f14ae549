"""Single shooting: runs of one scene from the start with the initial unknowns ``u``,
the endpoint residual and its Jacobian from the exact sensitivities (the runs of
``scene.run(sensitivities=True)``'s plan, never finite differences), each read off its
compiled loop's last row (``Shot``: a trial of the search makes no Trajectory).  A run
that reaches the edge of the scene's split stops there (the plan watches it) and goes
on across it as ``scene.run`` does (``Shot``: its sensitivities carried through each
change of split, ``numeric.atlas``)."""

from __future__ import annotations

import math
import time

import numpy as np

from ...errors import JetnhError
from .. import arguments, atlas, interrupt, solve
from ..methods._common import EVENT, FINISHED, SINGULAR, STIFF, Status
from ..options import options
from .small import all_finite, finite_vector, max_abs, thin_svd

#: the measure of the scene's split (``verdicts.split_measure``) below which a run that
#: stopped early stopped at the edge of its chart
EDGE = 1e-2
#: steps a shooting run may take (a run that needs more counts as failed)
MAX_STEPS = 20_000
#: the measure of the scene's split at which a shooting run that cannot change split
#: stops (``edge_event``): its minor at 1 % of the Gram scale, where the loop would
#: start watching an indicator for a crawl; below it the motions that cannot change
#: split crawl toward the singular set (thousands of steps a run)
EDGE_STOP = 1e-4


def _parts(plan):
    """What every run of ``plan`` shares, kept per plan (the last 64; a plan is hashed
    by identity): ``(n, m, the first row, the loop's arguments before the state, those
    after p)``.  The first row of a run with sensitivities but for its state: zeros,
    then the initial sensitivities S0 = (I | 0) (n x m) flattened (the derivatives by
    every state of an inner segment, the Newton Jacobian's columns, on the constraints
    or off them; with holonomic constraints ``Shooter.first_row`` starts the search's
    first segment from ``solve.augmented``'s S0 instead, along g = 0); a run's row is a
    copy with the state written in."""
    found = _PARTS.get(plan)
    if found is None:
        lay = plan.sens.layout
        n, m = lay.n_state, lay.sensitivity_columns
        row = np.concatenate((np.zeros(n), np.eye(n, m).ravel()))
        row.setflags(write=False)
        if len(_PARTS) >= 64:
            _PARTS.clear()
        found = _PARTS[plan] = (n, m, row, (*plan.prefix, plan.t0, plan.t1),
                                tuple(plan.suffix))
    return found


_PARTS: dict = {}


class Shot:
    """One shooting run as its compiled loop left it: the end time ``t``, the final
    state ``y`` and its sensitivities ``S`` (n x columns), read off the loop's last row;
    the ``Trajectory`` (``solve.trajectory``, what ``solve.run`` would have made) only
    when asked for -- the trials of the search need the end alone."""

    __slots__ = ("t", "y", "S", "_made", "_trajectory")

    @classmethod
    def of(cls, scene, plan, y, p, stops=None, watch=None, first=None):
        """The run of ``plan`` (with sensitivities, a compiled explicit loop) from the
        state ``y`` with the run-time parameters ``p``, or None where it does not reach
        the end of its span or ends in a non-finite state (``stops``, a dict: its status
        counted there); ``watch``: ``(run, halt)`` of an ``interrupt.shared`` watch the
        runs share (a plan without a timeout), else the run has a watch of its own;
        ``first``: the loop's first row (``y``, then S0: ``Shooter.first_row``), where
        the caller has made it (the run's own array)."""
        if plan.switch and not plan.ce.python_funcs[-1](plan.t0, y, p) >= 0.0:
            # past the edge of the scene's split at t0: the run starts in another
            return cls._across(scene, plan, y, p, stops)
        n, m, row, head, tail = _PARTS.get(plan) or _parts(plan)
        if first is None:
            first = row.copy()
            first[:n] = y
        if watch is not None and plan.limit is None:
            run, halt = watch
            tic = time.perf_counter()
            out = run(plan.entry, (*head, first, p, *tail, halt))
        else:
            halt = np.zeros(1, dtype=np.int64)
            tic = time.perf_counter()
            out = interrupt.call(plan.entry, halt, plan.limit,
                                 (*head, first, p, *tail, halt))
        wall = time.perf_counter() - tic
        status, n_out = out[0], int(out[3])
        if (status == EVENT or status == SINGULAR) and plan.switch:
            # at the edge of the scene's split (connect's runs watch no other event), or
            # stopped singular past it: the run taken across it as Scene.run does
            return cls._across(scene, plan, first[:n], p, stops, out, first)
        if status != FINISHED or n_out < 1:
            if stops is not None:
                stops[int(status)] = stops.get(int(status), 0) + 1
                # where it stopped (the loop's last state where it returns one, else its
                # last row) and the indicator it stopped on (-1: none)
                if len(out) == 12:
                    stops["y"] = (int(status), float(out[5]), np.array(out[6][:n]),
                                  int(out[-1]))
                else:
                    stops["y"] = (int(status), float(out[1][n_out - 1]),
                                  np.array(out[2][n_out - 1][:n]), -1) if n_out else None
            return None
        last = out[2][n_out - 1]
        S = last[n:]
        # the loop has checked the state (``loop.finite_status``), not its sensitivities
        if not finite_vector(S):
            return None
        self = object.__new__(cls)
        self.t, self.y, self.S = float(out[1][n_out - 1]), last[:n], S.reshape(n, m)
        self._made, self._trajectory = (scene, plan, out, wall, first, p), None
        return self

    @classmethod
    def _across(cls, scene, plan, y, p, stops, out=None, first=None):
        """``of`` for a run that reached the edge of the scene's split (its loop's
        tuple ``out`` from ``first``, y then S0; None: the start is past it): taken on across it as
        ``solve.run`` takes it (``atlas.end_across``; its sensitivities carried across
        each switch, its end in the scene's states), or None.  Its Trajectory is
        ``solve.run``'s, made when asked for."""
        if out is None:
            tr = solve.run(scene, plan, y.copy(), p)
            status = tr.status
            t, y_end = float(tr.t[-1]), tr.y[-1]
            S = tr.sensitivities[-1] if status == FINISHED else None
        else:
            tr = None
            status, t, y_end, S = atlas.end_across(scene, plan, out, first, p)
        if status != FINISHED or not arguments.all_finite(y_end) or not \
                arguments.all_finite(S):
            if stops is not None:
                stops[int(status)] = stops.get(int(status), 0) + 1
                # (its indicators are those of the chart it stopped in: not named here)
                stops["y"] = (int(status), t, np.array(y_end), -1)
            return None
        self = object.__new__(cls)
        self.t, self.y, self.S = t, y_end, S
        self._made, self._trajectory = (scene, plan, y.copy(), p), tr
        return self

    @property
    def trajectory(self):
        """The run's ``Trajectory`` (made on first access, then kept)."""
        if self._trajectory is None and len(self._made) == 4:     # across an edge
            scene, plan, y, p = self._made
            self._trajectory = solve.run(scene, plan, y.copy(), p)
        if self._trajectory is None:
            scene, plan, out, wall, y, p = self._made
            self._trajectory = solve.trajectory(
                scene, plan.method.name, out, wall, plan.kern, plan.ce, p, plan.t0, y,
                plan.singular_tol, plan.checked, plan.limit,
                {**plan.dense, "partial_last": False},
                n_events=_events_shown(plan), sens=plan.sens)
        return self._trajectory


def edge_event(scene):
    """``[Event]``: the edge of ``scene``'s split where its runs cannot change split
    (``atlas.applies`` false), det(A_alpha)^2 - ``EDGE_STOP`` det(A A^T) falling through
    0 (A = df/dqdot; the form of ``atlas.Atlas.edge``), terminal; None where the runs
    change split at their edge, where the split's minor is constant, or where it has
    more than ``atlas.MAX_K`` rows (a symbolic determinant too large to compile)."""
    found = scene._memo.get("shooting_edge", scene)
    if found is scene:
        from ..events import Event

        system = scene.system
        found = None
        if (0 < system.k <= atlas.MAX_K and not atlas.applies(scene, None)
                and not all(e.is_number for e in system.jacobian_dependent)):
            A = system.jacobian
            Ad = system.jacobian_dependent
            gram = A * A.T
            if system.k == 1:
                expr = Ad[0, 0]**2 - EDGE_STOP * gram[0, 0]
            else:
                expr = (Ad.det(method="berkowitz")**2
                        - EDGE_STOP * gram.det(method="berkowitz"))
            found = [Event(expr, terminal=True, direction=-1, name=atlas.EDGE)]
        scene._memo["shooting_edge"] = found
    return found


def _events_shown(plan):
    """How many of ``plan``'s events a Trajectory of its run reports: all but the edge
    of the split it watches last (the atlas's, or ``edge_event``'s); None: all."""
    ce = plan.ce
    return len(ce) - 1 if ce is not None and ce.names[-1] == atlas.EDGE else None


def _crawled(plan, p, y0, t, y, index):
    """Where a run of ``plan`` from ``y0`` stopped as singular at ``(t, y)`` on the
    indicator ``index`` before it reached its threshold (``diagnosis.singularity``'s
    test: the loop stopped it crawling toward the zero; ``p``: the run-time
    parameters), the indicator's value there relative to its initial one; else None."""
    kern = plan.kern
    m = len(kern.layout.indicators)
    g0, g = np.empty(m), np.empty(m)
    kern.sing(float(plan.t0), np.ascontiguousarray(y0, dtype=float), p, g0)
    kern.sing(float(t), np.ascontiguousarray(y, dtype=float), p, g)
    with np.errstate(all="ignore"):
        rel = float(g[index] / g0[index])
    crawled = math.isfinite(rel) and rel > 4 * plan.singular_tol and rel > 1e-12
    return rel if crawled else None


def _near(scene, plan, t, y, y0) -> str:
    """The singular set the state ``y`` at ``t`` of a run of ``plan`` from ``y0`` is
    near (``diagnosis.near_singular``), or ""."""
    from .. import diagnosis

    near = diagnosis.near_singular(scene, plan.kern, t, np.ascontiguousarray(y),
                                   scene._p, plan.t0, np.ascontiguousarray(y0, dtype=float))
    return "" if near is None else near[0]


def first_values(motion) -> tuple[list, list]:
    """``(state, aux)`` at t0 of ``motion`` (a ``Shot`` or a Trajectory), as lists: its
    Trajectory's first row and the auxiliary values there (``Trajectory.aux``: the
    dependent velocities first); a Shot's read off its loop's output (the same
    numbers), its Trajectory not made."""
    if isinstance(motion, Shot) and motion._trajectory is None and len(motion._made) == 6:
        _, plan, out, _, _, p = motion._made
        t, y, kern = out[1][:1], out[2][:1, :len(motion.y)], plan.kern
    else:
        tr = motion.trajectory if isinstance(motion, Shot) else motion
        t, y, kern, p = tr.t[:1], tr.y[:1], tr._kernels, tr._p
    aux = np.empty((1, kern.layout.n_aux))
    kern.aux_rows(t, y, p, aux)
    return y[0].tolist(), aux[0].tolist()


class OutOfTime(Exception):
    """The wall-clock budget of ``connect(timeout=)`` has passed (raised by a run of the
    search, past every route's handling: not a ``JetnhError``)."""


#: the rounding of a coordinate's value, in units of its size: a miss below this many
#: ulps of max(|start|, |end|) is below the resolution of the doubles themselves
ROUNDING = 16.0 * np.finfo(float).eps


#: a named coordinate's end is met relative to its own displacement, at least this
#: fraction of the largest one; one that ends where it started, relative to the
#: largest (it leaves and returns: the integration resolves it relative to the path)
SMALLEST_MOVE = 1e-3


def end_scale(start, end) -> np.ndarray:
    """The search's scale of each named end coordinate's miss (its weighting and its
    first stopping test; not what ``tol`` is checked against, ``own_scale``): its own
    displacement |end - start|, at least ``SMALLEST_MOVE`` times the largest
    displacement of the named coordinates, or the largest where it ends where it
    started; where none moves (a loop), the configuration's size max |start|, and 1
    only where that is 0 too; plus the rounding of the values (``ROUNDING``
    max(|start|, |end|)), the resolution of the doubles that hold them.  (On Python
    floats: a few entries, where numpy's calls cost ~10 us a connect.)"""
    start = [float(v) for v in start]
    end = [float(v) for v in end]
    move = [abs(b - a) for a, b in zip(start, end)]
    size = max(move, default=0.0)
    if size == 0.0:
        size = max(map(abs, start), default=0.0)
    if size == 0.0:
        size = 1.0
    return np.array([(max(d, SMALLEST_MOVE * size) if d > 0 else size)
                     + ROUNDING * max(abs(a), abs(b))
                     for d, a, b in zip(move, start, end)], dtype=float)


def own_scale(start, end, excursion) -> list:
    """What ``connect``'s ``tol`` is relative to: ``end_scale`` for a named coordinate
    that moves, but for one that returns to its start its own ``excursion`` along the
    motion found (max over t of |q(t) - q(t0)|, in its own units, never another
    coordinate's displacement), plus the rounding of its values (``ROUNDING``
    max(|start|, |end|)); 0 only where it is 0 and never moves (its miss is then 0
    too).  (Still in another's units: the ``SMALLEST_MOVE`` floor of one that moves.)"""
    start, end = [float(v) for v in start], [float(v) for v in end]
    scale = end_scale(start, end).tolist()
    return [s if b != a else e + ROUNDING * abs(a)
            for s, a, b, e in zip(scale, start, end, excursion)]


def excursion(motion, rows) -> list:
    """max over t of |y_r(t) - y_r(t0)| along ``motion`` (a ``Shot`` or a Trajectory)
    for each state row r of ``rows``, over its steps (a Shot's read off its loop's
    output, its Trajectory not made)."""
    if isinstance(motion, Shot) and motion._trajectory is None and len(motion._made) == 6:
        out = motion._made[2]
        y = out[2][:int(out[3])]
    else:
        y = (motion.trajectory if isinstance(motion, Shot) else motion).y
    y = np.asarray(y)[:, rows]
    return np.max(np.abs(y - y[0]), axis=0).tolist()


def relative_miss(miss, scale) -> float:
    """max miss / scale over the conditions (a 0 miss of a 0 scale is 0, any other
    miss of it infinite)."""
    return max([a / b if b > 0 else (0.0 if a == 0 else np.inf)
                for a, b in zip(miss, scale)], default=0.0)


def _speed(q0, q1, T) -> float:
    """The straight line's speed scale: the largest displacement start -> end of the
    named coordinates over T (``end_scale``'s fallbacks where none moves)."""
    return float(end_scale([q0[c] for c in q1], [q1[c] for c in q1]).max()) / abs(T)


class Shooter:
    """Runs of one scene from the start with the unknowns ``u``: the endpoint residual
    and its Jacobian from the sensitivities.  ``deadline`` (``time.monotonic()``, or
    None): no run starts after it (``OutOfTime``); ``stops``: the runs that stopped
    early, by status, and as "edge" those that stopped near the edge of the scene's
    split (its measure below ``verdicts.EDGE``): where the runs cannot change split
    (``atlas.applies``: Suslov's equations in the paper's convention, more than 3
    constraints), or no other split is regular there."""

    deadline = None
    #: ``(run, halt)`` of the ``interrupt.shared`` watch the runs share, or None (a watch
    #: per run)
    watch = None

    def __init__(self, scene, q0, q1, unknowns, fixed, rtol, atol, method, rcond):
        self.scene, self.unknowns, self.fixed = scene, unknowns, fixed
        names = scene.state_names
        self.rows = [names.index(c) for c in q1]
        self.target = np.array(list(q1.values()))
        #: each end condition's scale: the accepted miss is ``tol`` times it
        #: (``end_scale``)
        self.scale = end_scale([q0[c] for c in q1], list(q1.values()))
        self.start_named = [q0[c] for c in q1]
        #: whether a named coordinate ends where it started (its ``own_scale`` is then
        #: its excursion along the motion; else every own scale is ``scale``'s)
        self.returns = any(float(q0[c]) == float(v) for c, v in q1.items())
        self.cols = [names.index(u) for u in unknowns]
        # as index arrays (a list is converted on every use)
        self._rows = np.array(self.rows, dtype=np.intp)
        self._cols = np.array(self.cols, dtype=np.intp)
        self._block = None           # the entries of dq_named(t1)/du in S, flattened
        given = {**q0, **fixed}
        self.y0 = np.array([given.get(n, 0.0) for n in names])
        self._first = None           # the loop's first row from y0 (``first_row``)
        self.rtol, self.atol, self.method, self.rcond = rtol, atol, method, rcond
        self.end_names = tuple(q1)
        self.seen: dict = {}
        self.span = scene.t_span         # the runs' span (continuation in T moves t1)
        self.n_velocities = len(scene.velocities)       # the independent: lead unknowns
        self.plans: dict = {}            # (span, save) -> the driver's plan of the runs
        self.holonomic = bool(scene.system.holonomic)
        self.stops: dict = {}
        #: the last run that stopped early, per cause (``_stopped``)
        self.last_stops: dict = {}
        self.runs = 0

    #: whether runs that cannot change split stop at its edge (``edge_event``)
    watch_edge = True

    def own_scale(self, motion) -> list:
        """Each end condition's scale that ``tol`` is checked against, along ``motion``
        (the named coordinates' ``own_scale``; the momenta's as ``scale``): ``scale``
        itself where none returns to its start (the same numbers, no excursion read)."""
        if not self.returns:
            return self.scale.tolist()
        n = len(self.rows)
        return own_scale(self.start_named, self.target[:n].tolist(),
                         excursion(motion, self.rows)) + self.scale[n:].tolist()

    def plan(self, span, save="steps"):
        """The driver's plan of a shooting run on ``span`` (with sensitivities; every
        step or the ends), made once: each run then only calls the compiled loop.
        Where the runs cannot change split (``atlas.applies``), the plan watches the
        split's edge as a terminal event (``edge_event``, with ``watch_edge``): a run
        stops there, counted as "edge", instead of crawling toward the singular set."""
        found = self.plans.get((span, save))
        if found is None:
            edge = edge_event(self.scene) if self.watch_edge else None
            key = ("shooting", self.method, self.rtol, solve.hashable(self.atol), span,
                   save, MAX_STEPS, edge is not None)
            # kept on the scene too: repeated problems on one scene plan nothing
            found = self.plans[span, save] = solve.planned(
                self.scene, key, lambda: solve.plan(
                    self.scene, self.method, t_span=span, save=save, sensitivities=True,
                    events=edge,
                    opts=options(rtol=self.rtol, atol=self.atol, max_steps=MAX_STEPS)))
        return found

    def start(self, y, span, save="steps", first=None):
        """The ``Shot`` of the plan of ``span`` from the state ``y`` (its own array), or
        None where it fails before the end of the span or ends in a non-finite
        state; ``first``: the loop's first row, where made (``first_row``; ``y`` is then
        its state)."""
        scene = self.scene
        if self.deadline is not None and time.monotonic() > self.deadline:
            raise OutOfTime
        self.runs += 1
        if not all_finite(y):
            return None
        if self.holonomic:
            try:
                scene._check_holonomic(y, span[0], scene._p)
            except JetnhError:
                return None
        plan = self.plans.get((span, save)) or self.plan(span, save)
        shot = Shot.of(scene, plan, y, scene._p, self.stops, self.watch, first)
        if shot is None:
            last = self.stops.pop("y", None)
            if last is not None:
                self._stopped(plan, y, *last)
        return shot

    def _stopped(self, plan, y0, status, t, y, index):
        """Count a run from ``y0`` that stopped early with ``status`` at ``(t, y)`` on
        the singularity indicator ``index`` (-1: none): as "edge" where near the edge
        of the scene's split, as "crawl" where a singular stop came before its
        indicator reached the threshold (the loop found it crawling toward its zero:
        ``_crawled``); the last stop of each kind kept for ``stops_note``."""
        stops = self.stops
        if not arguments.all_finite(y):
            self.last_stops[status] = (t, y, y0, -1, plan)
            return
        kind = status
        if status == SINGULAR and index >= 0:
            rel = _crawled(plan, self.scene._p, y0, t, y, index)
            if rel is not None:
                stops["crawl"] = stops.get("crawl", 0) + 1
                kind = "crawl"
        self.last_stops[kind] = (t, y, y0, index, plan)
        from .verdicts import split_measure

        if split_measure(self.scene, t, y) < EDGE:
            stops["edge"] = stops.get("edge", 0) + 1

    def stops_note(self) -> str:
        """Why runs stopped before t1, by cause (the last of each kind named: where,
        and on which singular set), then the edge of the split (``edge_note``); ""
        where none did."""
        stops, parts = self.stops, []
        crawl = stops.get("crawl", 0)
        k = stops.get(STIFF, 0)
        if k:
            last, where = self.last_stops.get(STIFF), ""
            if last is not None:
                t, y, y0, _, plan = last
                near = _near(self.scene, plan, t, y, y0) if arguments.all_finite(y) else ""
                where = f"the last at t = {t:.10g}: " + (f"{near}; " if near else "")
            parts.append(
                f"{k} stopped as stiff ({where}Hairer's test found {self.method}'s steps "
                "held by stability, not by rtol): connect integrates with explicit "
                "methods (dop853, dopri5), which cannot follow a stiff motion; run "
                "scene.run(method='radau') to see it, and connect over a shorter span "
                "or to an end reached before the motion turns stiff")
        if crawl:
            t, y, y0, index, plan = self.last_stops["crawl"]
            expr = plan.kern.layout.indicators[index]
            rel = _crawled(plan, self.scene._p, y0, t, y, index)
            parts.append(
                f"{crawl} crawled toward the singular set {expr} = 0 and stopped there "
                f"(the last at t = {t:.10g}, where {expr} is {rel:.3g} of its initial "
                f"value): {self.method}'s steps shrank faster than the distance to it, as "
                "where the equations are a 0/0 that floating point cannot resolve")
        k = stops.get(SINGULAR, 0) - crawl
        if k:
            last = self.last_stops.get(SINGULAR)
            where = ""
            if last is not None:
                where = f" (the last at t = {last[0]:.10g}" + (
                    f", on {last[4].kern.layout.indicators[last[3]]} = 0"
                    if last[3] >= 0 else "") + ")"
            parts.append(f"{k} reached a singular configuration{where}")
        for code, what in ((Status.MAX_STEPS, f"took more than {MAX_STEPS} steps"),
                           (Status.TOO_SMALL_STEP, "had their step fall below the "
                            "spacing of the floats"),
                           (Status.NONFINITE, "became NaN or infinite"),
                           (Status.NOT_CONVERGED, "did not converge")):
            k = stops.get(code, 0)
            if k:
                last = self.last_stops.get(code)
                parts.append(f"{k} {what}" + (
                    "" if last is None else f" (the last at t = {last[0]:.10g})"))
        if not parts:
            return self.edge_note()
        edge = self.edge_note(of_them=True)
        n = sum(v for key, v in stops.items() if type(key) is int)
        note = (f"{n} of the {self.runs} runs stopped before t1: " + "; ".join(parts))
        return note + (f"; {edge}" if edge else "")

    def edge_note(self, of_them=False) -> str:
        """Where runs stopped at the edge of the scene's split: what that means and the
        fix ("" where none did); ``of_them``: counted "of them" (after a count of
        the runs)."""
        k = self.stops.get("edge", 0)
        if not k:
            return ""
        dep = ", ".join(self.scene.dependent_velocities) or "none"
        runs = "of them" if of_them else f"of the {self.runs} runs"
        return (f"{k} {runs} stopped at the edge of the scene's split "
                f"(dependent velocities {dep}: the constraints cannot be solved for them "
                "there) and could not go on in another split (the motions of this "
                "principle depend on the split, or no other split is regular there): "
                "where the end lies beyond it, connect from a System with other "
                "dependent coordinates (System(..., dependent=[...])) or in two legs")

    def state(self, u) -> np.ndarray:
        y = self.y0.copy()
        y[self._cols] = u
        return y

    def first_row(self, u, plan) -> np.ndarray:
        """The first row of a run of ``plan`` from the start with the unknowns ``u``:
        the state (``state(u)``), then the initial sensitivities S0 (``solve.augmented``:
        along g = 0 with holonomic constraints, as ``Scene.run`` starts; the unknowns
        move no coordinate, so the same for every u), a fresh array.  Without holonomic
        constraints S0 = (I | 0), the row ``_parts`` keeps for the plan (the same
        numbers; numpy's calls in ``solve.augmented`` cost ~10 us a search)."""
        if self._first is None:
            if self.holonomic:
                first = solve.augmented(self.scene, plan, self.y0, self.scene._p)
            else:
                first = (_PARTS.get(plan) or _parts(plan))[2].copy()
                first[:len(self.y0)] = self.y0
            first.setflags(write=False)
            self._first = first
        first = self._first.copy()
        first[self._cols] = u
        return first

    def named(self, S) -> np.ndarray:
        """dq_named/du, the block of the sensitivities ``S`` (n x columns, C-ordered)."""
        if self._block is None:
            m = S.shape[1]
            self._block = np.array([r * m + c for r in self.rows for c in self.cols],
                                   dtype=np.intp)
        return S.take(self._block).reshape(len(self.rows), len(self.cols))

    def endpoint(self, u):
        """``(q_named(t1), dq_named(t1)/du, its Shot)``, or None where the run fails
        (the last few kept: the guess and the answer are evaluated more than once)."""
        key = (np.asarray(u, dtype=float).tobytes(), self.span)
        seen = self.seen
        got = seen.get(key, seen)           # (the dict itself: not seen)
        if got is seen:
            if len(seen) > 8:
                seen.clear()
            got = seen[key] = self._endpoint(u)
        return got

    def _endpoint(self, u):
        shot = self.run(u)
        if shot is None:
            return None
        return shot.y[self._rows], self.named(shot.S), shot

    def run(self, u):
        """The ``Shot`` from the start with the unknowns ``u`` (every step, with
        sensitivities), or None where it fails before t1 (or takes more than
        ``MAX_STEPS`` steps: a wild trial of the search must not take minutes)."""
        span = self.span
        first = self.first_row(u, self.plans.get((span, "steps")) or self.plan(span))
        return self.start(first[:len(self.y0)], span, first=first)

    def regular_start(self, u0, q0, q1, T, n_velocities):
        """The default guess, moved off a point where the run stops before t1 (a speed
        that falls to a singular zero) or where the shooting Jacobian is rank-deficient
        in any units (``regular``: zero velocities, a straight line along an abnormal
        direction): first to the
        minimum-norm Gauss-Newton point of its run's sensitivities (``newton_point``:
        the motion the guess's linearisation says reaches the end), then by a fixed
        pattern of the size of the straight-line velocities, with the velocities
        doubled and quadrupled; 12 tries, the first regular one kept (else the first
        that reaches t1)."""
        u = u0 + 0.0                        # the first try: u0 itself
        got = self.endpoint(u)
        reaching = None
        if got is not None:
            if self.regular(got):
                return u
            newton = self.newton_point(u, got)
            if newton is not None and self.regular(self.endpoint(newton)):
                return newton
            reaching = u
        scale = _speed(q0, q1, T)
        pattern = 0.5 * (-0.6) ** np.arange(len(u0))
        speed = np.ones(len(u0))
        for k in range(1, 12):
            speed[:n_velocities] = 2.0 ** (k // 4)
            u = speed * u0 + (scale * np.roll(pattern, k) * (k % 4) if k % 4 else 0.0)
            got = self.endpoint(u)
            if got is not None:
                if self.regular(got):
                    return u
                reaching = u if reaching is None else reaching
        return u0 if reaching is None else reaching

    def regular(self, got) -> bool:
        """Whether the ``endpoint`` ``got`` exists (the run reached t1) and its shooting
        Jacobian, free of units (``unit_free``), has full rank by a margin (smallest
        singular value above 1e-6 of the largest)."""
        return got is not None and full_rank(singular_values(self.unit_free(got[1])))

    def unit_free(self, Jm) -> np.ndarray:
        """The shooting Jacobian ``Jm`` free of the units of the conditions and of the
        unknowns: each condition's row over its scale (``scale``: a named coordinate's
        over its displacement, one that returns to its start over the largest), then
        each column over its norm."""
        A = Jm / self.scale[:, None]
        norms = np.sqrt((A * A).sum(axis=0))
        return A / np.where(norms > 0, norms, 1.0)

    def newton_point(self, u, got, usv=None):
        """``u`` plus the minimum-norm Gauss-Newton step of its endpoint ``got`` (the
        truncated SVD, at most the size of ``u`` and 1), or None where it does not
        move; ``usv``: the SVD of its Jacobian where already made."""
        U, s, Vt = self.truncated(svd(got[1]) if usv is None else usv)
        if not s.size:
            return None
        du = -(Vt.T @ ((U.T @ (got[0] - self.target)) / s))
        size = math.sqrt(du.dot(du)) / max(1.0, math.sqrt(u.dot(u)))
        if size > 1.0:
            du /= size
        return u + du if np.count_nonzero(du) else None

    def truncated(self, usv):
        """The singular value decomposition ``usv`` of the shooting Jacobian cut to its
        numerical rank (relative cut-off ``rcond``)."""
        U, s, Vt = usv
        r = rank(s, self.rcond)
        return (U, s, Vt) if r == s.size else (U[:, :r], s[:r], Vt[:r])


def svd(Jm):
    """The thin singular value decomposition ``(U, s, Vt)`` of ``Jm`` (compiled,
    ``small.thin_svd``: a small matrix costs a fraction of a LAPACK call's set-up)."""
    return thin_svd(Jm)


def singular_values(Jm):
    """The singular values of ``Jm``, largest first."""
    return thin_svd(Jm)[1]


def full_rank(s) -> bool:
    """Whether singular values ``s`` (largest first) are those of a matrix of full rank
    by a margin: the smallest above 1e-6 of the largest."""
    return bool(s.size and s[0] > 0 and s[-1] > 1e-6 * s[0])


def rank(s, rcond) -> int:
    """The numerical rank of singular values ``s`` (largest first): those above
    ``rcond`` times the largest."""
    return rank_of(s.tolist(), rcond)


def rank_of(values, rcond) -> int:
    """``rank`` of singular values given as a list of floats."""
    if not values or not values[0] > 0:
        return 0
    cut = rcond * values[0]
    return len([v for v in values if v > cut])


#: growth max |dy(t1)/dy(t0)| of the guess's run above which the default splits the span
GROWTH = 1e6
#: the most segments the default chooses (``segments`` may ask for more)
MAX_SEGMENTS = 16


def default_segments(shooter, u) -> int:
    """The number of shooting segments for the guess ``u``: 1 where its run reaches t1
    with sensitivities below ``GROWTH``; else one segment per factor 100 of the growth
    (``MAX_SEGMENTS`` where the run fails before t1), at least 2."""
    got = shooter.endpoint(u)
    if got is None:
        return MAX_SEGMENTS
    # (a Shot's sensitivities are finite: ``Shot.of``)
    growth = max_abs(got[2].S, len(shooter.y0))
    if not math.isfinite(growth):
        return MAX_SEGMENTS
    if growth <= GROWTH:
        return 1
    return int(min(MAX_SEGMENTS, max(2, np.ceil(np.log10(growth) / 2.0))))


class Segments:
    """Multiple shooting of a ``Shooter``'s problem on ``k`` equal segments of the span:
    the unknowns are the shooter's ``u`` and the full states ``Y_1 .. Y_{k-1}`` at the
    inner nodes; the conditions are the matching ``y(t_i; Y_{i-1}) - Y_i = 0`` and the
    end ``q_named(t1; Y_{k-1}) = end``.  The Jacobian is block bidiagonal: the segments'
    state transition matrices (their exact sensitivities) and -I."""

    def __init__(self, shooter, k, tol):
        self.shooter, self.k, self.tol = shooter, int(k), tol
        t0, t1 = shooter.scene.t_span
        self.nodes = np.linspace(t0, t1, self.k + 1)
        self.n = len(shooter.y0)
        self.m = len(shooter.cols)
        coordinates = {q.name for q in shooter.scene.system.J.q}
        #: which states are coordinates (their origin is free: ``scale``)
        self.coordinate = np.array([s in coordinates for s in shooter.scene.state_names])

    def guess(self, u):
        """``u`` and the inner states on the line from the start to the named end (the
        other coordinates kept, the unknowns' states from ``u``)."""
        sh = self.shooter
        y, t0, t1 = sh.state(u), self.nodes[0], self.nodes[-1]
        inner = []
        for t in self.nodes[1:-1]:
            Y = y.copy()
            Y[sh.rows] = y[sh.rows] + (t - t0) / (t1 - t0) * (sh.target - y[sh.rows])
            inner.append(Y)
        return np.concatenate([np.asarray(u, dtype=float)] + inner)

    def split(self, U):
        """The initial states of the segments from the unknowns ``U``."""
        sh, n, m = self.shooter, self.n, self.m
        return [sh.state(U[:m])] + [U[m + i * n:m + (i + 1) * n] for i in range(self.k - 1)]

    def run(self, i, y):
        return self.shooter.start(np.array(y, dtype=float),
                                  (float(self.nodes[i]), float(self.nodes[i + 1])), "final")

    def evaluate(self, U, target):
        """``(F, dF/dU)`` of the matching and end conditions, or None where a segment's
        run fails."""
        sh, n, m, k = self.shooter, self.n, self.m, self.k
        starts = self.split(U)
        F = np.empty((k - 1) * n + len(sh.rows))
        Jm = np.zeros((F.size, U.size))
        for i, y in enumerate(starts):
            shot = self.run(i, y)
            if shot is None:
                return None
            end, S = shot.y, shot.S[:, :n]
            # columns: segment 0 depends on u (its unknowns' states), the others on Y_i
            cols = (slice(0, m), sh.cols) if i == 0 else (slice(m + (i - 1) * n,
                                                                  m + i * n), slice(None))
            if i < k - 1:
                r = slice(i * n, (i + 1) * n)
                F[r] = end - starts[i + 1]
                Jm[r, cols[0]] = S[:, cols[1]]
                Jm[r, m + i * n:m + (i + 1) * n] = -np.eye(n)
            else:
                r = slice((k - 1) * n, F.size)
                F[r] = end[sh.rows] - target
                Jm[r, cols[0]] = S[sh.rows][:, cols[1]]
        return F, Jm

    def scale(self, U):
        """Each condition's scale at the unknowns ``U``, free of the units and the
        origin of every state: a matching condition's is its state's own size along
        the nodes (the start, the inner states and, for a named coordinate, its end),
        a coordinate's its excursion from the start there (``excursion``'s, on the
        nodes), any other state's (velocities, multipliers) its largest magnitude
        there, with the rounding of the values (``ROUNDING`` max |Y| / ``tol``: a miss
        below the doubles' resolution is met); the end conditions' the shooter's
        ``scale`` (``end_scale``; single shooting polishes the answer, or the stitched
        motion is checked against it)."""
        sh = self.shooter
        Y = np.vstack(self.split(U))
        size = np.abs(Y).max(axis=0)
        reach = np.abs(Y - Y[0]).max(axis=0)
        named = np.abs(sh.target[:len(sh.rows)] - Y[0, sh.rows])
        reach[sh.rows] = np.maximum(reach[sh.rows], named)
        own = np.where(self.coordinate, reach, size) + ROUNDING * size / self.tol
        # (a state that is 0 at every node has no size of its own: its misses are met at
        # the rounding of the largest state (at 1 where every state is 0), never at
        # a scale of 0, which no miss can meet)
        floor = ROUNDING * size.max() / self.tol or 1.0
        own = np.where(own > 0.0, own, floor)
        return np.concatenate([np.tile(own, self.k - 1), sh.scale])
