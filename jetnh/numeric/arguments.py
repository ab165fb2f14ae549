"""The checks of every run argument that crosses into compiled code.

A compiled loop trusts its arrays: a state vector of the wrong length reads and writes
outside its buffers, a NaN tolerance or a zero step never ends.  So every argument of
``Scene.run`` and of the ensembles is checked here first, and turned into exactly the
types the compiled loops declare (contiguous float64 arrays, Python floats and ints):

- numbers: real, finite (``inf`` only where it means "no limit"), of the right sign;
  integers are integers (``100.0`` is accepted, ``100.5``, ``True`` and ``nan`` are not);
- tolerances: ``rtol`` 0 or in [100 eps, 1) (a relative error of 100 % accepts any step),
  ``atol`` >= 0, a scalar or one value per
  state, and every state with a nonzero error scale (``rtol > 0`` or its ``atol > 0``);
- the state ``y0`` and the run-time parameters ``params``: a dict keyed by Symbol, name or
  dynamicsymbol (``jetnh.geometry.jet.key_name``; missing entries keep the scene's
  values) or a sequence in the documented order (``scene.state_names``,
  ``scene.runtime_params``) of exactly the right length;
- budgets: ``max_steps`` bounds the steps of every method (the fixed-step methods refuse
  ``n_steps`` beyond it up front), the stored rows fit in ``MAX_OUTPUT_BYTES``, and
  ``timeout`` (seconds of wall-clock time) stops a run that takes too long.

Every refusal is an ``ArgumentError`` (a ``JetnhError`` and ``ValueError``) that names the argument, the value and the fix.
"""

from __future__ import annotations

import math
import operator

import numpy as np
import sympy as sp

from ..errors import ArgumentError
from ..geometry.jet import key_name

#: the smallest nonzero relative tolerance that float64 arithmetic can honour
RTOL_MIN = 100 * np.finfo(float).eps
#: the largest output a run may allocate up front (rows x states x 8 bytes)
MAX_OUTPUT_BYTES = 4 * 2**30
#: the largest step budget (numba's int64 counters, and far beyond any real run)
MAX_STEPS_LIMIT = 2**53


def name_of(key, what) -> str:
    """The name of a key given as a Symbol or a string."""
    name = key_name(key)
    if name is not None:
        return name
    raise ArgumentError(f"{what} must be keyed by Symbol, by name or by dynamicsymbol x(t) "
                        f"(or x(t).diff()), not {type(key).__name__} "
                     f"({key!r})")


def real(value, what) -> float:
    """A real number as a float (NaN and infinities pass: see ``finite``)."""
    if type(value) is float:            # (most: at once)
        return value
    if isinstance(value, (bool, np.bool_)) or isinstance(value, (str, bytes)):
        raise ArgumentError(f"must be a number, got {value!r}", argument=what)
    if isinstance(value, (complex, np.complexfloating)) or (
            isinstance(value, sp.Basic) and value.is_real is False):
        raise ArgumentError(f"must be a real number, got {value!r}", argument=what)
    try:
        return float(value)
    except (TypeError, ValueError, OverflowError):
        raise ArgumentError(f"must be a number, got {value!r}", argument=what) from None


def finite(value, what) -> float:
    v = real(value, what)
    if not math.isfinite(v):
        raise ArgumentError(f"is {v}; give a finite number", argument=what)
    return v


def positive(value, what, allow_inf=False) -> float:
    """A number > 0 (``inf`` too when ``allow_inf``: "no limit")."""
    v = real(value, what)
    if math.isnan(v) or v <= 0.0 or (math.isinf(v) and not allow_inf):
        raise ArgumentError(f"must be a positive {'number' if allow_inf else 'finite number'}"
                            f", got {value!r}", argument=what)
    return v


def count(value, what, limit=MAX_STEPS_LIMIT) -> int:
    """A positive integer (an integral float such as ``1e4`` is accepted)."""
    if isinstance(value, (bool, np.bool_)):
        raise ArgumentError(f"must be a positive integer, got {value!r}", argument=what)
    try:
        v = operator.index(value)
    except TypeError:
        f = real(value, what)
        if not (math.isfinite(f) and f.is_integer()):
            raise ArgumentError(f"must be a positive integer, got {value!r}",
                                argument=what) from None
        v = int(f)
    if not 1 <= v <= limit:
        raise ArgumentError(f"must be a positive integer of at most {limit}, got {value!r}",
                            argument=what)
    return v


def all_finite(a: np.ndarray, b: np.ndarray | None = None) -> bool:
    """Whether every entry of the float arrays ``a`` (and ``b``) is finite: a finite sum
    says so cheaply (of the entries as Python floats for a few, which never warns; else of
    squares); where it is not (a NaN, an infinity or an overflow), each entry is looked
    at."""
    if a.size + (0 if b is None else b.size) <= _FEW:
        total = sum(a.reshape(-1).tolist())
        if b is not None:
            total += sum(b.reshape(-1).tolist())
    else:
        flat = a.reshape(-1)
        with np.errstate(over="ignore", invalid="ignore"):   # an overflow: looked at below
            total = flat.dot(flat)
            if b is not None:
                flat = b.reshape(-1)
                total += flat.dot(flat)
    return math.isfinite(total) or bool(
        np.isfinite(a).all() and (b is None or np.isfinite(b).all()))


