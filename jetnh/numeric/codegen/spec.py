"""What a set of kernels is made from (``KernelSpec``: their identity and its key) and
what code generation makes of it (``KernelSource``).

The key hashes the symbolic input, not the output, so that a cache hit skips the
derivation, the code generation and compilation; it carries every Python file of the
package (``source_hash``), so that no edit of the derivation or of the code generator can
leave a stale kernel behind a warm cache.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import pathlib
from dataclasses import dataclass, field

import sympy as sp

from ...algebra import dag
from ...frozen import FrozenDict
from ...mechanics import principles
from ..layout import CODEGEN_VERSION, Layout
from .quick import quick_ops

#: the kernel sets of one scene: its continuous kernels, with the Jacobian of ``rhs``,
#: with sensitivities, the discrete step's, the user events' and connect's verdicts'
#: (``KernelSpec.variant``)
VARIANTS = ("", "jacobian", "sensitivities", "discrete", "events", "verdicts")


@dataclass
class KernelSource:
    """Generated source text and its layout."""

    key: str
    layout: Layout
    source: str
    timings: dict = field(default_factory=dict)


def multiplier_symbols(system, principle) -> tuple[sp.Symbol, ...]:
    """The multiplier states of ``principle`` (name, alias or value), without deriving:
    the one rule every kernel, layout and scene names them by."""
    return tuple(principles.get(principle).multiplier_symbols(system))


def multiplier_names(system, principle) -> tuple[str, ...]:
    """Names of the multiplier states of ``principle`` (``multiplier_symbols``)."""
    return tuple(s.name for s in multiplier_symbols(system, principle))


def source_hash(root: pathlib.Path) -> str:
    """A hash of every Python file of the package at ``root`` (path and bytes, in path
    order): any edit, move or new module invalidates the cached kernels, so no hand-kept
    list of the modules that shape a kernel can go stale."""
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        h.update(path.relative_to(root).as_posix().encode() + b"\0")
        h.update(path.read_bytes() + b"\0")
    return h.hexdigest()[:16]


@functools.lru_cache(maxsize=1)
def _derivation_source_hash() -> str:
    return source_hash(pathlib.Path(__file__).resolve().parents[2])


def symbolic_key(system, principle, params, runtime_params=(), integrals=None, form=None,
                 convention="paper", extra="") -> str:
    """A hash of everything the kernels depend on (the symbolic input, not the output), so a
    cache hit skips the derivation, the code generation and compilation."""
    import numba

    J = system.J
    h = hashlib.sha256()
    parts = [
        "jetnh-codegen", CODEGEN_VERSION, _derivation_source_hash(), sp.__version__,
        numba.__version__,
        repr(tuple(s.name for s in J.q)), J.t.name,
        dag.fingerprint(system.L),
        repr(tuple(dag.fingerprint(f) for f in system.constraints)),
        repr(tuple(dag.fingerprint(g) for g in system.holonomic)),
        repr(tuple((q.name, dag.fingerprint(e)) for q, e in system.forces.items())),
        dag.fingerprint(system.dissipation),
        repr(tuple(s.name for s in system.dependent)), repr(system.branch),
        principle, repr(form), convention,
        repr(sorted((k, float(v).hex()) for k, v in params.items())),
        repr(tuple(runtime_params)),
        repr(sorted((k, dag.fingerprint(v)) for k, v in (integrals or {}).items())),
        extra, f"quick above {quick_ops()}",
    ]
    for part in parts:
        h.update(part.encode())
        h.update(b"\0")
    return h.hexdigest()[:24]


@dataclass(frozen=True, eq=False)
class KernelSpec:
    """The identity of a set of kernels, and its key (computed once, at construction).

    ``params``: parameter name -> number; the runtime ones (``runtime_params``, read from
    ``p`` at run time) are dropped, the others are compiled in as constants.
    ``integrals``: name -> sympy expression (first integrals ``aux`` evaluates).
    ``variant``: one of ``VARIANTS`` -- "" the scene's ``rhs``, ``aux``, ``sing`` (and
    ``hol``); "jacobian" with ``jac``; "sensitivities" the state augmented by its
    sensitivities; "discrete" the discrete step of ``principle`` ("chetaev": dla,
    "vakonomic": dvi); "events" the user events ``events`` (``(index, expr)`` pairs);
    "verdicts" what connect's verdicts read along a motion (``codegen.verdicts``).
    Two specs are equal when their keys are.
    """

    system: object
    principle: str
    params: FrozenDict = field(default_factory=FrozenDict)
    runtime_params: tuple = ()
    integrals: FrozenDict = field(default_factory=FrozenDict)
    form: str | None = None
    convention: str = "paper"
    variant: str = ""
    events: tuple = ()
    key: str = field(init=False, repr=False)

    def __post_init__(self):
        runtime = tuple(self.runtime_params)
        if self.variant not in VARIANTS:
            raise ValueError(f"unknown kernel variant {self.variant!r}")
        values = dict(
            principle=principles.canonical(self.principle), runtime_params=runtime,
            params=FrozenDict({str(k): v for k, v in self.params.items()
                               if str(k) not in runtime}),
            integrals=FrozenDict({str(k): v for k, v in (self.integrals or {}).items()}),
            events=tuple(self.events))
        for name, value in values.items():
            object.__setattr__(self, name, value)
        extra = self.variant
        if self.variant == "events":
            extra = "events:" + repr([(i, dag.fingerprint(e)) for i, e in self.events])
        object.__setattr__(self, "key", symbolic_key(
            self.system, self.principle, self.params, runtime, self.integrals, self.form,
            self.convention, extra=extra))

    def but(self, **changes) -> "KernelSpec":
        """This spec with ``changes`` (a new key)."""
        return dataclasses.replace(self, **changes)

    @property
    def multipliers(self) -> tuple[sp.Symbol, ...]:
        """The multiplier states (``multiplier_symbols``)."""
        return multiplier_symbols(self.system, self.principle)

    def __eq__(self, other):
        return isinstance(other, KernelSpec) and other.key == self.key

    def __hash__(self):
        return hash(self.key)
