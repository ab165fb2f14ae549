"""conserved_quantities: first integrals of the catalogue, both routes, bad input."""

import random

import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

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
    # the default space (polynomials of degree 2 in t, q times 1, sin psi, cos psi) is over
    # the solve's budget for four coordinates: a smaller space, searched in full
    with pytest.raises(jn.JetnhError, match="over the budget"):
        jn.conserved_quantities(s, "chetaev", degree=2)
    basis = jn.conserved_quantities(s, "chetaev", degree=2,
                                    coefficients=[1, sp.sin(psi), sp.cos(psi)])
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
    # 8 polynomial in the independent velocities, and 2 that need z_t (their restriction
    # z_t = y x_t has coefficients of degree 3 in q, outside the space of the others)
    assert len(basis) == 10
    assert sum(1 for I in basis if zd in I.free_symbols) == 2
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


# ---------------------------------------------------------------------- parameters
def test_heisenberg_vakonomic_parameter_dependent():
    """lambda, m x_t + 2 lambda y, m y_t - 2 lambda x and the energy: constants that
    depend on the parameter m (the ansatz solves over polynomials in m)."""
    s = models.get("heisenberg")
    x, y, z = s.J.q
    xd, yd, _ = s.J.qd
    m, lam = sp.Symbol("m"), sp.Symbol("lambda_z")
    basis = jn.conserved_quantities(s, "vakonomic", degree=2)
    gens = (s.J.t, x, y, z, xd, yd, lam)
    for expected in (lam, m * xd + 2 * lam * y, m * yd - 2 * lam * x, m * (xd**2 + yd**2)):
        assert _in_span(expected, basis, gens), expected
    assert not _in_span(xd, basis, gens)              # not a vakonomic integral
    for I in basis:
        assert _DI_numeric(s, "vakonomic", I) < 1e-30
    # no two are proportional over the parameters
    ratios = {sp.cancel(a / b) for i, a in enumerate(basis) for b in basis[i + 1:]}
    assert not any(r.free_symbols <= {m} for r in ratios)


def test_oscillator_energy_with_parameters():
    J = jn.JetSpace("x")
    x, xd = J.q[0], J.qd[0]
    m, k = sp.symbols("m k")
    s = jn.System(J, m * xd**2 / 2 - k * x**2 / 2)
    basis = jn.conserved_quantities(s, "chetaev", degree=2, coefficients=[1, x, x**2])
    assert len(basis) == 1
    assert sp.cancel(basis[0] / (m * xd**2 + k * x**2)).is_number


def test_parameter_functions_are_atoms():
    """The knife edge's energy has the factor sin(alpha): a polynomial in the atom
    sin(alpha), found with the coefficient 1/cos(phi)^2 that v^2 = x_t^2/cos(phi)^2 needs."""
    s = models.get("knife_edge")
    x, y, phi = s.J.q
    xd, _, phid = s.J.qd
    m, I, g, alpha = (sp.Symbol(n) for n in ("m", "I", "g", "alpha"))
    basis = jn.conserved_quantities(s, "chetaev", degree=2,
                                    coefficients=[1, x, 1 / sp.cos(phi)**2])
    E = m * xd**2 / sp.cos(phi)**2 / 2 + I * phid**2 / 2 - m * g * sp.sin(alpha) * x
    cs = sp.symbols(f"c0:{len(basis)}")
    res = sp.expand(E - sum(c * b for c, b in zip(cs, basis)))
    sol = sp.solve(sp.Poly(res.subs(1 / sp.cos(phi)**2, sp.Symbol("sec2")),
                           xd, phid, x, sp.Symbol("sec2")).coeffs(), cs, dict=True)
    assert sol and all(not v.has(x, xd, phid) for v in sol[0].values())


