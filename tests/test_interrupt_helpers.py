"""The Ctrl-C tests' shared scaffolding (``_interrupt_helpers``) does what they rely on:
the stand-in loop returns its halt value or 0 after its cap, a recording handler hears
SIGINT and leaves the previous handler and wakeup fd in place, and a call of the
stand-in is stopped by a SIGINT sent into it; the two Ctrl-C test modules use it and
keep no copy of their own."""

import signal

import numpy as np
import pytest

import _interrupt_helpers as helpers
from jetnh.numeric import interrupt


@pytest.fixture(autouse=True)
def listening():
    """Python's own SIGINT handler (a process started in the background by a shell
    without job control inherits SIGINT ignored)."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)


def test_spin_returns_the_halt_value_or_zero_after_its_cap():
    halt = np.zeros(1, dtype=np.int64)
    assert helpers.spin(halt, 0.01) == 0
    halt[0] = 7
    assert helpers.spin(halt, 10.0) == 7


def test_recording_sigint_hears_and_restores():
    before = signal.getsignal(signal.SIGINT)
    fd = signal.set_wakeup_fd(-1)
    signal.set_wakeup_fd(fd)
    with helpers.recording_sigint(lambda signum: ("seen", signum)) as seen:
        got, took = helpers.stopped_by_sigint(0.1)
        assert got == interrupt.INTERRUPT and took < 3.0
    assert seen == [("seen", signal.SIGINT)]
    assert signal.getsignal(signal.SIGINT) is before
    now = signal.set_wakeup_fd(-1)
    signal.set_wakeup_fd(now)
    assert now == fd


@pytest.mark.parametrize("module", ["test_interrupt_wakeup", "test_run_fixed_cost"])
def test_the_ctrl_c_tests_share_it(module):
    import importlib

    mod = importlib.import_module(module)
    assert not hasattr(mod, "_spin") and not hasattr(mod, "_sigint_in")
    assert mod.stopped_by_sigint is helpers.stopped_by_sigint
