"""Equivalence of principles: identically, on the branch (32), along states."""

import numpy as np
from hypothesis import given, settings

import jetnh.strategies as jst
from jetnh import JetSpace, System, compare
from jetnh.equivalence import defect_along, frobenius_T
from jetnh.models import appell_hamel, rolling_disk
from jetnh.testing import vanishes


def test_disk_verdicts():
    s = rolling_disk()
    assert compare(s, "chetaev", "suslov").identical
    assert compare(s, "vakonomic", "holder").identical
    c = compare(s, "vakonomic", "suslov")
    assert not c.identical and c.on_branch_32


def test_appell_hamel_vakonomic_agrees_for_every_multiplier():
    c = compare(appell_hamel(), "vakonomic", "suslov")
    assert c.identical


def test_suslov_differs_from_chetaev_when_p_T_is_nonzero():
    J = JetSpace("x y z")
    x, y, z = J.q
    s = System(J, sum(v**2 for v in J.qd) / 2, [J.qd[2] - y * J.qd[0]], [z])
    assert not compare(s, "chetaev", "suslov").identical
    pT = s.on_constraints(s.p_dependent[0]) * s.T()[0, 0]
    assert not vanishes(pT, s)


@settings(max_examples=8)
@given(jst.constrained_systems(max_n=3, affine=True))
def test_integrable_iff_T_vanishes(case):
    J, L, cons, dep = case
    s = System(J, L, cons, dep)
    T_zero = all(vanishes(e, s) for e in s.T()) and all(vanishes(e, s) for e in frobenius_T(s))
    assert T_zero == s.is_integrable()


def test_defect_along_states():
    s = rolling_disk()
    rng = np.random.default_rng(0)
    n = 7
    d = {q.name: rng.uniform(0, 1, n) for q in s.J.q}
    d.update(phi_t=rng.uniform(0, 1, n), psi_t=rng.uniform(0, 1, n), R=np.ones(n),
             I1=np.full(n, 0.5), I2=np.full(n, 0.25))
    assert defect_along(s, "chetaev", "suslov", d) < 1e-12
    d["lambda_x"] = -d["phi_t"] * np.cos(d["psi"])       # lambda = -p: the branch (32)
    d["lambda_y"] = -d["phi_t"] * np.sin(d["psi"])
    assert defect_along(s, "chetaev", "vakonomic", d) < 1e-12
    d["lambda_x"] = d["lambda_x"] + 0.3
    assert defect_along(s, "chetaev", "vakonomic", d) > 1e-3
