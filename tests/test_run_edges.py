"""Edges of a run that must never give a silent wrong answer: a span of zero length (or
one whose end rounded onto its start), a relative tolerance of 100 % or more, a bad
``[simulation]`` value in a model file (refused before any derivation), output rows
between projected steps off the holonomic constraints, and overflowing sums in the
finiteness check."""

import subprocess
import sys
import warnings

import numpy as np
import pytest

import jetnh as jn
from jetnh.errors import ArgumentError, ModelFileError
from jetnh.modelfile import loads
from jetnh.numeric import arguments
from jetnh.numeric.options import StepControl

from damped_sleigh import ORIGIN, PARAMS, damped_sleigh
from model_texts import PENDULUM_XY_STARTED

P, O = PARAMS, ORIGIN

SLEIGH = """
name = "damped sleigh"
coordinates = ["x", "y", "th"]
dependent = ["y"]
lagrangian = "m/2*((x_t - a*sin(th)*th_t)**2 + (y_t + a*cos(th)*th_t)**2) + I/2*th_t**2"
constraints = ["-sin(th)*x_t + cos(th)*y_t"]
[forces]
th = "-c*th_t"
[parameters]
m = 2.0
a = 0.3
I = 0.5
c = 0.1
[initial]
x_t = 1.0
th_t = 0.4
[simulation]
"""



@pytest.fixture(scope="module")
def sleigh():
    return jn.Scene(damped_sleigh(), "chetaev", params=P, initial={**O, "x_t": 1, "th_t": .4},
                    t_span=(0.0, 1.0))


@pytest.fixture(scope="module")
def pendulum():
    model = loads(PENDULUM_XY_STARTED)
    return jn.Scene(model.system, "chetaev", params={"G": 9.81, "l": 1.0},
                    initial=dict(model.initial), t_span=(0.0, 100.0))


# ------------------------------------------------------------------ zero-length spans
@pytest.mark.parametrize("span", [(1e20, 1e20 + 1), (0, 0), (-3.5, -3.5)])
def test_a_zero_length_span_is_refused_everywhere(sleigh, span):
    """(1e20, 1e20 + 1) is (1e20, 1e20) once rounded: it used to run as one row that
    "reached the end of the interval"."""
    with pytest.raises(ArgumentError, match="zero length.*shift the time origin"):
        jn.Scene(sleigh.system, "chetaev", params=P, initial=dict(sleigh.initial),
                 t_span=span)
    for method in ("dop853", "radau", "rk4"):
        with pytest.raises(ArgumentError, match="zero length"):
            sleigh.run(t_span=span, method=method,
                       **({"n_steps": 4} if method == "rk4" else {}))
    with pytest.raises(ArgumentError, match="zero length"):
        sleigh.replace(t_span=span)
    with pytest.raises(ArgumentError, match="zero length"):
        arguments.time_span(span)


def test_a_nonzero_span_still_runs_backwards_and_forwards(sleigh):
    fwd = sleigh.run(t_span=(0.0, 0.5), save="final")
    back = sleigh.run(t_span=(0.5, 0.0), y0=fwd.y[-1], save="final", rtol=1e-12,
                      atol=1e-12)
    assert fwd.success and back.success
    assert np.allclose(back.y[-1], sleigh.y0, atol=1e-8)


# ------------------------------------------------------------------ tolerances
@pytest.mark.parametrize("rtol", [1.0, 1e3, 1e9])
def test_rtol_of_100_percent_or_more_is_refused(sleigh, rtol):
    with pytest.raises(ArgumentError, match="rtol must be below 1.*rtol=1e-6"):
        sleigh.run(rtol=rtol)
    with pytest.raises(ArgumentError, match="rtol must be below 1"):
        sleigh.run(step=StepControl(rtol=rtol), t_eval=[0.5])
    with pytest.raises(ArgumentError, match="rtol must be below 1"):
        sleigh.ensemble({"x_t": [1.0, 2.0]}, rtol=rtol)
    with pytest.raises(ArgumentError, match="rtol must be below 1"):
        jn.sweep(sleigh, {"x_t": [1.0, 2.0]}, rtol=rtol)


def test_rtol_just_below_one_runs(sleigh):
    assert sleigh.run(rtol=0.5, atol=1e-6, save="final").success


# ------------------------------------------------------------------ model files
@pytest.mark.parametrize("simulation, match", [
    ('t_end = 0.0', "t_start, t_end: t_span = .0.0, 0.0. has zero length"),
    ("t_start = 1e20\nt_end = 1.00000000000000001e20", "t_start, t_end: .* zero length"),
    ('t_end = 5.0\nrtol = 1e9', "rtol, atol: rtol must be below 1"),
    ('t_end = 5.0\nmethod = "euler"', "method: unknown method 'euler'; choose one of"),
])
def test_bad_simulation_values_are_refused_when_the_file_is_read(simulation, match):
    with pytest.raises(ModelFileError, match=r"\[simulation\] " + match):
        loads(SLEIGH + simulation)


def test_a_negative_t_end_is_read_as_documented():
    assert loads(SLEIGH + "t_end = -5.0").simulation["t_end"] == -5.0
    assert "integrates backwards" in jn.modelfile.__doc__


