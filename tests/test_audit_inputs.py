"""Inputs a new user got wrong without being told: a stability verdict off a steady
motion, strings in sweep grids, the error classes of bad values in linearize and sweep, a
Lagrangian with accelerations, empty and zero-width scans, the Equations repr."""

import numpy as np
import pytest

import jetnh as jn
from jetnh.errors import ArgumentError, LagrangianError
from jetnh.sweep import sweep

from damped_sleigh import damped_sleigh

PARAMS = {"m": 2.0, "a": 0.3, "I": 0.5, "c": 0.1}


@pytest.fixture(scope="module")
def sleigh():
    return damped_sleigh()


@pytest.fixture(scope="module")
def straight(sleigh):
    return jn.linearize(sleigh, "chetaev", at={"th": 0.0, "x_t": 1.5, "th_t": 0.0},
                        params=PARAMS)


# ---------------------------------------------------------------------- steady motions
def test_no_verdict_off_a_steady_motion(straight):
    """Turning at th_t = 1 the speed changes (v' = a th_t^2): x' = (th_t, a th_t^2, ...)
    is not 0, so there is no stability verdict; straight motion is steady, with the
    eigenvalue -(m a v + c)/(I + m a^2) beside the two zeros of the family."""
    m, a, I, c = PARAMS["m"], PARAMS["a"], PARAMS["I"], PARAMS["c"]
    assert straight.steady_motion and straight.residual == 0.0
    assert straight.verdict == "marginal" and straight.stable is True
    assert np.allclose(sorted(straight.eigenvalues.real), [-(m * a * 1.5 + c) / (I + m * a**2),
                                                           0.0, 0.0], atol=1e-12)
    turning = straight.replace(at={"th_t": 1.0})
    assert turning.residual > 1.0                     # |(th_t, a th_t^2, ...)|
    assert not turning.steady_motion
    assert turning.verdict == "not a steady motion" and turning.stable is None
    assert np.isnan(turning.margin)
    assert "not a steady motion" in repr(turning)
    back = turning.steady(["th_t"])                   # steady() finds the straight one
    assert back.steady_motion and abs(back.at["th_t"]) < 1e-9
    assert back.verdict == "marginal"


def test_steady_tolerance_is_relative_to_the_rates(straight):
    """Each rate is judged against the size of its own terms (and the rounding of the
    point through it), not against |A| |x| nor the number 1: at x_t = 1e6 straight
    motion is steady, and a turn th_t = 1e-3, 1e-9 or 1e-12 is none (th' = th_t is its
    own term), however fast the sleigh runs."""
    fast = straight.replace(at={"x_t": 1e6})
    assert fast.steady_motion and fast.verdict == "marginal"
    for th_t in (1e-3, 1e-9, 1e-12):
        nudged = straight.replace(at={"x_t": 1e6, "th_t": th_t})  # ~ a th_t^2 + th_t x_t
        assert not nudged.steady_motion and nudged.verdict == "not a steady motion"


def test_scan_marks_points_off_steady_motions(straight):
    """Along th_t only th_t = 0 is steady: the other margins are NaN, not stable."""
    scan = straight.along("th_t", [-1.0, 0.0, 1.0])
    assert scan.steady_motion.tolist() == [False, True, False]
    assert np.isnan(scan.margins[[0, 2]]).all() and scan.stable.tolist() == [False, True,
                                                                             False]
    assert scan.frame["steady_motion"].tolist() == [False, True, False]
    assert scan.crossings == ()


# ---------------------------------------------------------------------- error classes
@pytest.mark.parametrize("at,words", [
    ({"th": 0.0, "x_t": float("nan"), "th_t": 0.0}, "give a finite value"),
    ({"th": 0.0, "x_t": "1.5", "th_t": 0.0}, "must be a number"),
    ({"th": 0.0, "x_t": 1.5}, "missing operating-point values: th_t"),
    ({"th": 0.0, "x_t": 1.5, "th_t": 0.0, "zeta": 1.0}, "not a state"),
    ([0.0, 1.5, 0.0], "at must be a dict"),
])
def test_bad_operating_points_are_argument_errors(sleigh, at, words):
    with pytest.raises(ArgumentError, match=words):
        jn.linearize(sleigh, "chetaev", at=at, params=PARAMS)


