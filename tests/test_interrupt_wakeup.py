"""A call knows whether the wakeup fd is still the watchdog's socket without setting it
(``interrupt.set_wakeup_fd`` in place of ``signal.set_wakeup_fd`` notes every change):
whoever sets a wakeup fd between runs, through ``signal`` or past it, a Ctrl-C during
the next call still stops it within a second, reaches the SIGINT handler once after it,
and leaves the other party's wakeup fd as it was."""

import _signal
import os
import signal
import socket
import threading
import time

import numpy as np
import pytest

from _interrupt_helpers import recording_sigint, sigint_in, stopped_by_sigint
from jetnh import models
from jetnh.numeric import STOPPED, Scene, interrupt


def _wakeup_fd():
    fd = interrupt._set_wakeup_fd(-1)    # (CPython's own: read without noting anything)
    interrupt._set_wakeup_fd(fd, warn_on_full_buffer=False)
    return fd


@pytest.fixture(autouse=True)
def listening():
    """Python's own SIGINT handler during each test: a process started in the
    background by a shell without job control inherits SIGINT ignored, and a call then
    (rightly) listens for none."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)


@pytest.fixture
def handler():
    """A SIGINT handler of the test's own, recording each signal; the previous handler
    and wakeup fd restored after the test."""
    with recording_sigint(lambda signum: signum) as seen:
        yield seen


@pytest.fixture
def theirs():
    """A wakeup socket of someone else's (an event loop's): (reader, its writer's fd)."""
    r, w = socket.socketpair()
    r.setblocking(False)
    w.setblocking(False)
    try:
        yield r, w.fileno()
    finally:
        r.close()
        w.close()


def test_set_wakeup_fd_is_cpythons_in_front():
    """``signal.set_wakeup_fd`` is the module's stand-in: it returns the previous fd and
    refuses a non-main thread as CPython's does, and forgets the watchdog's fd."""
    assert signal.set_wakeup_fd is interrupt.set_wakeup_fd is _signal.set_wakeup_fd
    assert signal.set_wakeup_fd.__wrapped__ is interrupt._set_wakeup_fd
    prior = signal.set_wakeup_fd(-1)    # (a fd an earlier test in this process left in
    interrupt.call(lambda: None, interrupt.flag())  # place: the call would forward to it)
    assert interrupt._KNOWN[0] is interrupt._WATCHDOG
    fd = signal.set_wakeup_fd(-1)
    assert interrupt._KNOWN[0] is None
    assert fd == interrupt._WATCHDOG.own
    assert signal.set_wakeup_fd(fd) == -1
    errors = []

    def elsewhere():
        try:
            signal.set_wakeup_fd(-1)
        except ValueError as exc:
            errors.append(exc)

    thread = threading.Thread(target=elsewhere)
    thread.start()
    thread.join()
    assert len(errors) == 1 and _wakeup_fd() == fd
    if prior not in (-1, fd):
        signal.set_wakeup_fd(prior)


def test_a_wakeup_fd_set_between_runs_is_theirs_again_after_a_stopped_call(handler, theirs):
    """After calls that found the fd the watchdog's (and no longer set it), someone sets
    theirs through ``signal``: the next call hears Ctrl-C, their socket gets the byte,
    their fd is in place after it; once they give it up the calls take it back."""
    reader, fd = theirs
    for _ in range(3):
        interrupt.call(lambda: None, interrupt.flag())
    assert interrupt._KNOWN[0] is interrupt._WATCHDOG
    previous = signal.set_wakeup_fd(fd, warn_on_full_buffer=False)
    assert previous == interrupt._WATCHDOG.own
    got, took = stopped_by_sigint()
    assert got == interrupt.INTERRUPT and took < 3.0
    assert handler == [signal.SIGINT]
    assert _wakeup_fd() == fd
    time.sleep(0.05)
    assert signal.SIGINT in reader.recv(64)
    signal.set_wakeup_fd(-1)
    got, took = stopped_by_sigint()
    assert got == interrupt.INTERRUPT and took < 3.0 and handler == [signal.SIGINT] * 2
    assert _wakeup_fd() == interrupt._WATCHDOG.own
    assert interrupt._KNOWN[0] is interrupt._WATCHDOG


def test_a_wakeup_fd_set_past_the_stand_in_is_found_where_it_was_replaced(
        monkeypatch, handler, theirs):
    """Where ``signal.set_wakeup_fd`` is no longer the stand-in (replaced since), every
    call confirms the fd: a wakeup fd set past both (CPython's own function) is found,
    Ctrl-C still stops the call and the fd is theirs after it."""
    reader, fd = theirs
    interrupt.call(lambda: None, interrupt.flag())
    assert interrupt._KNOWN[0] is interrupt._WATCHDOG
    monkeypatch.setattr(signal, "set_wakeup_fd", interrupt._set_wakeup_fd)
    interrupt._set_wakeup_fd(fd, warn_on_full_buffer=False)   # unnoticed
    got, took = stopped_by_sigint()
    assert got == interrupt.INTERRUPT and took < 3.0 and handler == [signal.SIGINT]
    assert _wakeup_fd() == fd
    monkeypatch.undo()
    interrupt._set_wakeup_fd(-1)
    interrupt._KNOWN[0] = None


def test_ctrl_c_stops_a_long_run_and_restores_the_users_handler_and_fd(handler, theirs):
    """A long compiled run with the user's own SIGINT handler and wakeup fd in place:
    stopped within a second of Ctrl-C (status STOPPED, where it got to), the handler run
    once after it, the fd theirs again, and the next short run unchanged bit for bit."""
    reader, fd = theirs
    disk = Scene(models.get("rolling_disk"), "chetaev", initial=models.initial("rolling_disk"),
                 t_span=(0.0, 1e9), cache=False).compile()
    short = disk.replace(t_span=(0.0, 1.0))
    first = short.run(save="final")
    signal.set_wakeup_fd(fd, warn_on_full_buffer=False)
    timer = sigint_in(0.5)
    tic = time.monotonic()
    traj = disk.run(save="final", max_step=1e-3, max_steps=10**12)
    timer.join()
    assert time.monotonic() - tic < 3.0
    assert traj.status == STOPPED and 0.0 < traj.t[-1] < 1e9
    assert handler == [signal.SIGINT] and _wakeup_fd() == fd
    again = short.run(save="final")
    assert np.array_equal(again.y, first.y) and np.array_equal(again.t, first.t)
    assert handler == [signal.SIGINT] and _wakeup_fd() == fd


EARLY = """
import os, signal, socket, sys, threading, time
from signal import set_wakeup_fd as early      # bound before jetnh (as uvloop does)
from jetnh.numeric import interrupt

def spin(halt, cap):
    end = time.monotonic() + cap
    while time.monotonic() < end:
        if halt[0]:
            return int(halt[0])
    return 0

seen = []
signal.signal(signal.SIGINT, lambda signum, frame: seen.append(signum))
interrupt.call(spin, interrupt.flag(), None, (interrupt.flag(), 0.0))   # confirmed
assert interrupt._KNOWN[0] is interrupt._WATCHDOG
r, w = socket.socketpair()
r.setblocking(False)
w.setblocking(False)
time.sleep(interrupt.CONFIRM + 0.05)
early(w.fileno(), warn_on_full_buffer=False)   # unseen by the stand-in
assert interrupt._KNOWN[0] is interrupt._WATCHDOG
halt = interrupt.flag()
threading.Timer(0.2, os.kill, (os.getpid(), signal.SIGINT)).start()
tic = time.monotonic()
got = interrupt.call(spin, halt, None, (halt, 10.0))
print(got, time.monotonic() - tic, seen, early(-1) == w.fileno(), flush=True)
"""

FORKED = """
import os, signal, threading, time
from jetnh.numeric import interrupt

signal.signal(signal.SIGINT, signal.default_int_handler)   # (not SIG_IGN, inherited)

halt = interrupt.flag()
interrupt.call(lambda: None, halt)
interrupt.call(lambda: None, interrupt.flag())     # the common route
result = {}

def forker():
    time.sleep(0.2)
    pid = os.fork()
    if pid == 0:
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(2.0)
            os._exit(3)                                 # SIGINT held back for ever
        except KeyboardInterrupt:
            ok = (not interrupt._HALTS and interrupt._MAIN == threading.get_ident()
                  and interrupt.call(lambda: 7, interrupt.flag()) == 7)
            os._exit(0 if ok else 4)
    result["child"] = os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])

thread = threading.Thread(target=forker)
thread.start()

def wait():
    end = time.monotonic() + 5.0
    while time.monotonic() < end and "child" not in result and halt[0] == 0:
        time.sleep(0.01)

interrupt.call(wait, halt)
thread.join()
print(result["child"], flush=True)
"""


def _child(code):
    """What a child Python running ``code`` printed (its last line)."""
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", code], capture_output=True, timeout=300,
                         env=dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path)))
    assert out.returncode == 0, out.stderr.decode()[-2000:]
    return out.stdout.decode().split("\n")[-2]


