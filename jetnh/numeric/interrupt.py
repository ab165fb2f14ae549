"""Compiled loops that Ctrl-C and a wall-clock budget can stop.

A compiled loop holds no Python frame, so a KeyboardInterrupt cannot reach it until it
returns, and it reads no clock.  Every compiled solve therefore takes a ``halt`` flag (an
int64 array of one element) and reads it before each step; ``call(fn, halt, timeout)``
runs ``fn()`` (the compiled call, which receives ``halt``) in the calling thread while a
watchdog thread sets the flag:

- on SIGINT (Ctrl-C): ``halt[0] = INTERRUPT``; the loop stops within one step, and the
  SIGINT handler that was in place (Python's KeyboardInterrupt, or the user's own) runs
  once the compiled call has returned.  The watchdog hears the signal through
  ``signal.set_wakeup_fd``, which CPython's C-level handler writes to even while the main
  thread runs machine code.  A KeyboardInterrupt raised inside numba's callbacks into
  Python would surface as a SystemError (or worse), so the Python-level SIGINT handler is
  ``_on_sigint``, installed once (again if it was replaced): during a compiled call it
  only records the signal, otherwise it calls the handler it stands in for.  The
  watchdog's socket stays the wakeup fd between runs when no one else had set one; a
  previous wakeup fd (an asyncio loop's, say) receives every byte during the call and is
  restored after it;
- past ``timeout`` seconds: ``halt[0] = TIMEOUT``; the loop returns what it has, with
  status STOPPED.

The watchdog is one daemon thread, started on demand (without waiting for it to run:
``threading.Thread.start`` waits for a hand-over that costs a short run's time several
times) and ended after ``IDLE`` seconds with nothing to watch (it drops the bytes of
signals that came while it was not running), so that runs interleaved with other work
find it running.  A call costs a registration, not a thread hand-over: in the main
thread without a timeout (most runs) its ``halt`` on a list the watchdog reads on
SIGINT, else a dict entry (without a lock: the lock only starts and ends the thread).
Whether the wakeup fd is still the watchdog's socket is known without asking CPython
(which can tell only by setting it: ``set_wakeup_fd`` checks the fd with two system
calls, the largest part of a short run's Python side): ``signal.set_wakeup_fd`` (and
``_signal``'s) is replaced by ``set_wakeup_fd``, the same function that also notes that
the wakeup fd may have changed, so a call confirms the fd (one ``set_wakeup_fd``) only
after someone else set one, after the watchdog changed, or where the function in place
is not this one (replaced again since), and at the latest ``CONFIRM`` seconds after the
last confirmation: a setter this replacement cannot see (a reference to CPython's
function bound before ``import jetnh``, as uvloop binds one at its import; the C API;
an extension calling it directly) leaves Ctrl-C unheard for at most that window, while
a tight loop of short runs still pays the two system calls at most once per window.
So ``import jetnh`` replaces ``signal.set_wakeup_fd`` and ``_signal.set_wakeup_fd``
process-wide with a wrapper that calls CPython's own, unchanged, and only notes the
change.  Signals reach only the main thread, so
elsewhere only the timeout is watched.  ``shared(halt)`` is one such watch for many
compiled calls in turn (a shooting search's runs): registered and the wakeup fd set
once, each call only resetting ``halt``.
"""

from __future__ import annotations

import atexit
import contextlib
import functools
import itertools
import os
import select
import signal
import _signal
import _thread
import socket
import threading
import time

import numpy as np

INTERRUPT, TIMEOUT = 1, 2
#: seconds the watchdog waits with nothing to watch before it ends
IDLE = 60.0
#: seconds after which a call confirms the wakeup fd again even though no one was seen
#: setting it (setters that bypass ``set_wakeup_fd``, module docstring): the longest
#: Ctrl-C can go unheard after such a setter, one confirmation per window in a loop
CONFIRM = 0.25


def flag() -> np.ndarray:
    """A fresh ``halt`` flag."""
    return np.zeros(1, dtype=np.int64)


