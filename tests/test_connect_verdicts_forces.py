"""connect's verdicts under non-potential forces: a vakonomic or Hoelder motion of a
forced system is no extremal of int L dt, so ``legendre`` and ``minimizer`` certify
nothing (None, with ``not_extremal`` saying why); ``cost`` is int L dt along the motion
(against the trapezoidal rule on the dense output), above the cost of an admissible path
with the same ends; forces that vanish at the parameter values certify as before (the
unforced system's verdicts); dissipation= and forces= give the same motion and verdicts;
random forced systems."""

from types import SimpleNamespace

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings, strategies as st

import jetnh as jn
import jetnh.strategies as jst
from jetnh.numeric.connect.verdicts import not_extremal

J = jn.JetSpace("x y z")
(x, y, z), (xd, yd, zd) = J.q, J.qd
c = sp.Symbol("c")
L = (xd**2 + yd**2) / 2
HEIS = [zd - (x * yd - y * xd) / 2]
O = {"x": 0.0, "y": 0.0, "z": 0.0}
END = {"x": 1.0, "y": 0.5, "z": 0.2}


def _forced():
    return jn.System(J, L, HEIS, dependent=[z], forces={x: -c * xd, y: -c * yd})


def _integral_of_L(sol):
    """int (x_t^2 + y_t^2)/2 dt on a fine grid of the dense output (trapezoid)."""
    t = np.linspace(*sol.trajectory.t[[0, -1]], 4001)
    v = sol.trajectory.at(t)
    return np.trapezoid((v["x_t"] ** 2 + v["y_t"] ** 2) / 2, t)


@pytest.mark.parametrize("principle", ["vakonomic", "holder"])
def test_forced_heisenberg_is_no_minimizer_and_says_so(principle):
    """The audit's reproducer: minimizer True and legendre 0.762 before; the unforced
    geodesic joins the same ends at a lower cost, so the forced motion is no minimizer."""
    sol = jn.connect(_forced(), principle, O, END, (0.0, 1.0), params={"c": 2.0})
    assert sol.residual < 1e-9
    assert sol.minimizer is None and sol.legendre is None
    assert "no extremal of int L dt" in sol.not_extremal
    assert "on x, y (forces=)" in sol.not_extremal
    assert "non-potential forces" in repr(sol) and "not checked" not in repr(sol)
    # cost: int L dt along the motion, by a second quadrature
    assert sol.cost == pytest.approx(_integral_of_L(sol), rel=1e-6)
    geodesic = jn.connect(jn.System(J, L, HEIS, dependent=[z]), principle, O, END,
                          (0.0, 1.0))
    assert geodesic.not_extremal == "" and geodesic.minimizer is True
    assert geodesic.cost < sol.cost - 0.2           # 0.8068 against 1.0770


def test_restarts_with_forces_say_why_they_did_not_search():
    """``restarts=`` searches only where the first answer is no minimizer; with forces
    the verdict is undecided, and ``search`` says so instead of staying empty."""
    sol = jn.connect(_forced(), "vakonomic", O, END, (0.0, 1.0), params={"c": 2.0},
                     restarts=2)
    plain = jn.connect(_forced(), "vakonomic", O, END, (0.0, 1.0), params={"c": 2.0})
    assert sol.cost == plain.cost and sol.minimizer is None
    assert sol.search.startswith("no restarts: the minimizer verdict is undecided")
    assert sol.not_extremal in sol.search


def test_forces_that_vanish_at_the_parameters_certify_as_before():
    """c = 0: the forced system's motion is the geodesic, with its verdicts."""
    free = jn.connect(_forced(), "vakonomic", O, END, (0.0, 1.0), params={"c": 0.0})
    geodesic = jn.connect(jn.System(J, L, HEIS, dependent=[z]), "vakonomic", O, END,
                          (0.0, 1.0))
    assert free.not_extremal == "" and free.minimizer is True
    assert free.legendre == pytest.approx(geodesic.legendre, abs=1e-12)
    assert free.cost == pytest.approx(geodesic.cost, rel=1e-9)


def test_dissipation_is_the_same_motion():
    """Rayleigh's D = c (x_t^2 + y_t^2) / 2 gives the forces -c x_t, -c y_t: the same
    motion, cost and (absent) verdicts, the reason naming dissipation=."""
    by_d = jn.System(J, L, HEIS, dependent=[z], dissipation=c * (xd**2 + yd**2) / 2)
    a = jn.connect(by_d, "vakonomic", O, END, (0.0, 1.0), params={"c": 2.0})
    b = jn.connect(_forced(), "vakonomic", O, END, (0.0, 1.0), params={"c": 2.0})
    assert a.minimizer is None and a.legendre is None
    assert "(dissipation=)" in a.not_extremal
    assert a.cost == pytest.approx(b.cost, rel=1e-9)
    assert a.initial["x_t"] == pytest.approx(b.initial["x_t"], rel=1e-8)


def test_chetaev_keeps_its_verdicts():
    """Chetaev: legendre and minimizer None as for every Chetaev motion, not_extremal ""
    (the principle's motions are no extremals whatever the forces)."""
    sol = jn.connect(_forced(), "chetaev", O, {"x": 1.0, "y": 0.5}, (0.0, 1.0),
                     params={"c": 2.0})
    assert sol.not_extremal == "" and sol.minimizer is None and sol.legendre is None


@settings(max_examples=10, deadline=None, suppress_health_check=list(HealthCheck))
@given(jst.constrained_systems(min_n=2, max_n=3), st.data())
def test_random_forced_systems(case, data):
    """Random systems with random forces s Q_q (s a parameter): the reason names exactly
    the forced coordinates at s = 1 and is empty at s = 0; Rayleigh dissipation
    sum c_q q_t^2 / 2 is named as dissipation=."""
    Jr, Lr, constraints, dependent = case
    forces = data.draw(jst.forces(Jr))
    s = sp.Symbol("s")
    S = jn.System(Jr, Lr, constraints, dependent,
                  forces={q: s * e for q, e in forces.items()})
    names = {q.name for q, e in forces.items() if sp.expand(e) != 0}

    def reason(system, params):          # not_extremal reads the scene's system and params
        return not_extremal(SimpleNamespace(system=system, params=params))

    told = reason(S, {"s": 1.0})
    assert reason(S, {"s": 0.0}) == ""
    if not names:                       # the drawn forces cancel: no force at all
        assert told == ""
        return
    assert told.startswith("the motion is no extremal of int L dt in general")
    on = told.split("forces on ")[1].split(" (")[0].split(", ")
    assert set(on) == names and "(forces=)" in told
    rates = {q: sp.Rational(k + 1, 3) for k, q in enumerate(forces)}
    D = sum(r * Jr.jet(q, 1)**2 / 2 for q, r in rates.items())
    told = reason(jn.System(Jr, Lr, constraints, dependent, dissipation=D), {})
    assert set(told.split("forces on ")[1].split(" (")[0].split(", ")) == set(
        q.name for q in forces)
    assert "(dissipation=)" in told
