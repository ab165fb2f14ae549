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
from .verdicts import (_GAUSS_X, GRAMIAN_RCOND, _Samples, action, conjugate_times,
                       gramian_ratio)


@dataclass(frozen=True)
class Connection:
    """A motion of ``principle`` joining two configurations (``connect``).

    The verdicts ``cost``, ``normal``, ``gramian_ratio`` and ``conjugate_times`` are
    computed on first access (one more run, sampled on the dense output) and then kept;
    so is the ``trajectory`` (made from the run that found the motion).
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

    @cached_property
    def trajectory(self) -> Trajectory:
        """The motion from start at t0 to (near) end at t1."""
        motion = self._motion
        return motion if isinstance(motion, Trajectory) else motion.trajectory

    @cached_property
    def _samples(self):
        tr = self.trajectory
        if isinstance(tr._segments, Stitched):
            return _StitchedSamples(tr)
        return _Samples(tr, self._run["rtol"], self._run["atol"], self._run["method"],
                        tr.y[0])

    @cached_property
    def cost(self) -> float:
        """The action int L dt along the motion (``action``)."""
        return action(self.trajectory, self._samples)

    @cached_property
    def gramian_ratio(self) -> float:
        """Smallest / largest eigenvalue of the constraint system's controllability
        Gramian along the motion (``gramian_ratio``)."""
        return gramian_ratio(self.trajectory, self._samples)

    @property
    def normal(self) -> bool:
        """False: an abnormal extremal (the constraint system's endpoint map loses rank
        along the motion: ``gramian_ratio`` below ``GRAMIAN_RCOND``)."""
        return bool(self.gramian_ratio > GRAMIAN_RCOND)

    @cached_property
    def conjugate_times(self) -> tuple:
        """The times in (t0, t1] where dq/du loses rank (``conjugate_times``)."""
        return conjugate_times(self.trajectory, list(self._columns), self._samples,
                               self._rcond)

    @property
    def minimizer(self):
        """Vakonomic and Hoelder: False where a conjugate time lies inside (t0, t1) --
        the extremal is then no local minimizer of the action (Jacobi's necessary
        condition); True where none does (necessary, not sufficient, for a minimum).
        None for Chetaev and Suslov, whose motions are not extremals of the action."""
        if self.principle not in VARIATIONAL:
            return None
        t0, t1 = float(self.trajectory.t[0]), float(self.trajectory.t[-1])
        return not any(abs(t - t1) > 1e-9 * abs(t1 - t0) for t in self.conjugate_times)

    def __repr__(self):
        return (f"Connection({self.principle}: cost {self.cost:.12g}, residual "
                f"{self.residual:.2e}, normal={self.normal}, conjugate_times="
                f"{tuple(round(t, 10) for t in self.conjugate_times)}"
                + ("" if self.minimizer is not False else " (not a minimizer)")
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


class _StitchedSamples(_Samples):
    """``_Samples`` of a stitched motion: from its segments' dense output."""

    def __init__(self, tr):
        t = tr.t
        a, b = t[:-1], t[1:]
        self.half = 0.5 * (b - a)
        self.gauss = ((0.5 * (a + b))[:, None] + self.half[:, None] * _GAUSS_X[None, :])
        self.grid = np.linspace(t[0], t[-1], self.GRID + 1)
        times = np.concatenate([self.gauss.ravel(), self.grid])
        n, m = tr.layout.n_state, len(tr.sensitivity_columns)
        Y = tr._segments.evaluate(tr, times, full=True)
        k = self.gauss.size
        self.gauss_y, self.grid_y = Y[:k, :n], Y[k:, :n]
        self.grid_S = Y[k:, n:].reshape(-1, n, m)
