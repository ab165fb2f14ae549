"""``A:B:N`` ranges on the command line: one parser (``cli.parser.evenly_spaced``) for
``linearize --param`` (a scan: N >= 2) and ``sweep --grid`` / ``--times`` (N >= 1), with
the same messages."""

import numpy as np
import pytest
from hypothesis import given, strategies as st

from jetnh.cli.parser import MAX_RANGE, evenly_spaced
from jetnh.cli.usage import UsageError


def inproc(capsys, *args):
    from jetnh.cli import main

    try:
        code = main(list(args))
    except SystemExit as exc:
        code = exc.code
    return code, capsys.readouterr().err


LINEARIZE = ("linearize", "chaplygin_sleigh", "-q", "--at", "theta=0,x_t=1,theta_t=0",
             "--param")
SWEEP = ("sweep", "chaplygin_sleigh", "-q", "--t-end", "1", "--grid")


@pytest.mark.parametrize("rng, words", [
    ("1:1:5", "'1:1:5' is a range of zero width (5 equal values); give A != B"),
    ("0:inf:5", "A and B must be finite numbers, got '0:inf:5'"),
    ("nan:1:5", "A and B must be finite numbers"),
    ("0:1:2.5", "A:B:N (N evenly spaced values from A to B; A and B numbers, N an integer)"),
    ("0:one:5", "A:B:N (N evenly spaced values from A to B"),
    ("0:1:5:7", "A:B:N (N evenly spaced values from A to B"),
    ("0:1:0", "N must be from"),
    (f"0:1:{MAX_RANGE + 1}", "N must be from"),
])
def test_both_commands_refuse_a_bad_range_in_the_same_words(capsys, rng, words):
    """The same range gives the same message after the option's name, whichever command
    reads it (sweep names the comma-separated list it also takes)."""
    code, lin = inproc(capsys, *LINEARIZE, f"x_t={rng}")
    assert code == 2 and "Traceback" not in lin, lin
    code, swp = inproc(capsys, *SWEEP, f"x_t={rng}")
    assert code == 2 and "Traceback" not in swp, swp
    lin = lin.split("--param x_t: ", 1)[1].strip()
    swp = swp.split("--grid x_t: ", 1)[1].strip()
    assert words in lin and words in swp, (lin, swp)
    if words == "N must be from":                          # each command's own rule
        assert lin.startswith("N must be from 2 to") and swp.startswith("N must be from 1 to")
    elif words.startswith("A:B:N"):
        assert swp.startswith(lin.split(" is not ")[0] + " is neither A:B:N")
        assert swp.endswith("nor a comma-separated list of finite numbers")
    else:
        assert lin.split(";")[0].split(", or")[0] == swp.split(";")[0].split(", or")[0]


def test_each_command_has_its_rule_for_n():
    """A scan needs two values, a grid axis one: the rule is the caller's, the message
    names it."""
    assert evenly_spaced("2:2:1", "--grid x", least=1) == (2.0, 2.0, 1)
    with pytest.raises(UsageError, match="--param x: N must be from 2 to 100000, got 1"):
        evenly_spaced("2:3:1", "--param x", least=2)
    with pytest.raises(UsageError, match="or --set x=2 instead"):
        evenly_spaced("2:2:4", "--param x", least=2, one="--set x={a} instead")


@given(a=st.floats(-1e6, 1e6), b=st.floats(-1e6, 1e6), n=st.integers(1, 50),
       least=st.integers(1, 2))
def test_a_range_reads_back_as_written(a, b, n, least):
    """Every range within the rule reads as its own (A, B, N); every other is refused."""
    text = f"{a!r}:{b!r}:{n}"
    if n < least or (a == b and n > 1):
        with pytest.raises(UsageError):
            evenly_spaced(text, "--x", least)
    else:
        assert evenly_spaced(text, "--x", least) == (a, b, n)


def test_sweep_values_keep_their_forms():
    from jetnh.cli.commands.sweep import _values

    assert _values("0:1:3", "--times", "--times {a}") == [0.0, 0.5, 1.0]
    assert _values("0.5,2", "--times", "--times {a}") == [0.5, 2.0]
    with pytest.raises(UsageError, match="or --times 3$"):
        _values("3:3:2", "--times", "--times {a}")
    assert np.all(np.diff(_values("-1:1:5", "--grid x", "")) > 0)
