"""The Whipple bicycle (Meijaard et al. 2007) written for KanesMethod, imported into jetnh:
jetnh's Chetaev accelerations agree with Kane's equations (``test_kane.agreement``) at
random states on the constraints (the pitch solved from the front contact's height), with
the benchmark's parameters."""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import sympy as sp

import jetnh as jn
from jetnh.algebra import dag
from jetnh.models.whipple import DEPENDENT, benchmark_parameters, upright, whipple_kane
from test_kane import RTOL, agreement

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def bicycle():
    km = whipple_kane()
    return km, jn.from_mechanics(km)


def pitch_on_the_ground(system, params):
    """A sampler of configurations: random contact point, yaw, wheel angles, roll q2 and
    steer q5; the pitch q4 from the configuration constraint (secant, 30 digits)."""
    J = system.J
    (height,) = (g.xreplace(params) for g in system.holonomic)
    at = {q.name: i for i, q in enumerate(J.q)}
    q4 = J.q[at["q4"]]

    def sample(rnd):
        qs = [rnd.uniform(-1, 1) for _ in J.q]
        qs[at["q2"]], qs[at["q5"]] = rnd.uniform(-0.3, 0.3), rnd.uniform(-0.4, 0.4)
        rest = {q: sp.Float(v, 30) for q, v in zip(J.q, qs) if q != q4}
        f = sp.lambdify(q4, height.xreplace(rest), "mpmath")
        with mpmath.workdps(30):
            qs[at["q4"]] = mpmath.findroot(f, 0)
        return qs
    return sample


def test_whipple_bicycle_agrees_with_kane(bicycle):
    km, s = bicycle
    assert len(s.constraints) == 5 and len(s.independent_velocities) == 3
    assert len(s.holonomic) == 1 and s.holonomic[0] == s.J.from_dynamic(km._f_h[0])
    params = {sp.Symbol(k): v for k, v in benchmark_parameters().items()}
    err = agreement(s, km, params, sample_q=pitch_on_the_ground(s, params), points=2)
    assert err < RTOL


def test_weave_and_capsize_speeds():
    """Meijaard et al. (2007), Table 3 / section 4: weave v_w = 4.29238253634111 m/s and
    capsize v_c = 6.02426201538837 m/s, the crossings of Re lambda = 0 along the speed of
    jetnh's own linearization of upright straight running."""
    km = whipple_kane()
    bike = jn.from_mechanics(km, dependent=DEPENDENT)
    params = benchmark_parameters()
    rR = params["WRrad"]
    lin = jn.linearize(bike, "chetaev", at=upright(bike, 5.0, params), params=params)
    scan = lin.along("q3_t", np.linspace(0.0, 10.0, 21) / rR)
    speeds = [c * rR for c in scan.crossings]
    assert speeds == pytest.approx([4.29238253634111, 6.02426201538837], abs=1e-10)
    stable = scan.values[scan.stable] * rR
    assert stable.min() == pytest.approx(4.5) and stable.max() == pytest.approx(6.0)
