"""A picklable function computed in a forked child process within a budget of CPU and
wall-clock time, stoppable by Ctrl-C: for work with no time bound of its own (sympy's
integrate) whose interruption in process could leave shared state half built.

The parent trusts nothing it gets back beyond its being the pickled answer of its own
child: whoever calls ``computed`` checks the value as it would an untrusted one.  Where
there is no ``os.fork`` the caller computes in process (``computed`` says "no fork").
"""

from __future__ import annotations

import contextlib
import gc
import math
import os
import pickle
import select
import signal
import threading
import time

#: seconds between two looks at Ctrl-C and at the child while it works
POLL = 0.05


def computed(fn, args, cpu, wall):
    """``("value", fn(*args))`` from a forked child given ``cpu`` seconds of CPU time and
    ``wall`` seconds in all, else ``(how, why)``: how "time" (out of CPU or wall time),
    "failed" (the child's error, a signal, an exit status) or "no fork" (none started).
    SIGINT is only recorded meanwhile (``_sigint_recorded``), so that no
    KeyboardInterrupt lands between the fork and the bookkeeping of the child or in its
    cleanup; the wait calls the handler (every ``POLL`` seconds) and ends at the child's
    exit as well as at the end of the pipe (a process forked meanwhile elsewhere holds the
    pipe open until it exits)."""
    with _sigint_recorded() as sigint:
        try:
            r, w = os.pipe()
        except OSError:
            return "no fork", None
        pid = ended = late = None
        chunks = []
        try:
            child = _forked(w, cpu, fn, args)
            if isinstance(child, OSError):
                return "no fork", None
            pid = child
            os.close(w)
            w = None
            poll, end = select.poll(), time.monotonic() + wall
            poll.register(r, select.POLLIN)
            while True:
                sigint()            # the handler in place before, if Ctrl-C was pressed
                left = end - time.monotonic()
                if left <= 0:
                    late = f"out of wall time ({wall:g} s)"
                    break
                if poll.poll(1000 * min(left, POLL)):
                    chunk = os.read(r, 1 << 16)
                    if not chunk:
                        break
                    chunks.append(chunk)
                else:
                    ended = _ended(pid, kill=False)
                    if ended is not False:      # it has exited: what it sent is here
                        pid = None
                        chunks.append(_rest(r))
                        break
        finally:
            for fd in (r, w):
                if fd is not None:
                    os.close(fd)
            if pid:
                ended = _ended(pid)
        if late:
            return "time", late
        try:
            ok, out = pickle.loads(b"".join(chunks))
        except Exception:  # nothing or a part sent: a signal ended the child, or an exit
            return _why_ended(ended, cpu)
        return ("value", out) if ok else ("failed", f"it failed: {out}")


def _forked(w, cpu, fn, args):
    """A child process computing ``fn(*args)`` into the pipe ``w`` (``_child``): its pid,
    or the OSError that refused it.  Every signal is blocked across the fork, so none
    reaches the child before ``_child`` has set every handler back to the default action;
    whatever is raised in the child, it exits here (nothing of the caller's runs there)."""
    parent = os.getpid()
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, signal.valid_signals())
    try:
        return os.fork()
    except OSError as exc:
        return exc
    finally:
        if os.getpid() != parent:
            try:
                _child(w, cpu, fn, args, mask)
            finally:
                os._exit(1)
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)


def _child(w, cpu, fn, args, mask):
    """In the child: the garbage collector kept off the parent's objects (``gc.freeze``:
    their finalizers are the parent's to run); every Python signal handler, SIGPROF's
    and SIGXCPU's, back to the default action, before the signals are unblocked (but
    those ``mask`` blocked in the parent); where ``cpu`` is finite, the CPU limits
    (SIGPROF after ``cpu`` seconds, RLIMIT_CPU a second later); no core file;
    ``(True, fn(*args))``, or ``(False, the error)``, pickled into ``w``; exit."""
    gc.freeze()
    import resource

    for sig in signal.valid_signals():
        if sig in (signal.SIGPROF, signal.SIGXCPU) or callable(signal.getsignal(sig)):
            with contextlib.suppress(OSError, ValueError):
                signal.signal(sig, signal.SIG_DFL)
    signal.set_wakeup_fd(-1)
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
    if math.isfinite(cpu):
        limit = math.ceil(cpu) + 1
        hard = resource.getrlimit(resource.RLIMIT_CPU)[1]
        if hard != resource.RLIM_INFINITY:
            limit = min(limit, hard)
        resource.setrlimit(resource.RLIMIT_CPU, (limit, limit))
        signal.setitimer(signal.ITIMER_PROF, max(cpu, 1e-3))     # (0 would disarm it)
    signal.pthread_sigmask(signal.SIG_SETMASK, mask - {signal.SIGPROF, signal.SIGXCPU})
    try:
        out = (True, fn(*args))
        data = pickle.dumps(out, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception as exc:    # sent back, named in the warning
        data = pickle.dumps((False, f"{type(exc).__name__}: {exc}"[:300]))
    with open(w, "wb") as f:
        f.write(data)
    os._exit(0)


def _rest(fd) -> bytes:
    """What is left in the pipe ``fd``, read without waiting."""
    os.set_blocking(fd, False)
    out = []
    with contextlib.suppress(BlockingIOError):
        while chunk := os.read(fd, 1 << 16):
            out.append(chunk)
    return b"".join(out)


def _ended(pid, kill=True):
    """The child ``pid`` reaped: ``os.wait4``'s (pid, wait status, resource usage); if it
    has not ended, it is killed first (it has sent all it will or is out of time: SIGKILL
    ends it however it is stuck), or with ``kill`` false, False is returned; None where
    someone else reaped it (a SIGCHLD handler of the program's: then the pid is not
    signalled, it may be another process's by now)."""
    try:
        ended = os.wait4(pid, os.WNOHANG)
        if not ended[0]:
            if not kill:
                return False
            os.kill(pid, signal.SIGKILL)
            ended = os.wait4(pid, 0)
        return ended
    except ChildProcessError:
        return None


def _why_ended(ended, cpu):
    """``(how, why)`` for a child that sent no result, from ``_ended``: out of CPU time
    only where a signal ended it once its CPU time had reached ``cpu`` (not the OOM
    killer, a crash or another's signal)."""
    if not ended:
        return "failed", "it was reaped elsewhere (a SIGCHLD handler) before it sent a result"
    _, status, use = ended
    code = os.waitstatus_to_exitcode(status)
    if code >= 0:
        return "failed", f"it ended with exit status {code}"
    if use.ru_utime + use.ru_stime >= cpu:
        return "time", "out of CPU time"
    try:
        name = signal.Signals(-code).name
    except ValueError:
        name = str(-code)
    return "failed", f"it was killed by signal {name}"


@contextlib.contextmanager
def _sigint_recorded():
    """Inside, SIGINT only records itself; the function yielded calls the handler in
    place before with the signal recorded, if any (Python's raises KeyboardInterrupt,
    another may return: the work then goes on), as the exit does after putting it back.
    Only the main thread's handler is changed: signals are handled only there, and a
    handler that is not a Python function (ignored, default, set in C) is left alone."""
    got = []
    old = (signal.getsignal(signal.SIGINT)
           if threading.current_thread() is threading.main_thread() else None)

    def deliver():
        if got:
            args = got[-1]
            got.clear()
            old(*args)

    if not callable(old):
        yield deliver
        return
    signal.signal(signal.SIGINT, lambda signum, frame: got.append((signum, frame)))
    try:
        yield deliver
    finally:
        signal.signal(signal.SIGINT, old)
        deliver()
