"""Numeric helpers shared by the compiled integrators (none of them calls the rhs).

Status codes returned by every ``solve`` (``Status``; the compiled loops use the plain
integers of the same names):

``FINISHED`` (0) reached the end of the interval; ``MAX_STEPS`` (1) stopped after the
allowed number of steps; ``TOO_SMALL_STEP`` (2) the step size fell below ten units in
the last place of t; ``NONFINITE`` (3) the right-hand side or the state became NaN or
infinite; ``NOT_CONVERGED`` (4) an implicit stage equation did not converge; ``EVENT``
(5) a terminal user event occurred; ``SINGULAR`` (6) a singularity indicator crossed zero
or fell below its threshold (see ``_events``); ``STOPPED`` (7) the caller asked the loop
to stop (its ``stop`` flag, checked before every step: Ctrl-C or a wall-clock budget,
see ``numeric.interrupt``); ``STIFF`` (8) an explicit method found the problem stiff: its
steps were bounded by its stability region, not by the tolerance (Hairer's test,
``loop.stiff_ratio``), so going on would only grind through the step budget.
"""

import enum
import hashlib
import math
import os
import types

import numba
import numpy as np
from numba.core import cgutils
from numba.extending import intrinsic


class Status(enum.IntEnum):
    """Why a run ended (see the module docstring)."""

    FINISHED = 0
    MAX_STEPS = 1
    TOO_SMALL_STEP = 2
    NONFINITE = 3
    NOT_CONVERGED = 4
    EVENT = 5
    SINGULAR = 6
    STOPPED = 7
    STIFF = 8


(FINISHED, MAX_STEPS, TOO_SMALL_STEP, NONFINITE, NOT_CONVERGED, EVENT, SINGULAR, STOPPED,
 STIFF) = (int(s) for s in Status)

STATUS_TEXT = {
    FINISHED: "reached the end of the interval",
    MAX_STEPS: "stopped after max_steps steps",
    TOO_SMALL_STEP: "step size fell below the spacing of floating-point numbers",
    NONFINITE: "the state or the right-hand side became NaN or infinite",
    NOT_CONVERGED: "an implicit stage equation did not converge",
    EVENT: "a terminal event occurred",
    SINGULAR: "stopped at a singular configuration",
    STOPPED: "stopped at the wall-clock budget (timeout)",
    STIFF: "the problem became stiff for the explicit method (use method='radau')",
}

#: the step-size controller of Hairer-Norsett-Wanner II.4 with scipy's constants
SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0

#: output modes
EVERY_STEP, AT_T_EVAL, ENDPOINTS = 0, 1, 2

#: the helpers: compiled into the loops that call them (only the loops are cached on disk);
#: ``jit`` each once per process (a library of its own, linked into its callers), ``inline``
#: into each caller at numba's IR level: the helpers called once or twice, which would
#: cost more as libraries (each compiled, then optimised again in every caller) than as code
jit = numba.njit(error_model="numpy", nogil=True)
inline = numba.njit(error_model="numpy", nogil=True, inline="always")


@jit
def all_finite(x):
    for i in range(x.shape[0]):
        if not math.isfinite(x[i]):
            return False
    return True


@jit
def grow(ts, ys, n):
    """Make room for at least n + 1 rows, doubling the capacity."""
    if n < ts.shape[0]:
        return ts, ys
    cap = max(2 * ts.shape[0], 16)
    ts2 = np.empty(cap)
    ys2 = np.empty((cap, ys.shape[1]))
    for i in range(n):
        ts2[i] = ts[i]
        for j in range(ys.shape[1]):
            ys2[i, j] = ys[i, j]
    return ts2, ys2


@jit
def store(ts, ys, n, t, y):
    ts, ys = grow(ts, ys, n)
    ts[n] = t
    for j in range(y.shape[0]):
        ys[n, j] = y[j]
    return ts, ys, n + 1


