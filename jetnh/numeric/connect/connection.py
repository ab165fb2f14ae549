"""The answer of ``connect``: a frozen ``Connection`` with lazily computed verdicts."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType

from ..trajectory import Trajectory
from .verdicts import GRAMIAN_RCOND, _Samples, action, conjugate_times, gramian_ratio


@dataclass(frozen=True)
class Connection:
    """A motion of ``principle`` joining two configurations (``connect``).

    The verdicts ``cost``, ``normal``, ``gramian_ratio`` and ``conjugate_times`` are
    computed on first access (one more run, sampled on the dense output) and then kept.
    """

    trajectory: Trajectory           # from start at t0 to (near) end at t1
    initial: MappingProxyType        # the full initial state found (name -> value)
    residual: float                  # max |q(t1) - end| over the named coordinates
    principle: str
    unknowns: tuple                  # names of the shooting unknowns
    rank: int                        # rank of the shooting Jacobian at the answer
    singular_values: tuple           # of the shooting Jacobian at the answer
    iterations: int                  # Levenberg-Marquardt iterations (all steps)
    _columns: tuple = field(repr=False, compare=False)     # the unknowns' states
    _rcond: float = field(repr=False, compare=False)
    _run: MappingProxyType = field(repr=False, compare=False)   # rtol, atol, method

    @cached_property
    def _samples(self):
        tr = self.trajectory
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

    def __repr__(self):
        return (f"Connection({self.principle}: cost {self.cost:.12g}, residual "
                f"{self.residual:.2e}, normal={self.normal}, conjugate_times="
                f"{tuple(round(t, 10) for t in self.conjugate_times)}, initial="
                f"{dict(self.initial)})")