#: up to this many entries ``all_finite`` sums Python floats (no ``np.errstate``, which
#: costs more than the sum)
_FEW = 256


def real_array(value, what, ndim=1) -> np.ndarray:
    """A C-contiguous float64 array of ``ndim`` dimensions from numbers only (no strings,
    booleans, complex values or symbols), all finite."""
    a = np.asarray(value)
    if a.dtype.kind == "O":
        flat = [real(v, what) for v in a.ravel()]
        a = np.asarray(flat, dtype=float).reshape(a.shape)
    elif a.dtype.kind in "bc" or a.dtype.kind not in "iuf":
        raise ArgumentError(f"must hold real numbers, got an array of {a.dtype}",
                            argument=what)
    a = np.array(a, dtype=float, order="C")      # (ascontiguousarray makes 0-d 1-d)
    if a.ndim != ndim:
        raise ArgumentError(f"must be {'a number' if ndim == 0 else f'{ndim}-d'}, "
                            f"got shape {a.shape}", argument=what)
    if not all_finite(a):
        bad = tuple(int(i) for i in np.argwhere(~np.isfinite(a))[0])
        where = "" if ndim == 0 else f" at index {bad if ndim > 1 else bad[0]}"
        raise ArgumentError(f"has a non-finite value ({a[bad]}){where}; give finite "
                            "numbers", argument=what)
    return a


def tolerances(rtol, atol, n) -> tuple[float, np.ndarray]:
    """``(rtol, atol as one value per state)`` for an error scale atol_i + rtol |y_i|."""
    r = real(rtol, "rtol")
    if not (math.isfinite(r) and (r == 0.0 or r >= RTOL_MIN)):
        raise ArgumentError(f"must be 0 or a finite number >= {RTOL_MIN:.3g} (float64 cannot "
                            f"honour a smaller relative error), got {rtol!r}", argument="rtol")
    if r >= 1.0:
        raise ArgumentError(f"must be below 1, got {rtol!r}: a relative error of 100 % or more "
                            "accepts any step, so the run would succeed with a meaningless "
                            "answer; give e.g. rtol=1e-6 (loose) to 1e-12 (tight)",
                            argument="rtol")
    if type(atol) is float and atol > 0.0 and atol != math.inf:     # the common case, fast
        return r, np.full(n, atol)
    a = np.asarray(atol)
    if a.ndim > 1 or (a.ndim == 1 and a.shape[0] != n):
        raise ArgumentError(f"must be a number or one value per state ({n}), got shape "
                            f"{a.shape}", argument="atol")
    a = real_array(a, "atol", a.ndim)
    if np.any(a < 0):
        raise ArgumentError(f"must be >= 0, got {atol!r}", argument="atol")
    a = np.ascontiguousarray(np.broadcast_to(a, (n,)), dtype=float)
    if r == 0.0 and np.any(a == 0.0):
        i = int(np.argmax(a == 0.0))
        raise ArgumentError(f"is 0 for state {i} while the relative tolerance is 0, which "
                            "leaves it without an error scale (no step would ever be "
                            "accepted); give a positive absolute or relative tolerance",
                            argument="atol")
    return r, a


#: the fewest representable times a span must hold (2**16: steps of a thousandth of the
#: span are still resolved to 1.5 %; fewer and t + h == t, or h is rounded to nothing)
MIN_TIME_RESOLUTION = 2**16


def time_span(t_span) -> tuple[float, float]:
    """``(t0, t1)``: real, finite, of nonzero finite length holding at least
    ``MIN_TIME_RESOLUTION`` representable times (else steps cannot be resolved:
    ``t + h == t``).  A zero length is refused too: there is nothing to integrate, and
    ``(1e20, 1e20 + 1)`` is such a span once ``1e20 + 1`` rounds to ``1e20``."""
    try:
        t0, t1 = t_span
    except (TypeError, ValueError):
        raise ArgumentError(f"t_span must be a pair (t0, t1), got {t_span!r}") from None
    t0, t1 = real(t0, "t_span[0]"), real(t1, "t_span[1]")
    length = abs(t1 - t0)
    if MIN_TIME_RESOLUTION * math.ulp(max(abs(t0), abs(t1))) <= length < math.inf:
        return t0, t1           # (most: at once; a NaN, an infinity, a zero length fail)
    if not (math.isfinite(t0) and math.isfinite(t1)):
        raise ArgumentError(f"t_span must be finite, got {t_span!r}")
    if t0 == t1:
        raise ArgumentError(
            f"t_span = ({t0!r}, {t1!r}) has zero length: there is nothing to integrate; give "
            "t1 != t0 (if t1 was written as t0 plus a small length, it rounded to t0 in "
            "floating point: shift the time origin, e.g. t_span=(0, length))")
    ulp = math.ulp(max(abs(t0), abs(t1)))
    if not math.isfinite(length) or length < MIN_TIME_RESOLUTION * ulp:
        raise ArgumentError(
            f"t_span = ({t0!r}, {t1!r}) cannot be resolved in floating point: "
            + (f"its length overflows" if not math.isfinite(length) else
               f"it holds only {length / ulp:.3g} representable times (at least "
               f"{MIN_TIME_RESOLUTION} are needed, or t + h == t for the steps)")
            + "; shift the time origin (for an autonomous system t_span=(0, "
            "t1 - t0) gives the same motion) or shorten the span")
    return t0, t1


