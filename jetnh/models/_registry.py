"""The catalogue's bookkeeping: each model's factory, options, default initial state and span.

A factory returns a ``System`` (with its parameters' defaults); scalable families take
keyword options (``n_trailer(N=2)``).  ``ModelInfo.initial(**options)`` is a state that
the model's docstring discusses (a good default for ``jetnh simulate``), keyed by name;
states not in it start at 0.  ``ModelInfo.model(**options)`` is the ``Model`` (the
record model files give too): the System with that state and span.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from ..modelfile.model import Model

#: the largest value of a family's size option (N of n_trailer): checked before anything
#: is built (a derivation grows with it; N = 64 already means 67 coordinates)
MAX_OPTION = 64


@dataclass(frozen=True)
class ModelInfo:
    """One catalogue entry: how to build its ``Model`` for given options."""

    name: str
    factory: Callable
    initial_state: Callable[..., dict]
    t_end: float = 1.0
    options: dict = field(default_factory=dict)     # keyword -> default (scalable families)
    tags: tuple = ()

    @property
    def summary(self) -> str:
        doc = (self.factory.__doc__ or "").strip()
        return doc.splitlines()[0] if doc else self.name

    def _checked(self, options) -> dict:
        """``options`` after checking names and the size budget (before any building)."""
        from ..errors import ModelFileError

        unknown = sorted(set(options) - set(self.options))
        if unknown:
            have = ", ".join(f"{k} (default {v})" for k, v in self.options.items()) or "none"
            raise ModelFileError(f"model {self.name!r} has no option {', '.join(unknown)}; "
                                 f"its options: {have}")
        for k, v in options.items():
            if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= MAX_OPTION:
                raise ModelFileError(
                    f"model {self.name!r}: option {k} must be an integer from 0 to "
                    f"{MAX_OPTION} (the size budget), not {v!r}")
        return options

    def system(self, **options):
        """The System, with ``options`` (e.g. N=3) overriding the defaults."""
        return self.factory(**self._checked(options))

    def initial(self, **options) -> dict:
        """The default initial state (names -> floats) for these options."""
        opts = {**self.options, **self._checked(options)}
        return dict(self.initial_state(**opts)) if self.options else dict(self.initial_state())

    def model(self, **options) -> Model:
        """The ``Model``: the System with ``options``, its default initial state and
        ``t_end``; named ``name`` or, with options, ``name:K=V,...`` (as on the command
        line)."""
        given = ",".join(f"{k}={v}" for k, v in self._checked(options).items())
        return Model(self.system(**options), f"{self.name}:{given}" if given else self.name,
                     initial=self.initial(**options), simulation={"t_end": self.t_end},
                     source="catalogue")


INFO: dict[str, ModelInfo] = {}


def register(name, factory, initial, t_end=1.0, options=None, tags=()):
    """Add a model; ``initial`` is a dict or a function of the options returning one."""
    init = initial if callable(initial) else (lambda **_: initial)
    INFO[name] = ModelInfo(name, factory, init, float(t_end), dict(options or {}), tuple(tags))
    return factory


def model(name, *, initial, t_end=1.0, options=None, tags=()):
    """Decorator form of ``register``."""
    def wrap(factory):
        return register(name, factory, initial, t_end, options, tags)
    return wrap
