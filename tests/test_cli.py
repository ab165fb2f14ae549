"""The jetnh command end to end, in a subprocess."""

import json
import subprocess
import sys


def run(*args):
    return subprocess.run([sys.executable, "-m", "jetnh", *args], capture_output=True,
                          text=True, timeout=300)


def test_compare_rolling_disk():
    r = run("compare", "rolling_disk")
    assert r.returncode == 0, r.stderr
    assert "nonholonomic" in r.stdout and "Chaplygin" in r.stdout
    assert "chetaev and suslov have the same accelerations at every state" in r.stdout
    assert "vakonomic and suslov agree on the branch" in r.stdout


def test_derive_json():
    r = run("derive", "appell_hamel", "--principle", "suslov", "--format", "json")
    assert r.returncode == 0, r.stderr
    data = json.loads(r.stdout)
    assert data["principle"] == "suslov" and data["multipliers"] == ["lambda_z"]
    assert set(data["accelerations"]) == {"x_tt", "y_tt", "z_tt", "lambda_z_t"}


def test_errors_exit_codes_and_no_traceback():
    r = run("derive", "no_such_model")
    assert r.returncode == 1 and "no model named" in r.stderr and "Traceback" not in r.stderr
    r = run("derive", "rolling_disk", "--form", "nonsense")
    assert r.returncode == 1 and "forms" in r.stderr and "Traceback" not in r.stderr
    r = run("frobnicate")
    assert r.returncode == 2 and "Traceback" not in r.stderr