class _Watchdog:
    """Sets the halt flags of the calls in progress on SIGINT and at their deadlines."""

    def __init__(self):
        self.lock = threading.Lock()
        self.calls: dict[int, list] = {}          # id -> [halt, deadline, forward fd]
        self.ids = itertools.count()
        self.signals, self.signal_w = socket.socketpair()
        self.control, self.control_w = socket.socketpair()
        for s in (self.signals, self.signal_w, self.control, self.control_w):
            s.setblocking(False)
        self.thread = None                     # its ident while it runs
        self.own = self.signal_w.fileno()      # the wakeup fd the watchdog hears

    def close(self):
        for s in (self.signals, self.signal_w, self.control, self.control_w):
            s.close()

    def register(self, halt, deadline, forward) -> int:
        """Watch ``halt`` (until its key leaves ``calls``): a dict entry, made without
        the lock (one store, atomic under the GIL); the lock only starts the thread."""
        key = next(self.ids)
        self.calls[key] = [halt, deadline, forward]
        if self.thread is None:
            try:
                self.start()
            except BaseException:             # no thread (limits): no watch left behind
                del self.calls[key]
                raise
        if deadline is not None:
            self._poke()
        return key

    def start(self):
        """Start the thread unless it runs (a watch registered before this call is seen
        by it: the thread ends only after finding nothing to watch, under the lock)."""
        with self.lock:
            if self.thread is None:
                _drain(self.signals)          # signals from before this watch
                self.thread = _thread.start_new_thread(self._loop, ())

    def _poke(self):
        try:
            self.control_w.send(b"\0")
        except OSError:                       # full: the watchdog wakes up anyway
            pass

    def _loop(self):
        idle_since = time.monotonic()
        while True:
            # a snapshot (calls come and go without the lock)
            deadlines = [c[1] for c in list(self.calls.values()) if c[1] is not None]
            if self.calls or _HALTS:
                idle_since = time.monotonic()
            elif time.monotonic() - idle_since > IDLE:
                with self.lock:
                    self.thread = None
                    if not (self.calls or _HALTS):    # (a call from now on starts one)
                        return
                    self.thread = _thread.get_ident()     # one registered meanwhile
                continue
            wait = IDLE if not deadlines else max(0.0, min(deadlines) - time.monotonic())
            try:
                ready, _, _ = select.select([self.signals, self.control], [], [], wait)
                if self.control in ready:
                    _drain(self.control)
                got = _drain(self.signals) if self.signals in ready else b""
            except (OSError, ValueError):     # the sockets were closed at exit
                with self.lock:
                    self.thread = None
                return
            now = time.monotonic()
            calls = list(self.calls.values())
            if signal.SIGINT in got:
                for halt in list(_HALTS):
                    halt[0] = INTERRUPT
            for c in calls:
                if signal.SIGINT in got:
                    c[0][0] = INTERRUPT
                if c[1] is not None and now >= c[1]:
                    c[0][0] = TIMEOUT
                    c[1] = None
            for fd in {c[2] for c in calls if c[2] >= 0}:   # the wakeup fd's owner before
                try:
                    os.write(fd, got)
                except OSError:
                    pass


def _drain(sock) -> bytes:
    data = b""
    while True:
        try:
            chunk = sock.recv(4096)
        except (BlockingIOError, InterruptedError):
            return data
        if not chunk:
            return data
        data += chunk


_WATCHDOG: _Watchdog | None = None


def _watchdog() -> _Watchdog:
    global _WATCHDOG
    if _WATCHDOG is None:
        _WATCHDOG = _Watchdog()
    return _WATCHDOG


