"""The answer of ``connect``: a frozen ``Connection`` with lazily computed verdicts."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType

import numpy as np

from ...errors import JetnhError
from ...frozen import readonly
from ..trajectory import Trajectory
from .problem import VARIATIONAL
from .verdicts import (GRAMIAN_RCOND, LEGENDRE_ZERO, NEAR_ABNORMAL, _Samples, action,
                       conjugate_times, gramian_change, gramian_ratio, legendre_margin,
                       not_extremal)


@dataclass(frozen=True)
class Connection:
    """A motion of ``principle`` joining two configurations (``connect``).

    The verdicts ``cost``, ``normal``, ``gramian_ratio`` and ``conjugate_times`` are
    computed on first access (one more run, sampled on the dense output) and then kept;
    so is the ``trajectory`` (made from the run that found the motion).

    Picklable (``__getstate__``): the trajectory travels (its compiled kernels reloaded
    from the scene's cache on first use in another process) with the verdicts computed
    so far; the others are computed there on first access, except for a motion that
    changed split or was stitched from segments, which is not evaluated between its
    rows after unpickling: its verdicts are computed before it is pickled.
    """

    _motion: object                  # the Trajectory, or the run that makes it (a Shot)
    initial: MappingProxyType        # the full initial state found (name -> value)
    residual: float                  # max |q(t1) - end| over the named coordinates
    #                                  and |P_i(t1)| over the free ones
    principle: str
    unknowns: tuple                  # names of the shooting unknowns
    rank: int                        # rank of the shooting Jacobian at the answer
    singular_values: tuple           # of the shooting Jacobian at the answer
    iterations: int                  # Levenberg-Marquardt iterations (all steps)
    _columns: tuple = field(repr=False, compare=False)     # the unknowns' states
    _rcond: float = field(repr=False, compare=False)
    _run: MappingProxyType = field(repr=False, compare=False)   # rtol, atol, method
    #: the end conditions: the named coordinates, then p_<q> for each free coordinate q
    #: (its transversality condition)
    conditions: tuple = ()
    #: how it was found: "Newton from the guess", "continuation in the endpoint",
    #: "collocation", "continuation in T" or "multiple shooting (k segments)"
    route: str = ""
    #: what the least-action search (``connect(restarts=)``) tried and where it stopped;
    #: "" where it did not run
    search: str = ""
    #: the largest miss of an end condition relative to its scale (its displacement
    #: start -> end, or its excursion along the motion where it returns to its start,
    #: ``shooting.own_scale``): what ``tol`` bounds
    relative_residual: float = 0.0
    #: the named end coordinates' values (the first of ``conditions``)
    _end: tuple = field(default=(), repr=False, compare=False)

    @cached_property
    def trajectory(self) -> Trajectory:
        """The motion from start at t0 to (near) end at t1."""
        motion = self._motion
        return motion if isinstance(motion, Trajectory) else motion.trajectory

    @cached_property
    def _samples(self):
        return _Samples(self.trajectory, dict(self._run))

    @cached_property
    def cost(self) -> float:
        """The action int L dt along the motion (``action``).  With non-potential forces
        (``not_extremal``) only that integral: the motion need not make it stationary,
        and it is no least action."""
        return action(self.trajectory, self._samples)

    @cached_property
    def gramian_ratio(self) -> float:
        """Smallest / largest eigenvalue of the constraint system's controllability
        Gramian along the motion, scaled to a unit diagonal (``verdicts.gramian_ratio``):
        in [0, 1], the same in any units of the coordinates."""
        return gramian_ratio(self.trajectory, self._samples)

    @cached_property
    def gramian_change(self) -> float:
        """The largest relative change of the constraint system's endpoint map's gain
        in any direction along the correction of the motion's end miss
        (``verdicts.gramian_change``): of the order of the relative miss for a normal
        motion, of order one where the miss lies in the second-order region of a fold
        of that map -- a path the end tolerance admits beside an abnormal one; the
        same in any units of the coordinates."""
        tr = self.trajectory
        names = tr.scene.state_names
        rows = [names.index(c) for c in self.conditions[:len(self._end)]]
        miss = tr.y[-1][rows] - np.array(self._end, dtype=float)
        return gramian_change(tr, self._samples, rows, miss)

    @property
    def normal(self) -> bool:
        """False: an abnormal extremal (the constraint system's endpoint map loses rank
        along the motion: ``gramian_ratio`` below ``GRAMIAN_RCOND``), or a motion that
        the end tolerance admits beside one (the map's gain changes by more than
        ``NEAR_ABNORMAL`` along the correction of the end miss: ``gramian_change``)."""
        return bool(self.gramian_ratio > GRAMIAN_RCOND
                    and self.gramian_change <= NEAR_ABNORMAL)

    @cached_property
    def conjugate_times(self):
        """Where the map from the unknowns to the configuration loses rank in (t0, t1]
        (``verdicts.conjugate_times``).  Vakonomic and Hoelder: the map to the whole
        configuration, dq(t)/du (the Jacobi fields): the conjugate points of the
        extremal.  Chetaev and Suslov, whose motions are no extremals of an action: the
        map to the named end coordinates, the two-point problem's endpoint map -- where
        it is singular, the end is a fold of the motions from the start (nearby ends
        are reached twice or not at all).  Vakonomic and Hoelder with non-potential
        forces (``not_extremal``): the folds of the map to the configuration, no
        conjugate points of an action.  None: not checked (fewer unknowns than
        coordinates to measure)."""
        rows = None
        if self.principle not in VARIATIONAL:
            names = self.trajectory.scene.state_names
            rows = [names.index(c) for c in self.conditions]
        return conjugate_times(self.trajectory, list(self._columns), self._samples,
                               self._rcond, rows)

    @cached_property
    def legendre(self):
        """The strengthened Legendre condition along the motion
        (``verdicts.legendre_margin``): the smallest eigenvalue of the Hessian of L +
        lambda f in the velocities, restricted to the admissible ones (ker df/dqdot,
        tangent to g = 0) and written in the independent velocities, scaled to a unit
        diagonal (the same in any units), at the worst of the equal-spaced times.
        Positive (at most 1): definite everywhere; negative: the action decreases along
        some rapid variation (no minimizer); None for Chetaev and Suslov, and where the
        motion is in general no extremal of the action (``not_extremal`` says why)."""
        if self.principle not in VARIATIONAL or self.not_extremal:
            return None
        return legendre_margin(self.trajectory, self._samples)

    @cached_property
    def not_extremal(self) -> str:
        """Vakonomic and Hoelder: why the motion is in general no extremal of int L dt
        (``verdicts.not_extremal``: generalized forces or dissipation that do not
        vanish at these parameter values), so that ``legendre`` and ``minimizer`` are
        None; "" without such forces, and for Chetaev and Suslov."""
        if self.principle not in VARIATIONAL:
            return ""
        return not_extremal(self.trajectory.scene)

    @property
    def minimizer(self):
        """Vakonomic and Hoelder: the necessary conditions of a local minimum of the
        action.  False where Legendre's fails (``legendre`` negative: L + lambda f is
        not positive semidefinite on the admissible velocities somewhere) or a conjugate
        time lies inside (t0, t1) (Jacobi's); True where the strengthened Legendre
        condition holds and no conjugate time lies inside (necessary, not sufficient,
        for a minimum); None where neither verdict applies (a Hessian singular
        somewhere, conjugate times not checked), for Chetaev and Suslov, whose
        motions are not extremals of the action, and under non-potential forces
        (``not_extremal`` says why)."""
        if self.principle not in VARIATIONAL or self.not_extremal:
            return None
        margin = self.legendre
        if margin < -LEGENDRE_ZERO:
            return False
        times = self.conjugate_times
        if times is None:
            return None
        t0, t1 = float(self.trajectory.t[0]), float(self.trajectory.t[-1])
        if any(abs(t - t1) > 1e-9 * abs(t1 - t0) for t in times):
            return False
        return True if margin > LEGENDRE_ZERO else None

    @property
    def _not_minimizer(self) -> str:
        """Why ``minimizer`` is False, in words: Legendre's condition failing (it is
        checked first) or the conjugate times inside the span; "" where it is not
        False."""
        if self.minimizer is not False:
            return ""
        if self.legendre < -LEGENDRE_ZERO:
            return f"Legendre's condition fails (legendre = {self.legendre:.3g})"
        t1 = float(self.trajectory.t[-1])
        inside = [t for t in self.conjugate_times if t != t1]
        return (("conjugate times" if len(inside) > 1 else "a conjugate time")
                + " inside the span (t = " + ", ".join(f"{t:.6g}" for t in inside) + ")")

    #: the verdicts kept in ``__dict__`` once computed (``cached_property``)
    _VERDICTS = ("cost", "gramian_ratio", "gramian_change", "conjugate_times", "legendre")

    def __getstate__(self):
        """The fields as plain data: the Trajectory for the run that made it (a
        ``shooting.Shot`` holds the search's compiled loop), the mappings as dicts, the
        verdicts computed so far (all of them where the trajectory cannot be evaluated
        after unpickling: ``Trajectory._segments``), not the samples (rebuilt)."""
        tr = self.trajectory
        if tr._segments is not None:
            for name in self._VERDICTS:
                getattr(self, name)
        state = {k: v for k, v in self.__dict__.items()
                 if k not in ("trajectory", "_samples")}
        state.update(_motion=tr, initial=dict(self.initial), _run=dict(self._run))
        return state

    def __setstate__(self, state):
        """Frozen again: the mappings read-only (``MappingProxyType``)."""
        state = dict(state)
        state["initial"] = MappingProxyType(dict(state["initial"]))
        state["_run"] = MappingProxyType(dict(state["_run"]))
        self.__dict__.update(state)

    def __repr__(self):
        times = self.conjugate_times
        minimizer = self.minimizer
        return (f"Connection({self.principle}: cost {self.cost:.12g}, residual "
                f"{self.residual:.2e}, normal={self.normal}, conjugate_times="
                + ("None (not checked)" if times is None else
                   f"{tuple(round(t, 10) for t in times)}")
                + {False: " (not a minimizer)", True: "",
                   None: "" if self.principle not in VARIATIONAL else
                   " (minimizer undecided: non-potential forces)"
                   if self.not_extremal else " (minimizer not checked)"}[minimizer]
                + ", initial="
                f"{dict(self.initial)})")

class Stitched:
    """The runs of multiple shooting's segments as one motion (``Trajectory._segments``):
    its rows are the segments' steps (each inner node once, as the end of the segment
    before it), its sensitivities those of each segment chained by the transition
    matrices of the ones before (dy(t)/dy(t0) = S_i(t) S_{i-1}(t_i) ... S_0(t_1)), its
    values between rows each segment's dense output (``evaluate``, ``at``)."""

    def __init__(self, pieces, chains):
        self.pieces = tuple(pieces)
        self.chains = tuple(readonly(np.array(P, dtype=float)) for P in chains)
        self.nodes = readonly(np.array(
            [float(p.t[0]) for p in pieces] + [float(pieces[-1].t[-1])]))

    @classmethod
    def join(cls, segments, U):
        """The stitched Trajectory of ``segments`` (``shooting.Segments``) at their
        unknowns ``U``, or None where a segment's run fails."""
        sh = segments.shooter
        pieces = []
        for i, y in enumerate(segments.split(U)):
            try:
                tr = sh.scene.run(rtol=sh.rtol, atol=sh.atol, method=sh.method, y0=y,
                                  t_span=(segments.nodes[i], segments.nodes[i + 1]),
                                  sensitivities=True)
            except JetnhError:
                return None
            if tr.status != 0:
                return None
            pieces.append(tr)
        first = pieces[0]
        n, cols = len(sh.y0), first.sensitivity_columns
        P = np.zeros((n, len(cols)))
        P[:, :n] = np.eye(n)
        chains, ts, ys, Ss = [], [], [], []
        for i, tr in enumerate(pieces):
            chains.append(P)
            rows = slice(0 if i == 0 else 1, None)
            S = cls._chain(tr.sensitivities[rows], P, n)
            ts.append(tr.t[rows]), ys.append(tr.y[rows]), Ss.append(S)
            P = S[-1]
        joined = cls(pieces, chains)
        info = [tr.diagnostics for tr in pieces]
        return Trajectory(
            first.scene, np.concatenate(ts), np.concatenate(ys), first._p,
            method=first.method, status=0,
            stop_reason=f"reached t1 ({len(pieces)} segments of multiple shooting, "
                        "stitched)",
            steps=sum(d.steps or 0 for d in info),
            rejected=sum(d.rejected or 0 for d in info),
            nfev=sum(d.rhs_evaluations for d in info),
            wall_time=sum(d.wall_time for d in info), kernels=first._kernels,
            segments=joined, sensitivities=(cols, np.concatenate(Ss)))

    @staticmethod
    def _chain(S, P, n):
        """Segment sensitivities S (to its own start) chained by P = dy(t_i)/d(y0, p)."""
        out = S[:, :, :n] @ P
        out[:, :, n:] += S[:, :, n:]
        return out

    def _rows(self, traj):
        return [slice(0 if i == 0 else 1, None) for i in range(len(self.pieces))]

    def aux(self, traj) -> np.ndarray:
        return np.concatenate([p.aux[r] for p, r in zip(self.pieces, self._rows(traj))])

    def at(self, traj, times) -> np.ndarray:
        return self.evaluate(traj, times)

    def evaluate(self, traj, times, full=False) -> np.ndarray:
        """The states at ``times`` (with ``full``: and the chained sensitivities,
        row-major), each from its segment's dense output."""
        from ..dense import evaluate

        tau = np.atleast_1d(np.asarray(times, dtype=float))
        n = traj.layout.n_state
        m = len(traj.sensitivity_columns)
        out = np.empty((tau.size, n + (n * m if full else 0)))
        sgn = 1.0 if self.nodes[-1] >= self.nodes[0] else -1.0
        which = np.minimum(np.searchsorted(sgn * self.nodes[1:-1], sgn * tau,
                                           side="left"), len(self.pieces) - 1)
        for i, piece in enumerate(self.pieces):
            idx = np.nonzero(which == i)[0]
            if not idx.size:
                continue
            Y = evaluate(piece, tau[idx], full=full)
            out[idx, :n] = Y[:, :n]
            if full:
                S = Y[:, n:].reshape(-1, n, m)
                out[idx, n:] = self._chain(S, self.chains[i], n).reshape(idx.size, -1)
        return out

