"""The command's own messages: warnings as ``jetnh: warning: ...`` (none with -q), and
``connect --compare`` keeping the first motion when the compared principle fails."""

import json

import pytest


def inproc(capsys, *args):
    """The command in this process; returns (exit code, stdout, stderr)."""
    from jetnh.cli import main

    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


PENDULUM = """coordinates = ["x", "y"]
dependent = ["y"]
lagrangian = "(x_t**2 + y_t**2)/2 - G*y"
constraints = ["x**2 + y**2 - 1"]

[parameters]
G = 9.81

[initial]
x = 0.5646424733950354
y = -0.8253356149096783
"""


@pytest.fixture(scope="module")
def pendulum(tmp_path_factory):
    path = tmp_path_factory.mktemp("models") / "pendulum.toml"
    path.write_text(PENDULUM)
    return str(path)


def test_a_warning_is_the_command_s_own_message(pendulum, capsys):
    """scipy-BDF does not project onto g = 0: JetnhWarning on the drift of |g|.  Before:
    '/.../scene.py:630: JetnhWarning: ...' and the source line, also under -q."""
    code, out, err = inproc(capsys, "simulate", pendulum, "--method", "scipy-BDF",
                            "--t-end", "3")
    assert code == 0 and "(success)" in out
    lines = [ln for ln in err.splitlines() if "warning" in ln.lower()]
    assert len(lines) == 1 and lines[0].startswith(
        "jetnh: warning: scipy-BDF: the run left the holonomic constraints g = 0 by up to")
    assert "JetnhWarning" not in err and ".py:" not in err
    code, out, err = inproc(capsys, "-q", "simulate", pendulum, "--method", "scipy-BDF",
                            "--t-end", "3")
    assert code == 0 and "(success)" in out and err == ""


def test_python_warnings_outside_the_command_are_untouched(pendulum, capsys):
    """The command's filter ends with it: the caller's warnings work as before."""
    import warnings

    from jetnh.errors import JetnhWarning

    inproc(capsys, "-q", "models")
    with pytest.warns(JetnhWarning, match="after the command"):
        warnings.warn("after the command", JetnhWarning)


@pytest.mark.parametrize("form", ["text", "json"])
def test_connect_compare_keeps_the_first_motion(capsys, form):
    """chetaev on the Heisenberg system reaches 2 of 3 end coordinates: its error goes
    to stderr (exit code 1), the vakonomic motion is printed.  Before: rc 1, nothing on
    stdout."""
    code, out, err = inproc(capsys, "-q", "connect", "heisenberg", "--to",
                            "x=1,y=0.5,z=0.2", "--t-end", "1", "--compare", "chetaev",
                            "--format", form)
    assert code == 1
    assert err.startswith("jetnh: error: --compare chetaev: the chetaev motions from the "
                          "start do not reach end")
    alone_code, alone, _ = inproc(capsys, "-q", "connect", "heisenberg", "--to",
                                  "x=1,y=0.5,z=0.2", "--t-end", "1", "--format", form)
    assert alone_code == 0
    if form == "json":
        data, ref = json.loads(out), json.loads(alone)
        assert data["compared"]["principle"] == "chetaev"
        assert "do not reach end" in data["compared"]["error"]
        assert data["principle"] == "vakonomic" and data["cost"] == ref["cost"]
        assert data["residual"] < 1e-9
    else:
        assert out.startswith(alone)            # the vakonomic answer, as alone
        assert out[len(alone):] == "-- chetaev\nnot connected (the error is on stderr)\n"
        assert "cost:      0.750298284" in out


def test_json_is_strict_where_a_value_is_not_finite(tmp_path, capsys):
    """An energy that overflows (inf - inf at x_t = 1000) is NaN in the diagnostics;
    the JSON record carries it as null, so strict parsers (RFC 8259 has no NaN) read it,
    and the finite values are unchanged."""
    path = tmp_path / "expv.toml"
    path.write_text('coordinates = ["x"]\nlagrangian = "x_t**2/2 + exp(x_t)"\n'
                    'constraints = []\n[initial]\nx_t = 1000\n')
    code, out, _ = inproc(capsys, "simulate", str(path), "--t-end", "1", "--format", "json")
    assert code == 0

    def refuse(name):
        raise ValueError(f"{name} is not JSON")
    record = json.loads(out, parse_constant=refuse)
    assert record["diagnostics"]["energy_initial"] is None
    assert record["diagnostics"]["energy_drift"] is None
    assert record["final"]["x"] == pytest.approx(1000.0, rel=1e-12)
    assert record["final"]["x_t"] == 1000.0