@inline
def initial_step_h0(y0, f0, rtol, atol, interval, scale):
    """First half of the starting-step heuristic (Hairer-Norsett-Wanner II.4, p. 169):
    h0 from |y0| and |f0|; fills ``scale`` = atol + rtol |y0|."""
    for i in range(y0.shape[0]):
        scale[i] = atol[i] + abs(y0[i]) * rtol
    d0 = 0.0
    d1 = 0.0
    for i in range(y0.shape[0]):
        d0 += (y0[i] / scale[i]) ** 2
        d1 += (f0[i] / scale[i]) ** 2
    n = max(y0.shape[0], 1)
    d0 = math.sqrt(d0 / n)
    d1 = math.sqrt(d1 / n)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    return min(h0, interval), d1


@inline
def initial_step_h1(f0, f1, h0, d1, scale, order, interval, max_step):
    """Second half: an explicit Euler step of size h0 estimates the second derivative."""
    d2 = 0.0
    for i in range(f0.shape[0]):
        d2 += ((f1[i] - f0[i]) / scale[i]) ** 2
    d2 = math.sqrt(d2 / max(f0.shape[0], 1)) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1))
    return min(100 * h0, h1, interval, max_step)


@inline
def start(rhs, t, y, p, f0, f1, ytmp, scale, ctl, error_order, t_end, stats, mode, t_eval,
          ts, ys, n_out):
    """The start of an adaptive run (every adaptive loop): ``f0 = f(t0, y0)`` checked
    finite, the first output row, a zero-length span answered, and the first step
    (``ctl.first_step`` or the heuristic of ``initial_step_h0``/``_h1``; ``f1`` is
    scratch).  Returns ``(status, h_abs, ts, ys, n_out)``: status NONFINITE or FINISHED
    (the run is over) or -1 (go on with the step h_abs)."""
    rtol, atol, first_step, max_step = ctl[0], ctl[1], ctl[2], ctl[3]
    direction = 1.0 if t_end >= t else -1.0
    interval = abs(t_end - t)
    rhs(t, y, p, f0)
    stats[2] += 1
    if not all_finite(f0):
        return NONFINITE, 0.0, ts, ys, n_out
    if mode != AT_T_EVAL:
        ts, ys, n_out = store(ts, ys, n_out, t, y)
    if interval == 0.0:
        if mode == AT_T_EVAL:
            j = 0
            while j < t_eval.shape[0] and t_eval[j] == t:
                ts, ys, n_out = store(ts, ys, n_out, t, y)
                j += 1
        return FINISHED, 0.0, ts, ys, n_out
    if first_step > 0.0:
        return -1, first_step, ts, ys, n_out
    h0, d1 = initial_step_h0(y, f0, rtol, atol, interval, scale)
    for i in range(y.shape[0]):
        ytmp[i] = y[i] + h0 * direction * f0[i]
    rhs(t + h0 * direction, ytmp, p, f1)
    stats[2] += 1
    return -1, initial_step_h1(f0, f1, h0, d1, scale, error_order, interval, max_step), ts, \
        ys, n_out


@jit
def copy_into(dst, src):
    """dst[:] = src as a loop (numba compiles slice assignment slowly)."""
    for i in range(src.shape[0]):
        dst[i] = src[i]


@inline
def min_step(t, direction):
    """Ten units in the last place of t in the direction of integration."""
    return 10.0 * abs(np.nextafter(t, direction * np.inf) - t)


# ---------------------------------------------------------------------- compiled entry points
f8 = numba.types.float64
i8 = numba.types.int64
#: the type of every right-hand side: rhs(t, y, p, out) -> None
RHS_SIGNATURE = numba.types.void(f8, f8[::1], f8[::1], f8[::1])
RHS = numba.types.FunctionType(RHS_SIGNATURE)

_COMPILED = {}
_SOURCES_HASH = None
HERE = os.path.dirname(os.path.abspath(__file__))


def sources_hash() -> str:
    """A hash of every module of this package: what the compiled loops are made of
    (computed once a process)."""
    global _SOURCES_HASH
    if _SOURCES_HASH is not None:
        return _SOURCES_HASH
    h = hashlib.sha256()
    for name in sorted(os.listdir(HERE)):
        if name.endswith(".py"):
            with open(os.path.join(HERE, name), "rb") as f:
                h.update(name.encode() + b"\0" + f.read())
    _SOURCES_HASH = h.hexdigest()[:16]
    return _SOURCES_HASH


