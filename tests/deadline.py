"""A guard for tests of code that must not hang."""

import signal
import time
from contextlib import contextmanager


@contextmanager
def deadline(seconds, what, hard=None):
    """Fail when the block takes ``seconds`` or longer; interrupt it (TimeoutError) at
    ``hard`` seconds (default ``seconds``) instead of hanging."""
    hard = seconds if hard is None else hard

    def boom(*_):
        raise TimeoutError(f"{what} did not return within {hard} s")
    old = signal.signal(signal.SIGALRM, boom)
    signal.setitimer(signal.ITIMER_REAL, hard)
    t0 = time.monotonic()
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    elapsed = time.monotonic() - t0
    assert elapsed < seconds, f"{what} took {elapsed:.1f} s"
