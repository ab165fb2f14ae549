"""conserved_quantities: first integrals of the catalogue, both routes, bad input."""

import random

import pytest
import sympy as sp

import jetnh as jn
from jetnh import models

pytestmark = pytest.mark.filterwarnings("ignore")


def _in_span(expr, basis, gens):
    """Whether expr is a combination of basis with coefficients free of gens (exact)."""
    cs = sp.symbols(f"c0:{len(basis)}")
    diff = sp.Poly(sp.expand(expr - sum(c * b for c, b in zip(cs, basis))), *gens)
    return bool(sp.solve(diff.coeffs(), cs, dict=True))


def _DI_numeric(sysm, principle, I, points=10):
    """Second route: D I with sympy's subs and evalf at random points."""
    eom = sysm.equations(principle)
    J = eom.J
    DI = sysm.on_constraints(J.D(I).subs(eom.accelerations()))
    rng = random.Random(3)
    syms = sorted(DI.free_symbols, key=str)
    out = []
    for _ in range(points):
        p = {s: sp.Rational(rng.randint(5, 20), 10) for s in syms}
        out.append(abs(DI.subs(p).evalf(40)))
    return max(out) if out else 0


def test_rolling_disk_chetaev():
    s = models.get("rolling_disk")
    x, y, phi, psi = s.J.q
    _, _, phid, psid = s.J.qd
    R, I1, I2 = s.parameters[2], s.parameters[0], s.parameters[1]
    basis = jn.conserved_quantities(s, "chetaev", degree=2)
    gens = (s.J.t, *s.J.q, phid, psid)
    energy = ((R**2 + I1) * phid**2 + I2 * psid**2) / 2
    for expected in (phid, psid, energy):
        assert _in_span(expected, basis, gens)
    assert not _in_span(psi, basis, gens)
    for I in basis:
        assert _DI_numeric(s, "chetaev", I) < 1e-30
        assert I.free_symbols.isdisjoint(s.dependent_velocities)


def test_nonholonomic_particle_chetaev():
    s = models.get("nonholonomic_particle")
    x, y, z = s.J.q
    xd, yd, zd = s.J.qd
    # the expected integrals, first checked against jetnh's accelerations
    acc = s.equations("chetaev").accelerations()
    for I in (yd, (1 + y**2) * xd**2):
        assert sp.cancel(s.on_constraints(s.J.D(I).xreplace(acc))) == 0
    basis = jn.conserved_quantities(s, "chetaev", degree=2)
    gens = (s.J.t, x, y, z, xd, yd)
    assert _in_span(yd, basis, gens) and _in_span((1 + y**2) * xd**2, basis, gens)
    assert not _in_span(xd, basis, gens)
    assert len(basis) == 8
    for I in basis:
        assert _DI_numeric(s, "chetaev", I) < 1e-30


def test_nonholonomic_particle_vakonomic_energy():
    s = models.get("nonholonomic_particle")
    x, y, z = s.J.q
    xd, yd, _ = s.J.qd
    basis = jn.conserved_quantities(s, "vakonomic", degree=2, coefficients=[1, y, y**2])
    assert _in_span((1 + y**2) * xd**2 + yd**2, basis, (x, y, z, xd, yd, sp.Symbol("lambda_z")))
    for I in basis:
        assert _DI_numeric(s, "vakonomic", I) < 1e-30


def test_bad_input():
    s = models.get("nonholonomic_particle")
    for d in (0, -1, 1.5, True):
        with pytest.raises(jn.ArgumentError, match="degree"):
            jn.conserved_quantities(s, "chetaev", degree=d)
    with pytest.raises(jn.PrincipleError, match="unknown principle"):
        jn.conserved_quantities(s, "newton")
    with pytest.raises(jn.ArgumentError, match="budget"):
        jn.conserved_quantities(s, "chetaev", degree=4)
    with pytest.raises(jn.ArgumentError, match="coefficient"):
        jn.conserved_quantities(s, "chetaev", coefficients=[s.J.qd[0]])
    with pytest.raises(jn.ArgumentError, match="System"):
        jn.conserved_quantities("rolling_disk", "chetaev")
