"""Run options as small immutable values: one definition for ``Scene.run``,
``run_ensemble`` and ``sweep``.  Two spellings of one run::

    scene.run(step=StepControl(rtol=1e-11, max_step=0.1), singular=Singular(tol=1e-8))
    scene.run(rtol=1e-11, max_step=0.1, singular_tol=1e-8)         # the same run

``StepControl``: tolerances, step limits and the step budget (adaptive methods) or the
fixed step (``n_steps`` or ``h``); ``Singular``: what to do at a singular configuration
(``"stop"`` or ``"ignore"``) and the threshold of the indicators; ``Newton``: the
iteration of the implicit and discrete methods.  Each field is also a keyword of the
run (``KEYWORDS``: the fields' names; ``singular_tol``, ``newton_tol`` and
``max_newton`` for the other two): ``options`` folds the keywords into the values (a
keyword given together with a value that sets it too is refused) and returns them as
one ``Options``.  Values are checked where the run uses them (``numeric.arguments``).
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from ..errors import ArgumentError


@dataclass(frozen=True)
class StepControl:
    """Step control: ``rtol``, ``atol`` (scalar or per state), ``first_step``,
    ``max_step`` (None: automatic, none), ``max_steps`` (budget), ``n_steps`` or ``h``
    (fixed-step methods).  Besides the budget, dop853 and dopri5 stop a run their steps
    cannot carry: with status STIFF where Hairer's stiffness test finds the steps held
    by stability (use radau), and as a singular stop where the motion crawls toward a
    singular set it cannot approach (``methods.loop``, ``methods._events``)."""

    rtol: float = 1e-9
    atol: object = 1e-12
    first_step: float | None = None
    max_step: float | None = None
    max_steps: int = 10_000_000
    n_steps: int | None = None
    h: float | None = None


@dataclass(frozen=True)
class Singular:
    """At a singular configuration: ``action`` "stop" (the default) or "ignore"; an
    indicator below ``tol`` times its initial size counts as zero.  At the edge of the
    split's chart (``numeric.atlas``): ``split`` "switch" (the default: the run goes on
    in another regular split) or "fixed" (the run keeps the scene's split and stops at
    its singular set as at any other)."""

    action: str = "stop"
    tol: float = 1e-10
    split: str = "switch"

    def __post_init__(self):
        if self.action not in ("stop", "ignore"):
            raise ArgumentError(f"singular must be 'stop' or 'ignore', not {self.action!r}")
        if self.split not in ("switch", "fixed"):
            raise ArgumentError(f"split must be 'switch' or 'fixed', not {self.split!r}")

    @property
    def stops(self) -> bool:
        return self.action == "stop"


@dataclass(frozen=True)
class Newton:
    """The Newton iteration of radau, dla and dvi: tolerance and iteration limit (None:
    the method's default)."""

    tol: float | None = None
    max_iter: int | None = None


def merge(value, cls, given: dict):
    """``value`` (an instance of ``cls`` or None: the defaults) with the keywords
    ``given`` (named as the fields) that are not None folded in."""
    set_ = {k: v for k, v in given.items() if v is not None}
    if value is None:
        return cls(**set_) if set_ else _DEFAULT[cls]
    if not isinstance(value, cls):
        raise ArgumentError(f"expected a {cls.__name__}, got {type(value).__name__}")
    if not set_:
        return value
    default = _DEFAULT[cls]
    clash = [k for k in set_ if not _same(getattr(value, k), getattr(default, k))]
    if clash:
        raise ArgumentError(f"{', '.join(clash)} given both as keyword and in the "
                            f"{cls.__name__} value; give it once")
    return replace(value, **set_)


def fields_of(value) -> tuple:
    """The fields of an option value, in order (cheaper than ``dataclasses.astuple``,
    which copies them)."""
    return tuple(vars(value).values())


def typed(value):
    """An option value (``StepControl``, ``Singular``, ``Newton``, or a number, string,
    sequence or array of one) as a part of a key: each field and entry with its type
    (``True == 1``, but a run refuses a bool where it takes 1), an array as its bytes,
    dtype and shape."""
    if isinstance(value, (StepControl, Singular, Newton)):
        return (type(value), *map(typed, vars(value).values()))
    if type(value) is list or type(value) is tuple:
        return tuple(map(typed, value)), type(value)
    if hasattr(value, "__array__") and not isinstance(value, (int, float)):
        a = np.asarray(value)
        if a.dtype.hasobject:           # (its bytes are addresses, which are reused)
            return ("objects", type(value), a.shape,
                    tuple((v, type(v)) for v in a.ravel().tolist()))
        return ("array", type(value), a.dtype.str, a.shape, a.tobytes())
    return value, type(value)


def _same(a, b) -> bool:
    try:
        return bool(a is b or a == b)
    except ValueError:          # an array
        return False


def singular_of(singular, singular_tol, split=None) -> Singular:
    """The ``Singular`` of the keywords ``singular`` (a string or a ``Singular``),
    ``singular_tol`` and ``split``."""
    if isinstance(singular, Singular):
        return merge(singular, Singular, {"tol": singular_tol, "split": split})
    return merge(None, Singular, {"action": None if singular == "stop" else singular,
                                  "tol": singular_tol, "split": split})


_DEFAULT = {cls: cls() for cls in (StepControl, Singular, Newton)}

#: the keyword run options each value stands for
KEYWORDS = {"step": tuple(f.name for f in fields(StepControl)),
            "singular": ("singular", "singular_tol", "split"),
            "newton": ("newton_tol", "max_newton")}
#: every run option these values define: the values and their keywords
NAMES = tuple(dict.fromkeys(("step", "singular", "newton") + sum(KEYWORDS.values(), ())))


@dataclass(frozen=True)
class Options:
    """The grouped options of one run (``options``)."""

    step: StepControl
    singular: Singular
    newton: Newton

    def __hash__(self):
        """Computed once (an Options is part of the key of every plan it makes:
        ``solve.planned``); not pickled, as string hashes differ between processes."""
        h = self.__dict__.get("_hash")
        if h is None:
            h = hash((self.step, self.singular, self.newton))
            object.__setattr__(self, "_hash", h)
        return h

    def __eq__(self, other):
        """Equal fields of equal types (``typed``): options equal to a run's that the run
        would refuse (``max_steps=True`` against 1) are not its options."""
        return self is other or (type(other) is Options and self._typed() == other._typed())

    def _typed(self) -> tuple:
        found = self.__dict__.get("_key")
        if found is None:
            found = (typed(self.step), typed(self.singular), typed(self.newton))
            object.__setattr__(self, "_key", found)
        return found

    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if k not in ("_hash", "_key")}


