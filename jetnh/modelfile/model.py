"""``Model``: a constrained system with its defaults, the one record that the catalogue
(``jetnh.models``), model files and the command line share."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from collections.abc import Mapping

from ..frozen import FrozenDict
from ..mechanics.system import System


@dataclass(frozen=True)
class Model:
    """A ``System`` and its defaults (immutable; equal by content).

    ``name``: the model's name (a model file's ``name``, a catalogue name with its
    options such as ``n_trailer:N=4``); ``initial``: states and multipliers by name (the
    others start at 0); ``principle``, ``convention``: the defaults of deriving and
    simulating (None: jetnh's, chetaev and paper); ``integrals``: first integrals by name
    (sympy expressions); ``simulation``: the ``[simulation]`` keys given (``t_start``,
    ``t_end``, ``method``, ``rtol``, ``atol``, ``points``); ``source``: where it was read
    from (a path, ``<string>``, or ``catalogue``).
    """

    system: System
    name: str = ""
    description: str = ""
    initial: Mapping[str, float] = field(default_factory=FrozenDict)
    principle: str | None = None
    convention: str | None = None
    integrals: Mapping = field(default_factory=FrozenDict)
    simulation: Mapping = field(default_factory=FrozenDict)
    source: str = "<string>"

    def __post_init__(self):
        for name in ("initial", "integrals", "simulation"):
            object.__setattr__(self, name, FrozenDict(getattr(self, name)))

    def __hash__(self):
        return hash((self.system, self.name, self.source))

    @property
    def parameters(self) -> dict:
        """The parameters' values by name (``system.defaults``)."""
        return {s.name: v for s, v in self.system.defaults.items()}

    @property
    def label(self) -> str:
        """The name to show: ``name``, else the stem of the file it was read from."""
        return self.name or Path(self.source).stem

    def with_split(self, dependent) -> "Model":
        """The same model with other dependent coordinates (``System.with_split``)."""
        return dataclasses.replace(self, system=self.system.with_split(dependent))