def compiled(pyfunc, argtypes, parallel=False, namespace=None, tag=""):
    """``pyfunc`` compiled for ``argtypes`` on first use and kept on disk in jetnh's
    signed store (``kernels.loop_cache``: numba's cache format, read only after its HMAC
    is checked; never numba's own cache directories); with ``namespace``, over those
    globals instead of its module's (a specialisation, named with ``tag``).

    The right-hand side is an argument given by its address (``function_at``), so the
    compiled loop does not depend on which scene calls it: one compilation serves all.
    The disk cache keys a function by its own code only, not the helpers compiled into it
    (``jit``, from other modules), so the key carries what the loop depends on: the
    function is stored under its name suffixed with ``sources_hash()`` (and stamped with
    it), and an edit of any module here compiles it anew.  (The cache does not key on
    ``parallel``: a function compiled both ways must be two Python functions.)
    """
    key = (pyfunc.__module__, pyfunc.__qualname__, tag)
    if key not in _COMPILED:
        from ..kernels.loop_cache import cache_for

        stamp = sources_hash()
        func = rebound(pyfunc, namespace)
        func.__qualname__ = "_".join(filter(None, (pyfunc.__qualname__, tag, stamp)))
        func.__module__ = pyfunc.__module__
        func.__doc__ = pyfunc.__doc__
        dispatcher = numba.njit(error_model="numpy", nogil=True, parallel=parallel)(func)
        dispatcher._cache = cache_for(func, stamp)
        dispatcher.compile(tuple(argtypes))
        dispatcher.disable_compile()
        _COMPILED[key] = dispatcher
    return _COMPILED[key]


def apart(pyfunc, namespace, tag):
    """``pyfunc`` over the globals ``namespace`` as a jit function of a name of its own
    (``compiled``'s rule, ``tag``): a function that a compiled entry calls, compiled into
    it (and kept on disk with it) as a function apart."""
    func = rebound(pyfunc, namespace)
    func.__qualname__ = "_".join(filter(None, (pyfunc.__qualname__, tag, sources_hash())))
    func.__module__ = pyfunc.__module__
    return numba.njit(error_model="numpy", nogil=True)(func)


def rebound(pyfunc, namespace=None):
    """A copy of the Python function ``pyfunc`` whose globals are ``namespace`` (default:
    its own)."""
    return types.FunctionType(pyfunc.__code__, pyfunc.__globals__ if namespace is None
                              else namespace, pyfunc.__name__, pyfunc.__defaults__,
                              pyfunc.__closure__)


class FunctionAddress:
    """A compiled C callback (a numba ``cfunc``) as numba's *wrapper address protocol*
    object: passed for a first-class-function argument, it unboxes to its cached address
    without the signature comparison numba makes for a cfunc (~20 us a call).  It must
    wrap a cfunc of the declared signature (``RHS_SIGNATURE``, or ``signature``)."""

    __slots__ = ("address", "cfunc")

    def __init__(self, cfunc, signature=RHS_SIGNATURE):
        if isinstance(cfunc, FunctionAddress):
            cfunc = cfunc.cfunc
        if cfunc._sig != signature:
            raise TypeError(f"expected a cfunc of signature {signature}, got {cfunc._sig}")
        self.cfunc = cfunc          # keeps the machine code alive
        self.address = cfunc.address

    def __wrapper_address__(self):
        return self.address


def callback_at(kind):
    """An intrinsic turning an integer address into the first-class function of type
    ``kind`` (a numba ``FunctionType``) whose C callback is there: the compiled loops take
    their callbacks as integers, which cost nothing to pass from Python, where numba
    unboxes a first-class function by two calls into Python (~2.3 us per argument and
    call).  Calling the result calls the address with ``kind``'s C signature; the caller
    keeps the callback alive (its ``FunctionAddress``) while the loop runs."""

    @intrinsic
    def at(typingctx, address):
        if not isinstance(address, numba.types.Integer):
            return None

        def codegen(context, builder, signature, args):
            value = cgutils.get_null_value(context.get_value_type(kind))
            return builder.insert_value(value, builder.inttoptr(args[0], cgutils.voidptr_t), 0)

        return kind(address), codegen

    return at


#: the right-hand side (type ``RHS``) at an address (``FunctionAddress.address``)
function_at = callback_at(RHS)