def test_bad_linearize_arguments_are_argument_errors(sleigh, straight):
    point = {"th": 0.0, "x_t": 1.5, "th_t": 0.0}
    with pytest.raises(ArgumentError, match="not a parameter"):
        jn.linearize(sleigh, at=point, params={**PARAMS, "g": 9.81})
    with pytest.raises(ArgumentError, match="missing parameter values"):
        jn.linearize(sleigh, at=point, params={"m": 1.0})
    with pytest.raises(ArgumentError, match="drop must be"):
        jn.linearize(sleigh, at=point, params=PARAMS, drop="all")
    with pytest.raises(ArgumentError, match="needs a jetnh System"):
        jn.linearize("sleigh", at=point)
    with pytest.raises(ArgumentError, match="neither a parameter"):
        straight.along("zeta", [1.0])
    with pytest.raises(ArgumentError, match="at least one value"):
        straight.along("x_t", [])
    with pytest.raises(ArgumentError, match="cannot solve for"):
        straight.steady(["x"])
    with pytest.raises(ArgumentError, match="unknowns names no state to solve for"):
        straight.steady([])
    with pytest.raises(ArgumentError, match="tol must be a positive"):
        straight.steady(["th_t"], tol=-1.0)


def test_a_lagrangian_with_accelerations_is_a_lagrangian_error():
    J = jn.JetSpace("x y")
    with pytest.raises(LagrangianError, match="accelerations"):
        jn.System(J, J.qd[0] ** 2 / 2 + J.qd[0] * J.qdd[0])


# ---------------------------------------------------------------------- sweep
@pytest.fixture(scope="module")
def scene(sleigh):
    return jn.Scene(sleigh, "chetaev", params=PARAMS,
                    initial={"x": 0.0, "y": 0.0, "th": 0.0, "x_t": 1.0, "th_t": 0.0},
                    t_span=(0.0, 0.1))


@pytest.mark.parametrize("grid,words", [
    ({"m": "12"}, "grid values of 'm' must be numbers: it holds the string '12'"),
    ({"m": ["1", "2"]}, "holds the string '1'"),
    ({"m": [1.0, "2"]}, "holds the string '2'"),
    ({"m": np.array(["1", "2"])}, "holds the string"),
    ([{"m": 1.0}, {"m": "2"}], "grid point 1 must be numbers: it holds the string '2'"),
    ({"m": [True, False]}, "grid values of .m. must be a number, got True"),
    ({"m": [1.0, np.nan]}, "non-finite"),
    ({"m": []}, "empty"),
    ({"zeta": [1.0]}, "neither a parameter"),
    ({}, "the grid is empty"),
])
def test_sweep_refuses_bad_grid_values(scene, grid, words):
    """Strings are never parsed (as Scene and run refuse them); every bad value is an
    ArgumentError, raised before anything runs."""
    with pytest.raises(ArgumentError, match=words):
        sweep(scene, grid)


def test_sweep_bad_options_are_argument_errors(scene):
    with pytest.raises(ArgumentError, match="no option"):
        sweep(scene, {"m": [1.0]}, stepz=3)
    with pytest.raises(ArgumentError, match="chunk_size"):
        sweep(scene, {"m": [1.0]}, chunk_size=0)
    with pytest.raises(ArgumentError, match="outputs"):
        sweep(scene, {"m": [1.0]}, outputs=["zeta"])
    with pytest.raises(ArgumentError, match="progress"):
        sweep(scene, {"m": [1.0]}, progress="yes")


# ---------------------------------------------------------------------- command line
def _cli(capsys, *args):
    from jetnh.cli import main

    try:
        code = main(list(args))
    except SystemExit as exc:
        code = exc.code
    return code, capsys.readouterr().err


@pytest.mark.parametrize("args,words", [
    (["linearize", "chaplygin_sleigh", "--at", "theta=0,x_t=1,theta_t=0",
      "--param", "x_t=1:1:5"], "range of zero width"),
    (["linearize", "chaplygin_sleigh", "--at", "theta=0,x_t=1,theta_t=0",
      "--param", "x_t=0:inf:5"], "must be finite numbers"),
    (["sweep", "chaplygin_sleigh", "--grid", "x_t=1:1:5"], "range of zero width"),
    (["sweep", "chaplygin_sleigh", "--grid", "x_t=0:nan:5"], "finite numbers"),
    (["sweep", "chaplygin_sleigh", "--grid", "x_t=1,inf"], "finite numbers"),
])
def test_cli_refuses_degenerate_ranges(capsys, args, words):
    code, err = _cli(capsys, *args, "-q")
    assert code == 2 and words in err and "Traceback" not in err


def test_cli_sweep_accepts_a_single_value_range():
    from jetnh.cli.commands.sweep import _values

    assert _values("2:2:1", "--grid x") == [2.0]
    assert _values("0:1:3", "--grid x") == [0.0, 0.5, 1.0]


# ---------------------------------------------------------------------- display
def test_equations_repr_has_no_stray_space(sleigh):
    r = repr(sleigh.equations("chetaev"))
    assert r == "<Equations chetaev (maggi, paper convention)>"