def test_a_wakeup_fd_set_by_a_reference_bound_before_jetnh_is_found_within_confirm():
    """A wakeup fd set between runs through CPython's function bound before ``import
    jetnh`` (which the stand-in cannot see), more than ``CONFIRM`` after the last
    confirmation: Ctrl-C still stops the next long call within a second, the handler
    runs once after it, and the fd is theirs again."""
    got, took, seen, theirs = _child(EARLY).split(" ", 3)
    assert int(got) == interrupt.INTERRUPT and float(took) < 1.0
    assert seen == f"[{int(signal.SIGINT)}]" and theirs == "True"


def test_a_loop_of_short_calls_confirms_the_fd_at_most_once_per_window(monkeypatch):
    """Short calls back to back (a clock stepping 10 ms per call): CPython's
    ``set_wakeup_fd`` is asked once per ``CONFIRM`` window, not per call."""
    real, now, asked = interrupt._set_wakeup_fd, [1000.0], []

    def counted(fd, /, *, warn_on_full_buffer=True):
        asked.append(fd)
        return real(fd, warn_on_full_buffer=warn_on_full_buffer)

    def clock():
        now[0] += 0.01
        return now[0]

    interrupt.call(lambda: None, interrupt.flag())
    monkeypatch.setattr(interrupt, "_set_wakeup_fd", counted)
    monkeypatch.setattr(interrupt, "_monotonic", clock)
    interrupt._KNOWN[0] = None
    for _ in range(100):
        interrupt.call(lambda: None, interrupt.flag())
    # ~1 s of fake time (one clock read per call, plus one per confirmation)
    assert 1 + int(0.9 / interrupt.CONFIRM) <= len(asked) <= 2 + int(1.1 / interrupt.CONFIRM)
    assert set(asked) == {interrupt._WATCHDOG.own}


def test_a_child_forked_by_another_thread_during_a_call_gets_ctrl_c():
    """A thread forks while the main thread is inside a call: the child (whose main
    thread is the forking one, the call absent) raises KeyboardInterrupt on SIGINT and
    runs calls of its own."""
    assert _child(FORKED) == "0"