def entry_point(dispatcher):
    """The machine-code entry of a dispatcher compiled for one explicit signature: calling
    it skips numba's type dispatch (``typeof`` of every argument, ~15 us for each
    first-class function), which dominates the cost of a short run called from Python.
    The caller must pass exactly the declared types."""
    sigs = dispatcher.signatures
    if len(sigs) != 1:
        return dispatcher
    return dispatcher.overloads[sigs[0]].entry_point


@jit
def collect(r, res, mode, OUT_T, OUT_Y, INFO, T_LAST, Y_LAST, EV_N, EV_T):
    """Store run r of an ensemble: its output rows (NaN after an early stop; with
    ``mode == ENDPOINTS`` only the final row), ``INFO[r] = (status, steps, rejected, rhs
    evaluations, rows, singular index)``, its last state, and per event the number of
    occurrences and the first time."""
    status, ts, ys, n_out, stats, t, y, ev_t, ev_i, ev_y, n_ev, sing_index = res
    n = Y_LAST.shape[1]
    n_times = OUT_T.shape[1]
    if mode == ENDPOINTS:
        filled = 1 if n_out > 0 else 0
        first = n_out - 1
    else:
        filled = min(n_out, n_times)
        first = 0
    for k in range(filled):
        OUT_T[r, k] = ts[first + k]
        for j in range(n):
            OUT_Y[r, k, j] = ys[first + k, j]
    for k in range(filled, n_times):
        OUT_T[r, k] = np.nan
        for j in range(n):
            OUT_Y[r, k, j] = np.nan
    INFO[r, 0] = status
    INFO[r, 1] = stats[0]
    INFO[r, 2] = stats[1]
    INFO[r, 3] = stats[2]
    INFO[r, 4] = n_out
    INFO[r, 5] = sing_index
    T_LAST[r] = t
    if y is None:           # a watching loop that finished: its last state in row n_out
        for j in range(n):
            Y_LAST[r, j] = ys[n_out, j]
    else:
        for j in range(n):
            Y_LAST[r, j] = y[j]
    for a in range(n_ev):
        k = ev_i[a]
        if EV_N[r, k] == 0:
            EV_T[r, k] = ev_t[a]
        EV_N[r, k] += 1


@intrinsic
def take_next(typingctx, counter):
    """``counter[0]`` before adding 1 to it, atomically (an int64 array): the threads of
    an ensemble driver each take the next run so, until the runs are out (dynamic
    scheduling; numba's ``prange`` hands each thread a fixed block of iterations)."""
    if not (isinstance(counter, numba.types.Array) and counter.dtype == numba.types.int64):
        return None

    def codegen(context, builder, signature, args):
        data = context.make_array(signature.args[0])(context, builder, args[0]).data
        one = context.get_constant(numba.types.int64, 1)
        return builder.atomic_rmw("add", data, one, "monotonic")

    return numba.types.int64(counter), codegen


#: argument types of the ensemble drivers after the solver's own arguments
ENSEMBLE_OUT = (numba.types.float64[:, ::1], numba.types.float64[:, :, ::1],
                numba.types.int64[:, ::1], numba.types.float64[::1],
                numba.types.float64[:, ::1], numba.types.int64[:, ::1],
                numba.types.float64[:, ::1])


@jit
def solve_linear(A, b, x):
    """x = A^-1 b by Gaussian elimination with partial pivoting (A, b overwritten).
    Returns False if A is singular to working precision."""
    n = b.shape[0]
    for c in range(n):
        piv = c
        big = abs(A[c, c])
        for r in range(c + 1, n):
            if abs(A[r, c]) > big:
                big = abs(A[r, c])
                piv = r
        if big == 0.0 or not math.isfinite(big):
            return False
        if piv != c:
            for j in range(n):
                A[c, j], A[piv, j] = A[piv, j], A[c, j]
            b[c], b[piv] = b[piv], b[c]
        for r in range(c + 1, n):
            m = A[r, c] / A[c, c]
            if m != 0.0:
                for j in range(c, n):
                    A[r, j] -= m * A[c, j]
                b[r] -= m * b[c]
    for r in range(n - 1, -1, -1):
        s = b[r]
        for j in range(r + 1, n):
            s -= A[r, j] * x[j]
        x[r] = s / A[r, r]
    return True
