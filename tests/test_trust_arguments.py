"""Arguments of public functions are checked (type, size budget, solvability) before any
work, with a JetnhError that names the problem and the fix."""

import subprocess
import sys
import textwrap

import pytest
import sympy as sp
from hypothesis import given
from hypothesis import strategies as st

import jetnh as jn
from jetnh import models
from jetnh.errors import ArgumentError, ConstraintError, JetnhError, ModelFileError
from jetnh.models._registry import MAX_OPTION

GARBAGE = st.one_of(st.none(), st.integers(), st.floats(allow_nan=True), st.text(max_size=5),
                    st.lists(st.none(), max_size=2), st.just(object()),
                    st.just(sp.Symbol("x")))


@given(GARBAGE)
def test_compare_checks_its_system(bad):
    with pytest.raises(JetnhError):
        jn.compare(bad, "chetaev", "suslov")


@given(GARBAGE)
def test_sweep_checks_its_scene(bad):
    with pytest.raises(JetnhError):
        jn.sweep(bad, {"R": [1.0]})


def test_sweep_of_a_system_says_what_it_wants():
    with pytest.raises(ArgumentError, match="sweep needs a Scene.*not System"):
        jn.sweep(models.get("rolling_disk"), {"R": [1.0]})


@given(st.one_of(st.none(), st.integers(), st.floats(), st.just(object())))
def test_jetspace_checks_its_coordinates(bad):
    with pytest.raises(JetnhError):
        jn.JetSpace(bad)


@pytest.mark.parametrize("N", [-1, MAX_OPTION + 1, 10**9, 2.5, True, "3"])
def test_family_size_budget(N):
    with pytest.raises(ModelFileError, match="option N must be an integer"):
        models.get("n_trailer", N=N)
    with pytest.raises(ModelFileError):
        models.initial("n_trailer", N=N)


def _system(constraints, dependent):
    J = jn.JetSpace("x y z")
    L = sum(v**2 for v in J.qd) / 2
    return J, jn.System(J, L, constraints(J), dependent=dependent)


@pytest.mark.parametrize("make, words", [
    (lambda J: [J.qd[0]**4 + J.qd[0] - J.qd[1]], "degrees \\[4\\]"),
    (lambda J: [J.qd[0]**2 + J.qd[1]**2 - J.qd[2], J.qd[0] * J.qd[1] - 1 - J.qd[2]],
     "up to 4 solutions"),
    (lambda J: [sp.exp(J.qd[0]) + J.qd[0] - J.qd[1]], "LambertW"),
])
def test_nonlinear_constraints_within_the_budget(make, words):
    J = jn.JetSpace("x y z")
    dep = ["x"] if len(make(J)) == 1 else ["x", "y"]
    with pytest.raises(ConstraintError, match=words):
        _system(make, dep)[1].phi


def test_one_quadratic_is_still_solved():
    J, s = _system(lambda J: [J.qd[0]**2 - J.qd[1]**2 - J.qd[2]**2], ["x"])
    s = jn.System(J, s.L, s.constraints, dependent=["x"], branch=1)
    assert sp.simplify(s.phi[J.qd[0]]**2 - J.qd[1]**2 - J.qd[2]**2) == 0


@pytest.mark.parametrize("power", [sp.Float(1e300), 10**300, 65, -100])
def test_huge_powers_refused(power):
    J = jn.JetSpace("x y")
    with pytest.raises(JetnhError, match="budget of \\|exponent\\|"):
        jn.System(J, J.qd[0]**power + J.qd[1]**2)


@pytest.mark.parametrize("timeout", [float("nan"), -1.0, 0.0, "2", [2]])
def test_sweep_timeout_checked(timeout):
    sc = jn.Scene(models.get("appell_hamel"), "chetaev",
                  initial=dict(x=0, y=0, z=0, x_t=0.6, y_t=0.8), t_span=(0.0, 0.1))
    with pytest.raises(JetnhError, match="timeout"):
        jn.sweep(sc, {"x_t": [0.6]}, timeout=timeout)


def test_sweep_timeout_honoured():
    sc = jn.Scene(models.get("appell_hamel"), "chetaev",
                  initial=dict(x=0, y=0, z=0, x_t=0.6, y_t=0.8), t_span=(0.0, 0.1))
    with pytest.raises(JetnhError, match="did not finish within timeout"):
        jn.sweep(sc, {"x_t": [0.6] * 4, "y_t": [0.8]}, timeout=1e-9, chunk_size=1)