def _forget():
    """Close the watchdog's sockets (at exit; in a forked child, whose copy has no
    thread), giving up the wakeup fd first if it is theirs."""
    global _WATCHDOG, _MAIN
    _KNOWN[0] = None
    if _WATCHDOG is not None:
        fd = _WATCHDOG.signal_w.fileno()
        try:
            old = signal.set_wakeup_fd(-1)
            if old != fd:
                signal.set_wakeup_fd(old)
        except ValueError:                    # not the main thread
            pass
        _WATCHDOG.close()
        _WATCHDOG = None
    _DEPTH[0] = 0
    _CAUGHT.clear()
    if _get_ident() != _MAIN:
        # forked by another thread (the main thread's calls do not exist here) or at
        # exit off the main thread: nothing will pop _HALTS; this thread is now the main
        _HALTS.clear()
        _MAIN = threading.main_thread().ident
    # (else _HALTS kept: a child forked during a call in the main thread pops its entry
    # as the call unwinds, SIGINT held back until then as in the parent)


os.register_at_fork(after_in_child=_forget)
atexit.register(_forget)
_MAIN = threading.main_thread().ident
_SIGINT = int(signal.SIGINT)
_getsignal = _signal.getsignal       # (signal.getsignal: the same, as an enum, slower)
_get_ident = threading.get_ident
#: CPython's own (``set_wakeup_fd`` below stands in front of it)
_set_wakeup_fd = getattr(_signal.set_wakeup_fd, "__wrapped__", _signal.set_wakeup_fd)
#: the watchdog whose socket is known to be the wakeup fd: set where a call made it so
#: (or found it so), None once anyone else may have set one (``set_wakeup_fd``)
_KNOWN: list = [None]
#: when ``_KNOWN`` was last confirmed (``time.monotonic``)
_KNOWN_AT: list = [0.0]
_monotonic = time.monotonic


@functools.wraps(_set_wakeup_fd)
def set_wakeup_fd(fd, /, *, warn_on_full_buffer=True):
    # ``signal.set_wakeup_fd`` (CPython's, called as it is), noting that the wakeup fd may
    # no longer be the watchdog's socket (module docstring)
    _KNOWN[0] = None
    return _set_wakeup_fd(fd, warn_on_full_buffer=warn_on_full_buffer)


signal.set_wakeup_fd = _signal.set_wakeup_fd = set_wakeup_fd
#: the SIGINT handler ``_on_sigint`` stands in for, the compiled calls in progress in
#: the main thread other than those on ``_HALTS``, and the frames of the signals they
#: held back
_DELEGATE: list = [None]
_DEPTH = [0]
_CAUGHT: list = []
#: the halt flags of the calls in progress in the main thread without a timeout (``call``'s
#: common case; nested calls in the order they began): set by the watchdog on SIGINT
_HALTS: list = []


def _on_sigint(signum, frame):
    """The Python-level SIGINT handler: recorded during a compiled call (its handler
    runs once the call has returned), else the handler it stands in for."""
    if _HALTS or _DEPTH[0]:
        _CAUGHT.append(frame)
    else:
        _DELEGATE[0](signum, frame)


def _listening() -> bool:
    """Whether this thread hears SIGINT through a Python-level handler (the main thread,
    a callable handler), with ``_on_sigint`` installed in front of it."""
    if _get_ident() != _MAIN:
        return False
    handler = _getsignal(_SIGINT)
    if handler is _on_sigint:
        return True
    if not callable(handler):             # SIG_IGN, SIG_DFL, or not set from Python
        return False
    _DELEGATE[0] = handler
    _signal.signal(_SIGINT, _on_sigint)
    return True


def call(fn, halt: np.ndarray, timeout: float | None = None, args: tuple = ()):
    """``fn(*args)``, stoppable by Ctrl-C and by ``timeout`` through ``halt`` (see the
    module docstring)."""
    wd = _WATCHDOG
    if (timeout is None and wd is not None and _get_ident() == _MAIN
            and _getsignal(_SIGINT) is _on_sigint
            and ((_KNOWN[0] is wd and signal.set_wakeup_fd is set_wakeup_fd
                  and _signal.set_wakeup_fd is set_wakeup_fd
                  and _monotonic() - _KNOWN_AT[0] < CONFIRM) or _claim(wd))):
        # the common case (the main thread, _on_sigint in place, no timeout, the wakeup
        # fd the watchdog's): ``halt`` on the list the watchdog reads on SIGINT
        _HALTS.append(halt)
        try:
            if wd.thread is None:             # (ended after IDLE: sees _HALTS or starts)
                wd.start()
            return fn(*args)
        finally:
            if _HALTS:                        # (cleared in a child forked by a thread)
                _HALTS.pop()
            if _CAUGHT and not (_HALTS or _DEPTH[0]):
                _deliver()
    return _call(fn, halt, timeout, args)