def step_limits(first_step, max_step) -> tuple[float, float]:
    """``(first_step or 0.0 = automatic, max_step)`` of an adaptive method."""
    first = 0.0 if first_step is None else positive(first_step, "first_step")
    return first, positive(max_step, "max_step", allow_inf=True)


def times(t_eval, t0, t1) -> np.ndarray:
    """Output times: finite, inside ``[t0, t1]``, sorted in the direction of integration."""
    te = real_array(t_eval, "t_eval")
    lo, hi = min(t0, t1), max(t0, t1)
    if te.size and (te.min() < lo or te.max() > hi):
        raise ArgumentError(f"t_eval must lie within t_span = ({t0}, {t1}); it spans "
                         f"[{te.min()}, {te.max()}]")
    if np.any(np.diff(te) * (1 if t1 >= t0 else -1) < 0):
        raise ArgumentError("t_eval must be sorted in the direction of integration")
    return te


def fixed_steps(n_steps, h, t0, t1, what, max_steps) -> int:
    """The number of steps of a fixed-step method from ``n_steps`` or ``h`` over the
    checked span ``(t0, t1)`` (``time_span``: of nonzero length).

    From ``h`` the step taken is ``span / ceil(span / h)``: the fewest equal steps none
    longer than ``h`` (``h`` itself when it divides the span; a ratio within a relative
    1e-9 of a whole number counts as that number, so ``h = span / n`` gives ``n``)."""
    if n_steps is not None and h is not None:
        raise ArgumentError(f"{what}: give n_steps= or h=, not both")
    if n_steps is None:
        if h is None:
            raise ArgumentError(f"{what} is a fixed-step method: give n_steps= or h=")
        hh = positive(h, "h")
        ratio = abs(t1 - t0) / hh
        nearest = round(ratio)
        whole = abs(ratio - nearest) <= 1e-9 * ratio
        steps = max(1.0, nearest if whole else math.ceil(ratio))
        if steps > max_steps:
            raise ArgumentError(
                f"h = {hh:g} over t_span = ({t0}, {t1}) needs {steps:.3g} steps, beyond the "
                f"budget max_steps = {max_steps}; take a larger h or raise max_steps")
        return int(steps)
    steps = count(n_steps, "n_steps")
    if steps > max_steps:
        raise ArgumentError(f"= {steps} is beyond the budget max_steps = {max_steps}; "
                            "raise max_steps to allow it", argument="n_steps")
    return steps


def output_rows(rows, width, save):
    """Refuse an output that cannot be allocated."""
    size = (rows + 1) * (width + 1) * 8
    if save == "steps" and size > MAX_OUTPUT_BYTES:
        raise ArgumentError(
            f"storing {rows + 1} rows of {width} values takes {size / 2**30:.3g} GiB (limit "
            f"{MAX_OUTPUT_BYTES / 2**30:.3g} GiB); pass save='final', or fewer steps")


def timeout(value) -> float | None:
    """Seconds of wall-clock time a run may take (None or ``inf``: no limit)."""
    if value is None:
        return None
    v = positive(value, "timeout", allow_inf=True)
    return None if math.isinf(v) else v


def keyed_or_sequence(value, names, defaults, what, order_name) -> tuple[np.ndarray, dict]:
    """Values for ``names``: a dict keyed by Symbol, name or dynamicsymbol (missing keys keep
    ``defaults``; returns the given ones too) or a sequence in the order ``names``."""
    if isinstance(value, dict):
        given = {}
        for k, v in value.items():
            name = name_of(k, what)
            given[name] = finite(v, f"{what}[{name!r}]")
        out = np.array([given.get(nm, d) for nm, d in zip(names, defaults)], dtype=float)
        return np.ascontiguousarray(out), given
    if isinstance(value, (str, bytes)) or np.ndim(value) == 0 and not isinstance(
            value, (list, tuple, np.ndarray)):
        raise ArgumentError(f"{what} must be a dict keyed by name or a sequence of "
                         f"{len(names)} numbers in the order {order_name}, got {value!r}")
    a = real_array(value, what)
    if a.shape[0] != len(names):
        listing = ", ".join(names) if len(names) <= 20 else f"{', '.join(names[:20])}, ..."
        raise ArgumentError(f"{what} has {a.shape[0]} values, but this scene has {len(names)} "
                         f"({order_name}: {listing or 'none'}); pass exactly those, or a dict "
                         "keyed by name")
    return a, dict(zip(names, a.tolist()))
