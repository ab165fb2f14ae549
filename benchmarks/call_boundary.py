"""Where the compiled call of a short run goes: the call boundary of the dop853 loop.

    python benchmarks/call_boundary.py [--quick] [--out PATH]

(default output: benchmarks/results/call_boundary.json).  The loop of overhead.py's bare
call (rolling disk, chetaev; dop853 at its machine-code entry, no type dispatch; three
steps of 1e-3, and a zero-length span: one rhs evaluation, no step) against compiled
functions of the same 13 arguments that do nothing but return: an integer (the unboxing
of the arguments), the loop's 6-tuple of two new arrays (the boxing of its result), and
the pieces: the Control and the Watch namedtuples, one array, returned arrays (each
boxed by numba with a call of ``numba.core.serialize._numba_unpickle`` for the array's
Python type).  CPU seconds of a call (``time.process_time``: the machine is shared),
best of rounds of ``N`` calls, the functions' rounds interleaved.
"""

import json
import time

import numba
import numpy as np
from numba import njit, types

from _common import parser, write

from jetnh import models
from jetnh.numeric import Scene, interrupt, loops, methods
from jetnh.numeric.methods._common import entry_point
from jetnh.numeric.methods.loop import ARGS, CONTROL, WATCHED, Control, watch_of

f8, i8 = types.float64, types.int64


def _nothing(a, b, c, d, t0, t1, y0, p, ctl, te, mode, watch, halt):
    return 0


def _six(a, b, c, d, t0, t1, y0, p, ctl, te, mode, watch, halt):
    stats = np.zeros(3, dtype=np.int64)
    return 0, np.empty(3), np.empty((3, y0.shape[0])), np.int64(1), (
        stats[0], stats[1], stats[2]), -1


def _one(x):
    return 0


def _given(a, b):
    return a, b


def _new(a, b):
    return np.empty(3), np.empty((3, b.shape[1]))


def calls():
    sc = Scene(models.get("rolling_disk"), "chetaev", initial=models.initial("rolling_disk"),
               t_span=(0.0, 1e-6)).compile()
    kern, y0 = sc.kernels, sc.y0.copy()
    watch = watch_of(kern, None, True, 1e-10)
    keep = []

    def loop(t1, ctl):
        got = loops.entry(sc, methods.method("dop853"), kern, None, None, ctl, np.zeros(0), 2,
                          watch, None)
        keep.append(got)
        entry, prefix, suffix = got[:3]
        args = (*prefix, 0.0, t1, y0, sc.p, *suffix, interrupt.flag())
        return args, lambda: entry(*args)

    h3 = float(np.nextafter(1e-3, np.inf))
    args, three = loop(3e-3, Control(1e-3, np.full(len(y0), 1e-3), h3, h3, 10**7, 0))
    _, zero = loop(0.0, Control(1e-9, np.full(len(y0), 1e-12), 0.0, np.inf, 10**7, 0))
    nothing = entry_point(njit(i8(*ARGS))(_nothing))
    six = entry_point(njit(ARGS)(_six))
    ctl_only = entry_point(njit(i8(CONTROL))(_one))
    watch_only = entry_point(njit(i8(WATCHED))(_one))
    array_only = entry_point(njit(i8(f8[::1]))(_one))
    none = entry_point(njit(i8())(lambda: 0))
    a, b = np.empty(3), np.empty((3, len(y0)))
    given = entry_point(njit((f8[::1], f8[:, ::1]))(_given))
    new = entry_point(njit((f8[::1], f8[:, ::1]))(_new))
    memo = numba.core.serialize
    pickled = memo.dumps(np.ndarray)
    key = (12345, pickled, b"\0" * 20)
    memo._numba_unpickle(*key)
    return {
        "3-step call": three,
        "zero-span call (one rhs evaluation)": zero,
        "no-op of the loop's arguments, returns an int": lambda: nothing(*args),
        "no-op of the loop's arguments, returns a 6-tuple of two new arrays": lambda: six(*args),
        "no arguments, returns an int": lambda: none(),
        "Control alone": lambda: ctl_only(args[8]),
        "Watch alone": lambda: watch_only(args[11]),
        "one array alone": lambda: array_only(y0),
        "two given arrays returned": lambda: given(a, b),
        "two new arrays returned": lambda: new(a, b),
        "_numba_unpickle, from Python": lambda: memo._numba_unpickle(*key),
        "a Python lambda": lambda: None,
    }, keep


def measure(fs, n, rounds):
    best = {k: np.inf for k in fs}
    for f in fs.values():
        f()
    for _ in range(rounds):
        for k, f in fs.items():
            tic = time.process_time()
            for _ in range(n):
                f()
            best[k] = min(best[k], (time.process_time() - tic) / n)
    return best


def main(argv=None):
    args = parser(__doc__, "call_boundary").parse_args(argv)
    fs, _keep = calls()
    n, rounds = (100, 5) if args.quick else (500, 60)
    best = measure(fs, n, rounds)
    us = {k: v * 1e6 for k, v in best.items()}
    unbox = us["no-op of the loop's arguments, returns an int"] - us["no arguments, returns an int"]
    box = (us["no-op of the loop's arguments, returns a 6-tuple of two new arrays"]
           - us["no-op of the loop's arguments, returns an int"])
    start = us["zero-span call (one rhs evaluation)"] - (
        us["no-op of the loop's arguments, returns a 6-tuple of two new arrays"])
    summary = (f"the loop's zero-span call {us['zero-span call (one rhs evaluation)']:.2f} us "
               f"CPU: unboxing its 13 arguments {unbox:.2f} us, boxing its 6-tuple "
               f"{box:.2f} us, its start and one evaluation {start:.2f} us; the 3-step call "
               f"{us['3-step call']:.2f} us")
    print(summary)
    for k, v in us.items():
        print(f"{v:8.3f} us  {k}")
    write("call_boundary", dict(title="The call boundary of the compiled loop (CPU us)",
                                summary=[summary], us=us, calls_per_round=n, rounds=rounds),
          args.out, args.quick)


if __name__ == "__main__":
    main()