def options(step=None, singular="stop", newton=None, **keywords) -> Options:
    """The ``Options`` of the values ``step``, ``singular`` (a ``Singular`` or its
    action), ``newton`` and their keywords (``KEYWORDS``; None: not given).  Repeated
    calls with the same plain keywords return one value."""
    if step is None and newton is None and type(singular) is str:
        if not keywords and singular == "stop":
            return _PLAIN
        try:
            key = (singular, *((k, type(v), v) for k, v in sorted(keywords.items())))
            hit = _SEEN.get(key)
        except TypeError:       # an array: not hashable
            key = hit = None
        if hit is not None:
            return hit
    else:
        key = None
    unknown = [k for k in keywords if k not in NAMES]
    if unknown:
        raise ArgumentError(f"{', '.join(unknown)}: not a run option; the run options are "
                            f"{', '.join(NAMES)}")
    g = keywords.get
    out = Options(merge(step, StepControl, {k: g(k) for k in KEYWORDS["step"]}),
                  singular_of(singular, g("singular_tol"), g("split")),
                  merge(newton, Newton, dict(tol=g("newton_tol"), max_iter=g("max_newton"))))
    if key is not None and len(_SEEN) < 256:
        _SEEN[key] = out
    return out


_SEEN: dict = {}
#: the options of a run that gives none
_PLAIN = Options(_DEFAULT[StepControl], _DEFAULT[Singular], _DEFAULT[Newton])