def test_cli_refuses_bad_run_options_before_deriving(tmp_path):
    """A bad method or tolerance from the command line or from the file stops the
    command before the kernels are derived (no "deriving" step is announced)."""
    bad = tmp_path / "bad.toml"
    bad.write_text(SLEIGH + 't_end = 5.0\nmethod = "euler"\n')
    good = tmp_path / "good.toml"
    good.write_text(SLEIGH + "t_end = 5.0\n")
    for argv, match in (([str(bad)], "unknown method 'euler'"),
                        ([str(good), "--rtol", "5"], "--rtol must be below 1"),
                        ([str(good), "--method", "euler"], "unknown method 'euler'"),
                        ([str(good), "--t-end", "0"], "zero length")):
        r = subprocess.run([sys.executable, "-m", "jetnh", "simulate", *argv],
                           capture_output=True, text=True, timeout=300)
        assert r.returncode != 0 and match in r.stderr, r.stderr
        assert "Traceback" not in r.stderr and "deriving" not in r.stderr, r.stderr


# ------------------------------------------------------------------ holonomic rows
@pytest.mark.parametrize("method", ["dop853", "radau"])
def test_rows_at_t_eval_lie_on_the_holonomic_constraint(pendulum, method):
    """Dense output between projected steps is off g = 0 by its error (8e-10 here
    before); the rows are projected as the steps are, and move by that error only."""
    te = np.linspace(0.0, 100.0, 501)
    tr = pendulum.run(t_eval=te, method=method)
    steps = pendulum.run(method=method)
    assert tr.success and np.array_equal(tr.t, te)
    x, y = tr["x"], tr["y"]
    assert np.max(np.abs(x**2 + y**2 - 1.0)) < 1e-14
    assert np.max(np.abs(tr.holonomic_residual)) < 1e-14
    assert tr.diagnostics.holonomic_residual_max < 1e-14
    # the velocity level: the dependent velocity keeps x x_t + y y_t = 0
    assert np.max(np.abs(x * tr["x_t"] + y * tr["y_t"])) < 1e-12
    # the same motion as the steps (a second route: the steps' own rows)
    inside = steps.t[(steps.t > 0) & (steps.t < 100)][::50]
    near = pendulum.run(t_eval=inside, method=method)
    assert np.allclose(near.y, steps.y[np.searchsorted(steps.t, inside)], atol=1e-12)
    if method != "radau":           # at() re-takes the steps: the same rows to the bit
        assert np.array_equal(steps.at(te).to_numpy(), tr.y)


def test_rows_without_holonomic_constraints_are_the_dense_output(sleigh):
    """No projection where there is nothing to project: t_eval rows are the re-taken
    steps' dense output to the bit."""
    te = np.linspace(0.0, 1.0, 7)
    assert np.array_equal(sleigh.run().at(te).to_numpy(), sleigh.run(t_eval=te).y)


# ------------------------------------------------------------------ finiteness check
def test_all_finite_of_huge_values_warns_nothing():
    big = np.array([1e308, -1e308, 1e308])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert arguments.all_finite(big)
        assert arguments.all_finite(big, big)
        assert not arguments.all_finite(np.array([1e308, np.inf]))
        assert not arguments.all_finite(big, np.array([np.nan]))
        assert np.array_equal(arguments.real_array(big, "guess"), big)


@pytest.mark.parametrize("n", [10, 300, 3000, 5000, 40000])
def test_all_finite_at_every_size_route(n):
    """Each size route of ``all_finite`` (Python sum, dot product, entrywise) finds the one
    bad entry wherever it is, and passes huge finite values."""
    a = np.full(n, 1e200)
    assert arguments.all_finite(a) and arguments.all_finite(a[: n // 2], a[n // 2:])
    for bad in (np.nan, np.inf, -np.inf):
        for i in (0, n // 2, n - 1):
            b = a.copy()
            b[i] = bad
            assert not arguments.all_finite(b)
            assert not arguments.all_finite(a, b)


def test_projection_of_rows_leaves_singular_rows_and_is_the_steps_projection():
    """``projection.rows`` (the dense output's rows) against ``projection.project`` (the
    projection of a step inside a compiled loop), row by row: the same states to the
    bit, and a row where G G^T is singular (the circle's centre) left as it is."""
    import numba

    from jetnh.numeric.kernels.calls import Kernel
    from jetnh.numeric.methods import projection
    from jetnh.numeric.methods._common import RHS_SIGNATURE
    from jetnh.numeric.methods.loop import Control

    @numba.cfunc(RHS_SIGNATURE)
    def hol(t, y, p, out):              # g = x^2 + y^2 - 1 - t/10, G = (2x, 2y)
        out[0] = y[0]**2 + y[1]**2 - 1.0 - t / 10
        out[1] = 2 * y[0]
        out[2] = 2 * y[1]

    rng = np.random.default_rng(3)
    ys = np.vstack([rng.uniform(-2, 2, (6, 3)), [[0.0, 0.0, 5.0]]])
    ts = np.linspace(0.0, 1.0, 7)
    ctl = Control(1e-6, np.ones(3), 0.0, np.inf, 10, 0, 1, 2, 0)
    one = ys.copy()
    for t, y in zip(ts, one):
        projection.project(hol, ctl, t, y, np.zeros(0), projection.workspace(1, 2, 0))
    together = ys.copy()
    projection.rows(Kernel(hol, (3, 0, 3)), 1, 2, ts, together, np.zeros(0))
    assert np.array_equal(together, one)
    g = together[:6, 0]**2 + together[:6, 1]**2 - 1 - ts[:6] / 10
    assert np.max(np.abs(g)) < 1e-15
    assert np.array_equal(together[6], ys[6]) and np.array_equal(together[:, 2], ys[:, 2])
