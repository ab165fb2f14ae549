"""What the Ctrl-C tests share: a Python stand-in for a compiled loop, a SIGINT sent
from a timer thread (during a call of the stand-in), and a SIGINT handler of the test's own (the previous handler and
wakeup fd restored after it)."""

import contextlib
import os
import signal
import threading
import time

from jetnh.numeric import interrupt


def spin(halt, cap):
    """Python stand-in for a compiled loop: returns when ``halt`` is set (its value) or
    after ``cap`` seconds (0)."""
    end = time.monotonic() + cap
    while time.monotonic() < end:
        if halt[0]:
            return int(halt[0])
    return 0


def sigint_in(seconds):
    """SIGINT to this process after ``seconds`` (from a timer thread, started)."""
    timer = threading.Timer(seconds, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    return timer


def stopped_by_sigint(seconds=0.2):
    """A call (the watchdog's common route) that SIGINT, sent ``seconds`` into it, must
    stop: what it returned and how long it took."""
    halt = interrupt.flag()
    timer = sigint_in(seconds)
    tic = time.monotonic()
    got = interrupt.call(spin, halt, None, (halt, 10.0))
    timer.join()
    return got, time.monotonic() - tic


@contextlib.contextmanager
def recording_sigint(record):
    """A SIGINT handler that appends ``record(signum)`` to the list it yields; the
    previous handler and wakeup fd are in place again after it."""
    seen = []
    before = signal.signal(signal.SIGINT, lambda signum, frame: seen.append(record(signum)))
    fd = signal.set_wakeup_fd(-1)
    signal.set_wakeup_fd(fd)
    try:
        yield seen
    finally:
        signal.signal(signal.SIGINT, before)
        signal.set_wakeup_fd(fd)
