"""conserved_quantities, noether_symmetries, lie_symmetries: the whole space the contract
names is searched (all velocities modulo the constraints, the functions of q the system
contains), the answer is a basis modulo the constraints, budgets are checked before
anything is built, and the coefficients are checked (never parsed from strings)."""

import math
import subprocess
import sys
import textwrap

import pytest
import sympy as sp

import jetnh as jn
from jetnh import models
from jetnh.errors import ArgumentError

pytestmark = pytest.mark.filterwarnings("ignore::jetnh.JetnhWarning")


def _restricted(sysm, exprs):
    """exprs on the constraint manifold, expanded (exact)."""
    return [sp.expand(sysm.on_constraints(e)) for e in exprs]


def _values(sysm, exprs, count, params=None):
    """The restricted exprs at ``count`` random points (40 digits): rows."""
    import random
    r = _restricted(sysm, exprs)
    syms = sorted(set().union(*(e.free_symbols for e in r)), key=str)
    rng = random.Random(5)
    rows = []
    for _ in range(count):
        p = {v: sp.Rational(rng.randint(-90, 90), rng.randint(41, 47)) for v in syms}
        p.update({v: sp.Rational(rng.randint(4, 16), 8) for v in sysm.parameters})
        rows.append([sp.N(e.xreplace(p), 40) for e in r])
    return sp.Matrix(rows)


def _rank(M):
    import mpmath
    with mpmath.workdps(40):
        sv = mpmath.svd_r(mpmath.matrix(M.tolist()), compute_uv=False)
        return sum(1 for x in sv if abs(x) > mpmath.mpf(10) ** -25 * max(1, abs(sv[0])))


def _in_span_mod(sysm, expr, basis):
    """expr is a constant combination of basis modulo the constraints (40 digits at
    random points: the rank does not grow when expr joins)."""
    M = _values(sysm, [*basis, expr], len(basis) + 8)
    return _rank(M[:, :len(basis)]) == _rank(M)


def _independent_mod(sysm, basis):
    """No combination of basis vanishes on the constraint manifold (at random points)."""
    return _rank(_values(sysm, basis, len(basis) + 8)) == len(basis)


def knife_on_incline():
    """A knife edge on an inclined plane, constraint ydot = tan(theta) xdot (g sin(alpha)
    = 1, unit mass and inertia): the energy restricted to the constraint is
    (1 + tan^2 theta) xdot^2/2 + thetadot^2/2 + x, not polynomial in the independent
    velocities with coefficients in the span of t, q, tan(theta)."""
    J = jn.JetSpace("x y theta")
    x, y, th = J.q
    xd, yd, thd = J.qd
    L = (xd**2 + yd**2) / 2 + thd**2 / 2 - x
    return jn.System(J, L, constraints=[yd - sp.tan(th) * xd], dependent=[y])


def test_knife_edge_energy_found_by_default():
    s = knife_on_incline()
    x, y, th = s.J.q
    xd, yd, thd = s.J.qd
    basis = jn.conserved_quantities(s, "chetaev")
    energy = (xd**2 + yd**2) / 2 + thd**2 / 2 + x
    assert _in_span_mod(s, energy, basis)
    assert _in_span_mod(s, thd, basis) and _in_span_mod(s, th - s.J.t * thd, basis)
    assert not _in_span_mod(s, xd, basis)
    for I in basis:
        assert sp.cancel(s.on_constraints(I)) != 0
    assert _independent_mod(s, basis)


def test_chaplygin_sleigh_energy_with_trigonometric_coefficients():
    s = models.get("chaplygin_sleigh")
    x, y, th = s.J.q
    m, I, a = sp.symbols("m I a")
    basis = jn.conserved_quantities(s, "chetaev", degree=2,
                                    coefficients=[1, sp.sin(th), sp.cos(th)])
    assert basis, "the sleigh's energy is in this space"
    E = s.L                                          # no potential: the energy is L
    assert _in_span_mod(s, E, basis)
    assert _independent_mod(s, basis)


def test_trivial_quantities_are_never_returned():
    """z_t - y x_t is conserved trivially (it vanishes on the constraint): never in the
    answer; the basis is independent modulo the constraint."""
    s = models.get("nonholonomic_particle")
    x, y, z = s.J.q
    basis = jn.conserved_quantities(s, "chetaev", degree=1, coefficients=[1, y])
    for I in basis:
        assert sp.cancel(s.on_constraints(I)) != 0
    assert _independent_mod(s, basis)


def test_symmetries_search_the_functions_of_q():
    """The sleigh's rotation about the contact point needs sin and cos of theta: found
    by noether's default ansatz (xi_x = -y, xi_y = x is polynomial; the default adds
    the trigonometric functions and still finds the translations)."""
    s = models.get("chaplygin_sleigh")
    x, y, th = s.J.q
    syms = jn.noether_symmetries(s, "chetaev", degree=1)
    gens = [dict(g.xi) for g in syms]
    assert any(set(d) == {x} for d in gens) or any(set(d) <= {x, y} for d in gens)


@pytest.mark.parametrize("bad", [[None], [float("nan")], [sp.nan], [sp.oo], [object()],
                                 ["x"], [True], 3, "x", [sp.Symbol("zz")]])
def test_coefficients_checked(bad):
    s = models.get("nonholonomic_particle")
    for f in (jn.conserved_quantities, jn.noether_symmetries, jn.lie_symmetries):
        with pytest.raises(ArgumentError):
            f(s, "chetaev", 1, bad)


BUDGET_SCRIPT = textwrap.dedent("""
    import resource, sys
    resource.setrlimit(resource.RLIMIT_AS, (1_500_000_000, 1_500_000_000))
    import jetnh as jn
    from jetnh import models
    s = models.get("rolling_disk")
    for f in (jn.conserved_quantities, jn.noether_symmetries, jn.lie_symmetries):
        try:
            f(s, "chetaev", degree=40)
        except jn.JetnhError as exc:
            assert "over the budget" in str(exc), exc
        else:
            sys.exit(f"{f.__name__} accepted degree=40")
    print("refused")
""")


def test_budget_refuses_before_building():
    """degree=40: refused by the budget, within 1.5 GB of address space and a generous
    wall-clock bound (the child is killed otherwise), before any ansatz is built."""
    r = subprocess.run([sys.executable, "-c", BUDGET_SCRIPT], capture_output=True,
                       text=True, timeout=240)
    assert r.returncode == 0 and "refused" in r.stdout, r.stderr[-2000:]
