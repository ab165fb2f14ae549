"""What a generated kernel module is: the version of its format and its ``Layout``.

Shared by the code generator (which writes modules) and the disk cache (which keeps them
under ``v<CODEGEN_VERSION>`` and reads their layout back), so that neither imports the
other's module for them.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

#: the format of generated kernel modules (the cache keeps each version apart)
CODEGEN_VERSION = "10"


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

    @property
    def n_rhs(self) -> int:
        """The size of the state the ``rhs`` kernel integrates: the state, and with
        sensitivities the n x ``sensitivity_columns`` matrix S after it (row-major)."""
        return self.n_state * (1 + self.sensitivity_columns)

    @property
    def states(self) -> tuple[str, ...]:
        return self.coordinates + self.velocities + self.multipliers

    @property
    def n_state(self) -> int:
        return len(self.states)

    @property
    def n_aux(self) -> int:
        return (2 * len(self.dependent_velocities) + 1 + len(self.integrals) + self.power
                + self.holonomic)

    @property
    def energy_index(self) -> int:
        return 2 * len(self.dependent_velocities)

    def to_json(self) -> str:
        return json.dumps(self.__dict__, sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> "Layout":
        d = json.loads(text)
        return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in d.items()})
