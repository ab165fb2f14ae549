"""``jetnh linearize``: the operating point from --at, the verdict, a scan with its
crossing and plot, steady motions, JSON, usage errors."""

import json

import numpy as np
import pytest

from model_texts import PENDULUM_XY


def inproc(capsys, *args):
    from jetnh.cli import main

    try:
        code = main(list(args))
    except SystemExit as exc:
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def test_sleigh_forwards_and_backwards(capsys):
    code, out, err = inproc(capsys, "linearize", "chaplygin_sleigh", "-q",
                            "--at", "theta=0,x_t=1,theta_t=0")
    assert code == 0, err
    assert "state:      theta, x_t, theta_t (dropped: x, y)" in out
    assert "verdict: marginal" in out and "(a steady motion)" in out
    code, out, _ = inproc(capsys, "linearize", "chaplygin_sleigh", "-q", "--at",
                          "theta=0,x_t=-1,theta_t=0", "--format", "json")
    data = json.loads(out)
    assert data["verdict"] == "unstable" and data["residual"] == 0.0
    assert max(re for re, _ in data["eigenvalues"]) == pytest.approx(1 / 0.9)


def test_coin_scan_crossing_and_plot(capsys, tmp_path):
    png = tmp_path / "coin.png"
    code, out, err = inproc(capsys, "linearize", "rolling_coin", "-q", "--at",
                            "theta=0,psi_t=0,theta_t=0,phi_t=3", "--param",
                            "phi_t=0.2:4:20", "--plot", str(png), "--format", "json")
    assert code == 0, err
    crossing, = json.loads(out)["scan"]["crossings"]
    assert abs(crossing - np.sqrt(9.81 / 3)) < 1e-10
    assert png.stat().st_size > 1000


def test_steady_turning(capsys):
    code, out, err = inproc(capsys, "linearize", "rolling_coin", "-q", "--at",
                            "theta=0.2,psi_t=1.5,theta_t=0,phi_t=4", "--steady", "phi_t",
                            "--format", "json")
    assert code == 0, err
    assert json.loads(out)["residual"] < 1e-10


@pytest.mark.parametrize("args,words", [
    (["--param", "phi_t=1:2"], "--param phi_t: '1:2' is not A:B:N"),
    (["--param", "1:2:3"], "--param takes NAME=A:B:N"),
    (["--plot", "x.png"], "give --param"),
    (["--drop", "theta"], "cannot drop 'theta'"),
    (["--at", "zeta=1"], "not a state"),
])
def test_usage_errors(args, words, capsys):
    code, out, err = inproc(capsys, "linearize", "chaplygin_sleigh", "-q",
                            "--at", "theta=0,x_t=1,theta_t=0", *args)
    assert code != 0 and words in err and "Traceback" not in err


def test_help(capsys):
    code, out, _ = inproc(capsys, "linearize", "--help")
    assert code == 0 and "usage: jetnh linearize" in out and "--param" in out


def test_holonomic_constraint(capsys, tmp_path):
    """A model file with g = x^2 + y^2 - l^2: y follows from g = 0 (no zero eigenvalue);
    a point off g = 0 is refused with the value that would put it there."""
    path = tmp_path / "pendulum.toml"
    path.write_text(PENDULUM_XY)
    code, out, err = inproc(capsys, "linearize", str(path), "-q", "--at", "x=0,y=-1,x_t=0")
    assert code == 0, err
    assert "state:      x, x_t (from g = 0: y)" in out
    code, out, _ = inproc(capsys, "linearize", str(path), "-q", "--at", "x=0,y=-1,x_t=0",
                          "--format", "json")
    data = json.loads(out)
    assert data["eliminated"] == ["y"]
    assert np.allclose(sorted(im for _, im in data["eigenvalues"]),
                       [-np.sqrt(9.81), np.sqrt(9.81)], atol=1e-12)
    code, _, err = inproc(capsys, "linearize", str(path), "-q", "--at", "x=0.1,y=-1,x_t=0")
    assert code != 0 and "off the holonomic constraints" in err and "y = -0.99498" in err


def test_a_second_param_is_refused_naming_both(capsys):
    """A scan is along one name: a second --param is refused (naming both), never
    dropped, before anything is derived."""
    code, out, err = inproc(capsys, "linearize", "chaplygin_sleigh", "-q", "--at",
                            "theta=0,x_t=1,theta_t=0", "--param", "x_t=0.5:2:4",
                            "--param", "theta=0:1:3")
    assert code == 2 and out == ""
    assert "--param scans one name" in err
    assert "'x_t=0.5:2:4'" in err and "'theta=0:1:3'" in err