@settings(max_examples=5)
@given(st.integers(1, 3), st.integers(0, 2))
def test_planted_cyclic_with_parameter(a, b):
    """A cyclic coordinate w with p_w = c a w_t + b x_t, c a parameter: found, proportional
    over the parameters to the planted momentum."""
    J = jn.JetSpace("x y w")
    x, y, w = J.q
    xd, yd, wd = J.qd
    c = sp.Symbol("c")
    L = ((1 + y**2) * xd**2 + yd**2 + c * a * wd**2 + 2 * b * xd * wd) / 2 - x**2
    s = jn.System(J, L, [yd - x * xd], [y])
    basis = jn.conserved_quantities(s, "chetaev", degree=1, coefficients=[1])
    pw = c * a * wd + b * xd
    assert any(sp.cancel(I / pw).free_symbols <= {c} for I in basis)
    for I in basis:
        assert _DI_numeric(s, "chetaev", I) < 1e-30


def test_dependent_coefficients_give_no_trivial_quantity():
    """sin(y)^2 + cos(y)^2 = 1 among the coefficient functions: neither the constant nor
    the identically vanishing combinations come back."""
    s = models.get("nonholonomic_particle")
    x, y, z = s.J.q
    xd, yd, _ = s.J.qd
    basis = jn.conserved_quantities(s, "chetaev", degree=1,
                                    coefficients=[1, sp.sin(y)**2, sp.cos(y)**2])
    assert len(basis) == 1
    assert sp.simplify(basis[0] / yd).is_number


def test_suslov_integrals_include_the_multipliers():
    """The Suslov multipliers are states: lambda_alpha + p_alpha of the Chaplygin disk
    (Zhao et al. (41a)) is among its Suslov integrals, and every one has D I = 0 (sympy's
    subs route)."""
    s = models.rolling_disk()
    basis = jn.conserved_quantities(s, "suslov", degree=1)
    lx, ly = s.equations("suslov").multipliers
    import numpy as np

    rng = random.Random(5)
    cands = [s.on_constraints(lam + p) for lam, p in zip((lx, ly), s.p_dependent)]
    exprs = [s.on_constraints(b) for b in basis] + cands
    syms = sorted(set().union(*(e.free_symbols for e in exprs)), key=str)
    rows = [[float(e.subs(pt)) for e in exprs] for pt in
            ({x: rng.uniform(0.3, 1.4) for x in syms} for _ in range(3 * len(exprs)))]
    M = np.array(rows)
    r0 = np.linalg.matrix_rank(M[:, :len(basis)], tol=1e-9)
    assert r0 == np.linalg.matrix_rank(M, tol=1e-9) == len(basis)      # in the span
    assert any(b.has(lx) for b in basis) and any(b.has(ly) for b in basis)
    for I in basis:
        assert _DI_numeric(s, "suslov", I, points=4) < 1e-30


def test_default_space_holds_the_coefficients_of_L():
    """The spherical pendulum's energy and p_phi = sin(th)**2 ph_t have the coefficient
    sin(th)**2 of L: the default search finds them (an empty answer claims none exists)."""
    J = jn.JetSpace("th ph")
    th, ph = J.q
    thd, phd = J.qd
    g = sp.Symbol("g")
    s = jn.System(J, (thd**2 + sp.sin(th)**2 * phd**2) / 2 + g * sp.cos(th))
    from jetnh.mechanics.integrals import functions_of_q

    assert sp.sin(th)**2 in functions_of_q(s)
    basis = jn.conserved_quantities(s, "chetaev", degree=1)
    assert _in_span(phd * sp.sin(th)**2, basis, [thd, phd, sp.sin(th), sp.cos(th)])
    for I in basis:
        assert _DI_numeric(s, "chetaev", I, points=3) < 1e-30
    J2 = jn.JetSpace("x y")
    x = J2.q[0]
    s2 = jn.System(J2, J2.qd[0]**2 / (2 * (1 + x**2)) + J2.qd[1]**2 / 2)
    assert 1 / (x**2 + 1) in functions_of_q(s2)