def _claim(wd) -> bool:
    """Whether the wakeup fd is (now) the socket of ``wd``: made so where no one else's
    was set (``_take``); someone else's left as it was."""
    old = _take(wd)
    if old < 0:
        return True
    _set_wakeup_fd(old)
    return False


def _take(wd) -> int:
    """Make the wakeup fd the socket of ``wd``: the fd it replaced where that was someone
    else's (theirs again after the call), else -1, and the fd then known to be the
    watchdog's (``_KNOWN``) while ``set_wakeup_fd`` is the function in place."""
    own = wd.own
    old = _set_wakeup_fd(own, warn_on_full_buffer=False)
    if old == own or old < 0:             # (no one else's: it stays the watchdog's)
        if signal.set_wakeup_fd is set_wakeup_fd is _signal.set_wakeup_fd:
            _KNOWN[0] = wd
            _KNOWN_AT[0] = _monotonic()
        return -1
    _KNOWN[0] = None
    return old


def _deliver():
    """The SIGINT held back during the compiled calls, to the handler ``_on_sigint``
    stands in for."""
    frame = _CAUGHT[0]
    _CAUGHT.clear()
    _DELEGATE[0](_SIGINT, frame)


def _call(fn, halt, timeout, args):
    """``call`` in general: any thread, a timeout, a wakeup fd of someone else's (which
    receives every byte during the call and is restored after it)."""
    if not ((_get_ident() == _MAIN and _getsignal(_SIGINT) is _on_sigint)
            or _listening()):
        if timeout is None:
            return fn(*args)
        listen = False
    else:
        listen = True
    deadline = None if timeout is None else time.monotonic() + timeout
    wd = _WATCHDOG or _watchdog()
    old = -1
    if listen:
        old = _take(wd)
        _DEPTH[0] += 1
    key = None
    try:
        key = wd.register(halt, deadline, old)
        return fn(*args)
    finally:
        if key is not None:
            del wd.calls[key]
        if listen:
            _DEPTH[0] -= 1
            if old >= 0:                      # someone else's: theirs again
                _set_wakeup_fd(old)
            if _CAUGHT and not (_HALTS or _DEPTH[0]):
                _deliver()


@contextlib.contextmanager
def shared(halt: np.ndarray):
    """One watch of ``halt`` for many compiled calls in turn in this thread (the runs of
    a shooting search), without a timeout: ``halt`` is registered with the watchdog and
    the wakeup fd set once; yields ``run(fn, args)``, which resets ``halt`` and calls
    ``fn(*args)`` with Ctrl-C handled as ``call`` handles it (held back during the call,
    raised after it), at the cost of that bookkeeping alone.  Between the calls Ctrl-C
    raises at once, as without a watch."""
    if not ((_get_ident() == _MAIN and _getsignal(_SIGINT) is _on_sigint)
            or _listening()):
        def bare(fn, args):
            halt[0] = 0
            return fn(*args)
        yield bare
        return
    wd = _WATCHDOG or _watchdog()
    old = _take(wd)
    key = None
    try:
        key = wd.register(halt, None, old)

        def run(fn, args):
            halt[0] = 0
            if _getsignal(_SIGINT) is not _on_sigint:   # replaced since: a watch of its own
                return call(fn, halt, None, args)
            _DEPTH[0] += 1
            try:
                return fn(*args)
            finally:
                _DEPTH[0] -= 1
                if _CAUGHT and not (_HALTS or _DEPTH[0]):
                    _deliver()
        yield run
    finally:
        if key is not None:
            del wd.calls[key]
        if old >= 0:                          # someone else's: theirs again
            _set_wakeup_fd(old)
