"""What a generated kernel module is: the version of its format, the signatures of its
kernels and its ``Layout``.

Shared by the code generator (which writes modules) and the kernel store and loader
(which keep them under ``v<CODEGEN_VERSION>``, read their layout back and call them), so
that neither imports the other's package for them.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, fields
from functools import cached_property

#: the format of generated kernel modules (the cache keeps each version apart)
CODEGEN_VERSION = "14"

#: the numba signature of the kernels ``rhs``, ``aux``, ``sing``, ``hol``, ``events``
#: (t, y, p, out)
SIGNATURE = "void(float64, float64[::1], float64[::1], float64[::1])"
#: the numba signature of ``jac`` (t, y, p, J)
JAC_SIGNATURE = "void(float64, float64[::1], float64[::1], float64[:, ::1])"


@dataclass(frozen=True)
class Layout:
    """Names and positions of everything a kernel reads or writes."""

    coordinates: tuple[str, ...]
    velocities: tuple[str, ...]            # independent velocities (states)
    multipliers: tuple[str, ...]           # multiplier states
    dependent_velocities: tuple[str, ...]  # computed by aux
    constraints: int                       # number of residuals in aux
    integrals: tuple[str, ...]             # user first integrals in aux
    runtime_params: tuple[str, ...]
    coordinate_velocities: tuple[str, ...] = ()  # velocity name of each coordinate
    indicators: tuple[str, ...] = ()           # singularity indicators (sing kernel)
    indicator_kinds: tuple[str, ...] = ()      # "split" | "constraint" | "acceleration"
    power: bool = False                        # aux has the power of the forces
    holonomic: int = 0                         # aux ends with the m holonomic g_i
    sensitivity_columns: int = 0               # rhs carries S = dy/d(y0, p), n x this

    # the sizes and names below: made on first read, then plain attributes (a run reads
    # them; the fields are frozen)
    @cached_property
    def n_rhs(self) -> int:
        """The size of the state the ``rhs`` kernel integrates: the state, and with
        sensitivities the n x ``sensitivity_columns`` matrix S after it (row-major)."""
        return self.n_state * (1 + self.sensitivity_columns)

    @cached_property
    def states(self) -> tuple[str, ...]:
        return self.coordinates + self.velocities + self.multipliers

    @cached_property
    def n_state(self) -> int:
        return len(self.states)

    @cached_property
    def n_aux(self) -> int:
        return (2 * len(self.dependent_velocities) + 1 + len(self.integrals) + self.power
                + self.holonomic)

    @cached_property
    def energy_index(self) -> int:
        return 2 * len(self.dependent_velocities)

    def to_json(self) -> str:
        """The fields (not what the properties above keep)."""
        return json.dumps({f.name: getattr(self, f.name) for f in fields(self)},
                          sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> "Layout":
        d = json.loads(text)
        return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in d.items()})
