"""Tests of jetnh.mechanics.equations: the equations of motion under each principle, by value.

Zhao et al. (2008), sections 3-5.  Every check compares jetnh's derivation with an
independent one (the Euler-Lagrange equations of L + lambda f, identity (19) assembled
from the parts, the closed forms of the paper's examples worked by hand), or evaluates
residuals numerically at random states on the constraint manifold (independent
velocities at random, dependent ones from ``System.phi``) in 30-digit arithmetic.
"""

from __future__ import annotations

import random
import signal
from contextlib import contextmanager

import pytest
import sympy as sp
from hypothesis import Phase, given, settings, strategies as st

import jetnh.strategies as jst
from jetnh import ConstraintError, JetSpace, LagrangianError, PrincipleError
from jetnh.mechanics.system import System
from jetnh.mechanics.equations import FORMS
from jetnh.models import rolling_disk
from numbers30 import f30, num

TOL = 1e-18          # residuals that are identically zero, at 30 digits
RTOL = 1e-10         # agreement between two routes to the same numbers

randoms = st.randoms(use_true_random=False)
affine_systems = jst.constrained_systems(min_n=2, max_n=4, affine=True)
any_systems = jst.systems(min_n=2, max_n=4)


# ------------------------------------------------------------------ numeric helpers


def manifold_state(system: System, rnd: random.Random, extra=(), params=None) -> dict:
    """t, q, independent velocities and ``extra`` symbols at random; dependent velocities
    from phi, so that the state lies on the constraint manifold."""
    J = system.J
    vals = dict(params or {})
    for s in (J.t,) + J.q + system.independent_velocities + tuple(extra):
        vals[s] = f30(rnd.uniform(-1, 1))
    for v, phi in system.phi.items():
        vals[v] = num(phi, vals)
    return vals


def with_accelerations(vals: dict, acc: dict) -> dict:
    """``vals`` extended by the numeric accelerations and multiplier rates."""
    out = dict(vals)
    out.update({a: num(e, vals) for a, e in acc.items()})
    return out


def assert_close(a, b, what="", rtol=RTOL):
    assert abs(a - b) <= rtol * max(1, abs(a), abs(b)), f"{what}: {a} != {b}"


def assert_small(a, what="", scale=1):
    assert abs(a) <= TOL * max(1, scale), f"{what}: residual {a}"


@contextmanager
def time_limit(seconds: float, what: str):
    """Fail (not hang) when the block takes longer than ``seconds`` (SIGALRM, main thread)."""
    def expire(signum, frame):
        raise AssertionError(f"{what} took longer than {seconds} s")
    old = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


# ------------------------------------------------------------------ vakonomic = EL of L + lambda f
def _el_of_composite(system: System, constraints, multipliers):
    J2 = system.J.with_fields([m.name for m in multipliers])
    F = system.L + sp.Add(*[m * f for m, f in zip(multipliers, constraints)])
    return J2.euler(F), J2.euler(F, wrt=multipliers)


@settings(max_examples=10)
@given(any_systems, randoms)
def test_vakonomic_equations_are_euler_lagrange_of_composite_lagrangian(system, rnd):
    for form, constraints in (("multiplier", system.constraints),
                              ("explicit", system.explicit_constraints)):
        eom = system.equations("vakonomic", form)
        lams = eom.multipliers
        assert len(lams) == system.k and len(eom.multiplier_rates) == system.k
        el_q, el_lam = _el_of_composite(system, constraints, lams)
        assert len(eom.expressions) == system.J.n
        for mine, theirs in zip(eom.expressions, el_q):
            assert sp.expand(mine - theirs) == 0
        # the Euler-Lagrange equations in the multipliers are the constraints themselves
        assert list(el_lam) == list(constraints)
        # and the Hoelder equations (22) are the same equations (paper convention)
        holder = system.equations("holder", form)
        for a, b in zip(holder.expressions, eom.expressions):
            assert sp.expand(a - b) == 0


# ------------------------------------------------------------------ forms vanish on accelerations
def _multiplier_form_reactions(system, eom, vals):
    """Chetaev's multiplier form [L]_s + nu_a df^a/dqdot^s: nu from the dependent rows."""
    rows = [eom.expressions[i] for i in system.dep_index]
    nus = eom.reactions
    M = sp.Matrix([[num(sp.diff(r, nu), vals) for nu in nus] for r in rows])
    b = sp.Matrix([num(r.xreplace({nu: 0 for nu in nus}), vals) for r in rows])
    sol = M.LUsolve(-b)
    return {nu: sol[i] for i, nu in enumerate(nus)}


@settings(max_examples=10)
@given(any_systems, randoms)
def test_every_form_vanishes_on_the_accelerations_of_its_principle(system, rnd):
    for principle, forms in FORMS.items():
        eoms = [system.equations(principle, form) for form in forms]
        lams = eoms[0].multipliers
        acc = eoms[0].accelerations()
        assert set(system.J.qdd) | set(eoms[0].multiplier_rates) == set(acc)
        for _ in range(2):
            vals = with_accelerations(manifold_state(system, rnd, extra=lams), acc)
            for eom in eoms:
                assert eom.multipliers == lams        # explicit constraints: shared lambdas
                if eom.form == "multiplier" and principle == "chetaev":
                    vals = {**vals, **_multiplier_form_reactions(system, eom, vals)}
                for i, e in enumerate(eom.expressions):
                    assert_small(num(e, vals), f"{principle} {eom.form} row {i}")


@settings(max_examples=10)
@given(any_systems, randoms)
def test_accelerations_satisfy_the_differentiated_constraints(system, rnd):
    J = system.J
    Df = [J.D(f) for f in system.constraints]
    for principle in FORMS:
        eom = system.equations(principle)
        acc = eom.accelerations()
        vals = with_accelerations(manifold_state(system, rnd, extra=eom.multipliers), acc)
        for a, e in enumerate(Df):
            assert_small(num(e, vals), f"{principle}: D f^{a}")


@st.composite
def _implicit_systems(draw):
    """Explicit random constraints times a positive factor g(q): f = g (qdot^a - phi^a)."""
    J, L, constraints, dependent = draw(jst.constrained_systems(min_n=2, max_n=3))
    w = draw(jst.jet_expressions(J, order=0, max_depth=1, with_time=False))
    g = 1 + w**2
    return (J, L, tuple(g * f for f in constraints), dependent), g


@settings(max_examples=8)
@given(_implicit_systems(), randoms)
def test_implicit_constraints_multiplier_form_rescales_the_multipliers(case, rnd):
    """With f = g f', the multiplier form (15) has lambda for f and the explicit forms have
    lambda' = g lambda for f': the same q-accelerations at corresponding multipliers, and
    each form vanishes on its own accelerations."""
    (J, L, constraints, dependent), g = case
    system = System(J, L, constraints, dependent=dependent)
    mult = system.equations("vakonomic", "multiplier")
    expl = system.equations("vakonomic", "embedded")
    lams = mult.multipliers
    acc_m, acc_e = mult.accelerations(), expl.accelerations()
    vals = manifold_state(system, rnd, extra=lams)
    vals_e = {**vals, **{lam: num(g * lam, vals) for lam in lams}}
    for a in J.qdd:
        assert_close(num(acc_m[a], vals), num(acc_e[a], vals_e), str(a))
    # rates: lambda'_t = D(g) lambda + g lambda_t
    full = with_accelerations(vals, acc_m)
    for lam, rate in zip(lams, mult.multiplier_rates):
        expected = num(J.D(g) * lam + g * rate, full)
        assert_close(num(acc_e[rate], vals_e), expected, str(rate))
    for e in mult.expressions:
        assert_small(num(e, full))


# ------------------------------------------------------------------ identity (19)
@settings(max_examples=10)
@given(any_systems, randoms)
def test_identity_19_on_the_constraint_manifold(system, rnd):
    """[L]_mu + Phi^a_mu [L]_a = [L~]_mu + Phi^a_mu dL~/dq^a + p_a T^a_mu, on the manifold
    (q_t^a = phi^a and q_tt^a = D phi^a)."""
    J = system.J
    EL = J.euler(system.L)
    Lt = system.L_tilde
    ELt = J.euler(Lt, wrt=system.independent)
    Phi, T, p = system.Phi, system.T(on_constraints=False), system.p_dependent
    vals = manifold_state(system, rnd, extra=J.jets(2, system.independent))
    for a, qa in enumerate(system.dependent):
        vals[J.jet(qa, 2)] = num(J.D(system.phi[J.jet(qa, 1)]), vals)
    for m, qm in enumerate(system.independent):
        lhs = EL[J.q.index(qm)] + sp.Add(*[Phi[a, m] * EL[i]
                                            for a, i in enumerate(system.dep_index)])
        rhs = ELt[m] + sp.Add(*[Phi[a, m] * sp.diff(Lt, qa) + p[a] * T[a, m]
                                for a, qa in enumerate(system.dependent)])
        assert_close(num(lhs, vals), num(rhs, vals), f"(19) for {qm}", rtol=1e-20)


# ------------------------------------------------------------------ integrable constraints
@st.composite
def _holonomic_systems(draw, polynomial=False):
    """Velocity constraints D g^a = 0 from holonomic g^a(t, q) = 0, one per dependent
    coordinate: g^a = (1 + w^2)(q^a + c sin q^a) + h(t, q^mu, earlier q^b), |c| <= 1/2,
    so dg^a/dq^a > 0 and the dependent block of df/dqdot is triangular and invertible."""
    J = draw(jst.jet_spaces(min_n=2, max_n=4))
    L = draw(jst.lagrangians(J))
    m = draw(st.integers(1, J.n - 1))
    dependent = tuple(draw(st.permutations(J.q))[:m])
    independent = tuple(s for s in J.q if s not in dependent)
    def small(of, max_depth):
        if polynomial:
            return jst.polynomials(J, order=0, of=of)
        return jst.jet_expressions(J, order=0, max_depth=max_depth, of=of)

    constraints = []
    for a, qa in enumerate(dependent):
        w = draw(small(of=independent, max_depth=1))
        h = draw(small(of=independent + dependent[:a], max_depth=2))
        c = draw(st.sampled_from([0, sp.Rational(1, 2), -sp.Rational(1, 3)]))
        g = (1 + w**2) * (qa + c * sp.sin(qa)) + h
        constraints.append(J.D(g))
    return System(J, L, constraints, dependent=dependent)


@settings(max_examples=6, phases=[Phase.explicit, Phase.reuse, Phase.generate])
@given(_holonomic_systems(), randoms)
def test_integrable_constraints_make_all_principles_coincide(system, rnd):
    """For f = D g: [f]_s = d(Dg)/dq^s - D(dg/dq^s) = 0, so the vakonomic equations (15)
    reduce to [L]_s = lambda_t dg/dq^s, the holonomic equations with multiplier lambda_t:
    their q-accelerations do not depend on lambda and equal Chetaev's.  Suslov's (31b)
    differs from Chetaev's Voronets form by p_a T^a_mu, and T = 0 on the manifold."""
    J = system.J
    T = system.T()
    with time_limit(60, "deriving the accelerations"):
        chet = system.equations("chetaev").accelerations()
        others = [system.equations(p, f) for p, f in
                  (("vakonomic", "multiplier"), ("vakonomic", "embedded"),
                   ("holder", "multiplier"), ("suslov", "embedded"))]
        for eom in others:
            eom.accelerations()
    lams = others[0].multipliers
    for _ in range(2):
        vals = manifold_state(system, rnd, extra=lams + J.qdd)
        for f in system.constraints:
            for e in J.euler(f):
                assert_small(num(e, vals), "[f]_s")
        for e in T:
            assert_small(num(e, vals), "T on the manifold")
        ref = {a: num(chet[a], vals) for a in J.qdd}
        for eom in others:
            acc = eom.accelerations()
            for a in J.qdd:
                assert_close(num(acc[a], vals), ref[a], f"{eom.principle} {eom.form} {a}")


def test_accelerations_of_a_holonomic_four_coordinate_system_take_no_minutes():
    """Regression: the small linear solves must not expand their entries.  With sympy's
    default dotprodsimp, the 3x3 Berkowitz determinant of the reduced mass matrix of this
    system ran for minutes; without it, under a second."""
    J = JetSpace("q1 q2 q3 q4")
    q1, q2, q3, q4 = J.q
    t = J.t
    L = (3 * J.qd[0]**2 / 2 + J.qd[1]**2 * (q2**2 / 2 + 1) / 2 - 3 * J.qd[1] / 2
         + J.qd[2]**2 / 2 + J.qd[3]**2)
    g = ((1 + (q2**2 / 3 + q2 - q3 - 3)**2) * (q1 - sp.sin(q1) / 3) + 2 * q3 * q4
         + 1 / (1 + q4**4 * t**4))
    system = System(J, L, [J.D(g)], dependent=[q1])
    with time_limit(60, "the Chetaev accelerations"):
        acc = system.equations("chetaev").accelerations()
    rnd = random.Random(4)
    vals = with_accelerations(manifold_state(system, rnd), acc)
    assert_small(num(J.D(J.D(g)), vals), "D^2 g")


@settings(max_examples=6)
@given(_holonomic_systems(polynomial=True))
def test_time_derivatives_of_holonomic_constraints_are_integrable(system):
    assert system.is_integrable()


# ------------------------------------------------------------------ the split
@st.composite
def _two_splits(draw):
    """An affine system and a second split: the dependent q^a of one constraint swapped for
    an independent q^mu whose coefficient in that constraint is set to a nonzero constant
    -c (so that both splits are regular everywhere)."""
    J, L, constraints, dependent = draw(affine_systems)
    a = draw(st.integers(0, len(constraints) - 1))
    mu = draw(st.sampled_from([q for q in J.q if q not in dependent]))
    c = draw(st.sampled_from([1, -1, 2, sp.Rational(1, 2), -sp.Rational(3, 2)]))
    v = J.jet(mu, 1)
    constraints = list(constraints)
    constraints[a] = constraints[a] - sp.diff(constraints[a], v) * v - c * v
    system = System(J, L, constraints, dependent=dependent)
    other = list(dependent)
    other[a] = mu
    return system, system.with_split(other)


@settings(max_examples=10)
@given(_two_splits(), randoms)
def test_chetaev_accelerations_do_not_depend_on_the_split(case, rnd):
    s1, s2 = case
    a1 = s1.equations("chetaev").accelerations()
    a2 = s2.equations("chetaev").accelerations()
    for _ in range(2):
        vals = manifold_state(s1, rnd)
        for a in s1.J.qdd:
            assert_close(num(a1[a], vals), num(a2[a], vals), str(a))


@settings(max_examples=10)
@given(_two_splits(), randoms)
def test_vakonomic_split_change_maps_the_multipliers(case, rnd):
    """The explicit constraints of two splits differ by an invertible matrix:
    f'_(2) = A2^-1 f'_(1) with A2 = df'_(1)/dqdot^(dependent of split 2).  Then
    lambda_(1) . f'_(1) = lambda_(2) . f'_(2) for lambda_(2) = A2^T lambda_(1): the
    vakonomic equations of the two splits are the same equations in renamed multipliers.
    So the q-accelerations agree at corresponding multipliers, and the rates follow
    lambda_(2)_t = D(A2^T) lambda_(1) + A2^T lambda_(1)_t; at *equal* multiplier values they
    differ in general (tested on the rolling disk below)."""
    s1, s2 = case
    J = s1.J
    assert s1.constraints == s1.explicit_constraints
    e1, e2 = s1.equations("vakonomic", "embedded"), s2.equations("vakonomic", "embedded")
    acc1, acc2 = e1.accelerations(), e2.accelerations()
    N = s2.jacobian_dependent.T                     # lambda_(2) = N lambda_(1)
    lam1, lam2 = sp.Matrix(e1.multipliers), sp.Matrix(e2.multipliers)
    rate1, rate2 = e1.multiplier_rates, e2.multiplier_rates
    lam2_of_1 = N * lam1
    rate2_of_1 = N.applyfunc(J.D) * lam1 + N * sp.Matrix(rate1)
    # the multiplier form keeps the constraints as given: the same equations, renamed
    m2 = s2.equations("vakonomic", "multiplier")
    rename = dict(zip(m2.multipliers + m2.multiplier_rates, e1.multipliers + rate1))
    macc2 = m2.accelerations()
    for _ in range(2):
        vals1 = with_accelerations(manifold_state(s1, rnd, extra=e1.multipliers), acc1)
        vals2 = {**vals1, **{l2: num(e, vals1) for l2, e in zip(lam2, lam2_of_1)}}
        for a in J.qdd:
            assert_close(num(acc2[a], vals2), vals1[a], f"{a}")
        for r2, e in zip(rate2, rate2_of_1):
            assert_close(num(acc2[r2], vals2), num(e, vals1), f"{r2}")
        for key, e in macc2.items():
            assert_close(num(e.xreplace(rename), vals1), vals1[rename.get(key, key)], f"{key}")


@settings(max_examples=10)
@given(any_systems, randoms)
def test_suslov_q_accelerations_are_vakonomic_ones_at_minus_p(system, rnd):
    """(32): at lambda_a = -p_a the vakonomic embedded equations (20) become Suslov's (31),
    q-accelerations and multiplier rates alike (for the multipliers of the split's explicit
    constraints)."""
    vak = system.equations("vakonomic", "embedded")
    sus = system.equations("suslov", "embedded")
    av, asus = vak.accelerations(), sus.accelerations()
    assert vak.multipliers == sus.multipliers
    for _ in range(2):
        vals = manifold_state(system, rnd, extra=sus.multipliers)
        at_p = {**vals, **{lam: -num(p, vals) for lam, p in zip(vak.multipliers,
                                                                  system.p_dependent)}}
        for a in system.J.qdd + vak.multiplier_rates:
            # Suslov's accelerations do not depend on the multipliers at all
            assert_close(num(asus[a], vals), num(av[a], at_p), str(a))


# ------------------------------------------------------------------ Example 1: rolling disk
R, I1, I2 = sp.symbols("R I1 I2")     # the parameters of models.rolling_disk
C1, C2 = sp.symbols("C1 C2")


def _zero(expr) -> bool:
    return sp.simplify(expr) == 0


def test_example_1_suslov_gives_41():
    system = rolling_disk()
    J = system.J
    xd, yd = J.qd[:2]
    xtt, ytt, phitt, psitt = J.qdd
    eom = system.equations("suslov", "embedded")
    lx, ly = eom.multipliers
    lxt, lyt = eom.multiplier_rates
    rows = [system.on_constraints(e) for e in eom.expressions]
    # (38a) here: lambda_x_t = -x'', lambda_y_t = -y''
    assert _zero(rows[0] - (-lxt - xtt)) and _zero(rows[1] - (-lyt - ytt))
    # integrated, (41a): lambda = -dL/dqdot^alpha + C solves them
    sol = {lxt: J.D(-sp.diff(system.L, xd) + C1), lyt: J.D(-sp.diff(system.L, yd) + C2)}
    assert rows[0].xreplace(sol) == 0 and rows[1].xreplace(sol) == 0
    # (41b): (R^2 + I1) phi'' = 0, I2 psi'' = 0
    assert _zero(rows[2] + (R**2 + I1) * phitt)
    assert _zero(rows[3] + I2 * psitt)
    acc = system.equations("suslov").accelerations()
    assert _zero(system.on_constraints(acc[phitt])) and _zero(system.on_constraints(acc[psitt]))


def _disk_vakonomic_with_constants():
    """The embedded vakonomic equations (37) of the disk with (42a) substituted:
    lambda_x = -x' + C1, lambda_y = -y' + C2."""
    system = rolling_disk()
    J = system.J
    xd, yd = J.qd[:2]
    eom = system.equations("vakonomic", "embedded")
    lx, ly = eom.multipliers
    sub = {lx: -xd + C1, ly: -yd + C2}
    return system, eom, sub


def test_example_1_vakonomic_gives_jetnh_42():
    """jetnh's (42): lambda_t = -x'' as in (41a), and with lambda = -p + C,
    (R^2 + I1) phi'' + R psi' (C1 sin psi - C2 cos psi) = 0,
    I2 psi'' - R phi' (C1 sin psi - C2 cos psi) = 0."""
    system, eom, sub = _disk_vakonomic_with_constants()
    J = system.J
    psi = J.q[3]
    phid, psid = J.qd[2:]
    xtt, ytt, phitt, psitt = J.qdd
    lxt, lyt = eom.multiplier_rates
    rows = [system.on_constraints(e.xreplace(sub)) for e in eom.expressions]
    assert _zero(rows[0] - (-lxt - xtt)) and _zero(rows[1] - (-lyt - ytt))
    S = C1 * sp.sin(psi) - C2 * sp.cos(psi)
    assert _zero(rows[2] + (R**2 + I1) * phitt + R * psid * S)
    assert _zero(rows[3] + I2 * psitt - R * phid * S)
    # the same from accelerations(): the rates are -x'', -y'' and phi'', psi'' as above
    acc = eom.accelerations()
    on = lambda e: system.on_constraints(e.xreplace(sub))  # noqa: E731
    assert _zero(on(acc[phitt]) + R * psid * S / (R**2 + I1))
    assert _zero(on(acc[psitt]) - R * phid * S / I2)
    assert _zero(on(acc[lxt] + acc[xtt])) and _zero(on(acc[lyt] + acc[ytt]))
    # with C1 = C2 = 0 they are Suslov's (41b), as the paper says
    zero_c = {C1: 0, C2: 0}
    assert _zero(rows[2].xreplace(zero_c) + (R**2 + I1) * phitt)
    assert _zero(rows[3].xreplace(zero_c) + I2 * psitt)


def test_example_1_printed_42b_does_not_follow():
    """The printed (42b), (R^2+I1) phi'' - R (C1 sin phi - C2 cos phi) phi' = 0 and
    I2 psi'' + R (C1 sin phi - C2 cos phi) psi' = 0, fails on jetnh's solutions, and so does
    its most charitable reading with psi for phi inside sin, cos (the velocity factors
    phi', psi' are swapped as well, besides the sign)."""
    system, eom, sub = _disk_vakonomic_with_constants()
    J = system.J
    phi, psi = J.q[2:]
    phid, psid = J.qd[2:]
    phitt, psitt = J.qdd[2:]
    acc = eom.accelerations()
    sol = {phitt: system.on_constraints(acc[phitt].xreplace(sub)),
           psitt: system.on_constraints(acc[psitt].xreplace(sub))}
    rnd = random.Random(42)
    vals = {s: f30(rnd.uniform(0.3, 1.3)) for s in (R, I1, I2, C1, C2, phi, psi, phid, psid)}
    for angle in (phi, psi):
        S = C1 * sp.sin(angle) - C2 * sp.cos(angle)
        printed = [(R**2 + I1) * phitt - R * S * phid, I2 * psitt + R * S * psid]
        for e in printed:
            assert abs(num(e.xreplace(sol), vals)) > 1e-3


# ------------------------------------------------------------------ Example 2: Appell-Hamel
m_, g_, a_, b_ = sp.symbols("m g a b", positive=True)


def appell_hamel() -> System:
    """Example 2: L = m/2 (x'^2 + y'^2 + z'^2) - m g z, z' = (b/a) sqrt(x'^2 + y'^2)."""
    J = JetSpace("x y z")
    xd, yd, zd = J.qd
    L = m_ * (xd**2 + yd**2 + zd**2) / 2 - m_ * g_ * J.q[2]
    return System(J, L, [zd - b_ / a_ * sp.sqrt(xd**2 + yd**2)], dependent=["z"])


def test_example_2_suslov_gives_43():
    system = appell_hamel()
    J = system.J
    xd, yd, _ = J.qd
    xtt, ytt, ztt = J.qdd
    eom = system.equations("suslov", "embedded")
    lzt, = eom.multiplier_rates
    s = sp.sqrt(xd**2 + yd**2)
    K = 1 + b_**2 / a_**2
    rows = [system.on_constraints(e) for e in eom.expressions]
    assert _zero(rows[0] + (m_ * g_ + m_ * ztt + lzt))                       # (43c)
    assert _zero(rows[1] + m_ * (K * xtt + b_ * g_ / a_ * xd / s))           # (43a)
    assert _zero(rows[2] + m_ * (K * ytt + b_ * g_ / a_ * yd / s))           # (43b)


def _appell_hamel_vakonomic():
    system = appell_hamel()
    J = system.J
    xd, yd, _ = J.qd
    xtt, ytt, _ = J.qdd
    eom = system.equations("vakonomic", "embedded")
    lz, = eom.multipliers
    s = sp.sqrt(xd**2 + yd**2)
    W = xtt * yd - xd * ytt
    return system, eom, lz, s, W


def test_example_2_vakonomic_gives_jetnh_44():
    """jetnh's (44): with K = 1 + b^2/a^2, s = sqrt(x'^2 + y'^2), W = x'' y' - x' y'',
    -m (K x'' + (b g/a) x'/s) + (b/a)(m (b/a) s + lambda_z) y' W / s^3 = 0,
    -m (K y'' + (b g/a) y'/s) - (b/a)(m (b/a) s + lambda_z) x' W / s^3 = 0,
    m g + m z'' + lambda_z' = 0 (= printed (44c))."""
    system, eom, lz, s, W = _appell_hamel_vakonomic()
    J = system.J
    xd, yd, _ = J.qd
    xtt, ytt, ztt = J.qdd
    lzt, = eom.multiplier_rates
    K = 1 + b_**2 / a_**2
    coef = b_ / a_ * (m_ * b_ / a_ * s + lz)
    rows = [system.on_constraints(e) for e in eom.expressions]
    assert _zero(rows[0] + (m_ * g_ + m_ * ztt + lzt))
    assert _zero(rows[1] - (-m_ * (K * xtt + b_ * g_ / a_ * xd / s) + coef * yd * W / s**3))
    assert _zero(rows[2] - (-m_ * (K * ytt + b_ * g_ / a_ * yd / s) - coef * xd * W / s**3))


def test_example_2_printed_44_is_not_jetnh_44_but_the_conclusion_holds():
    """Printed (44a) has (m (b/a) s + lambda_z) y' W / s^3 where the derivation gives
    -(b/(a m)) (m (b/a) s + lambda_z) y' W / s^3 (after dividing by -m): not a multiple of
    the derived equation.  Its conclusion holds all the same: on jetnh's vakonomic
    solutions W = 0 and the q-accelerations are Suslov's (43), except on the branch
    lambda_z = (a m / b) s where the (x'', y'') block is singular."""
    system, eom, lz, s, W = _appell_hamel_vakonomic()
    J = system.J
    xd, yd, _ = J.qd
    xtt, ytt, ztt = J.qdd
    K = 1 + b_**2 / a_**2
    rows = [system.on_constraints(e) for e in eom.expressions]
    printed_a = K * xtt + b_ * g_ / a_ * xd / s + (m_ * b_ / a_ * s + lz) * yd * W / s**3
    corrected_a = (K * xtt + b_ * g_ / a_ * xd / s
                   - b_ / (a_ * m_) * (m_ * b_ / a_ * s + lz) * yd * W / s**3)
    assert _zero(rows[1] + m_ * corrected_a)
    rnd = random.Random(44)
    vals = {sym: f30(rnd.uniform(0.3, 1.3)) for sym in (m_, g_, a_, b_, lz, xd, yd, xtt, ytt)}
    # printed (44a) is not (44a derived) / (-m): the difference does not vanish
    assert abs(num(printed_a + rows[1] / m_, vals)) > 1e-3
    # the conclusion: W = 0 and the same q-accelerations as Suslov
    vak = eom.accelerations()
    sus = system.equations("suslov", "embedded").accelerations()
    for _ in range(3):
        state = manifold_state(system, rnd, extra=(lz,), params={
            sym: f30(rnd.uniform(0.5, 2)) for sym in (m_, g_, a_, b_)})
        full = with_accelerations(state, vak)
        assert_small(num(W, full), "W")
        for q in J.qdd:
            assert_close(full[q], num(sus[q], state), str(q))
    # the exceptional branch: det of the (x'', y'') block of the derived rows
    block = sp.Matrix(rows[1:]).jacobian([xtt, ytt])
    det = sp.factor(sp.simplify(block.det()))
    assert _zero(det.xreplace({lz: a_ * m_ / b_ * s}))
    assert not _zero(det.xreplace({lz: 0}))


# ------------------------------------------------------------------ bad input
def test_bad_input_gets_the_right_exception():
    J = JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    L = (xd**2 + yd**2 + zd**2) / 2
    f = yd - z * xd
    with pytest.raises(ConstraintError, match="dependent"):                   # f, 2f
        System(J, L, [f, 2 * f])
    with pytest.raises(ConstraintError, match="cannot be solved"):           # no y' in it
        System(J, L, [xd - z * zd], dependent=[y])
    with pytest.raises(ConstraintError, match="not a coordinate"):
        System(J, L, [f], dependent=["w"])
    with pytest.raises(ConstraintError, match="one per constraint"):
        System(J, L, [f], dependent=[x, y])
    with pytest.raises(ConstraintError, match="repeat"):
        System(J, L, [f, xd - zd], dependent=[y, y])
    assert System(J, L, [y - z * x]).holonomic == (y - z * x,)          # no velocity
    with pytest.raises(ConstraintError, match="no freedom"):
        System(J, L, [xd, yd, zd])
    system = System(J, L, [f], dependent=[y])
    with pytest.raises(PrincipleError, match="unknown principle"):
        system.equations("hamilton")
    with pytest.raises(PrincipleError, match="forms"):
        system.equations("suslov", "explicit")
    with pytest.raises(PrincipleError, match="forms"):
        system.equations("chetaev", "embedded")
    with pytest.raises(PrincipleError, match="convention"):
        system.equations("vakonomic", convention="lagrange")
    # Chetaev has no multiplier states: its reactions are algebraic
    eom = system.equations("chetaev", "multiplier")
    assert eom.multipliers == () and eom.multiplier_rates == () and len(eom.reactions) == 1


def test_singular_lagrangian_refused_when_accelerations_are_asked():
    J = JetSpace("x y")
    xd, yd = J.qd
    system = System(J, (xd + yd)**2 / 2)                     # Hessian [[1, 1], [1, 1]]
    eom = system.equations("chetaev")                        # deriving is fine
    with pytest.raises(LagrangianError, match="singular"):
        eom.accelerations()
    J3 = JetSpace("x y z")
    xd, yd, zd = J3.qd
    # z' = x (x' + y'): the reduced Hessian P^T M P = (1 + x^2) [[1, 1], [1, 1]] is singular
    system = System(J3, (xd + yd)**2 / 2 + zd**2 / 2, [zd - J3.q[0] * (xd + yd)],
                    dependent=["z"])
    for principle in FORMS:
        with pytest.raises(LagrangianError):
            system.equations(principle).accelerations()


def test_lagrangian_singular_only_off_the_constraint_distribution_is_accepted():
    """L = (x'^2 + z'^2)/2 is singular in y', but y' = z x' fixes y': the reduced Hessian
    P^T M P = I is regular and every principle determines the accelerations (jetnh first
    refused it, checking the full Hessian; fixed by checking the reduced one)."""
    J = JetSpace("x y z")
    xd, yd, zd = J.qd
    system = System(J, (xd**2 + zd**2) / 2, [yd - J.q[2] * xd], dependent=["y"])
    for principle in FORMS:
        eom = system.equations(principle)
        acc = eom.accelerations()
        assert set(acc) == set(J.qdd) | set(eom.multiplier_rates)
    # Chetaev: x'' = z'' = 0; Suslov too (it is vakonomic at lambda_y = -p_y = 0, (32))
    for principle in ("chetaev", "suslov"):
        acc = system.equations(principle).accelerations()
        assert acc[J.qdd[0]] == 0 and acc[J.qdd[2]] == 0


def test_split_dependence_on_the_rolling_disk():
    """Splits (x, y) and (phi, y) of the disk: Chetaev agrees; vakonomic agrees only under
    lambda_(2) = A2^T lambda_(1), not at equal multiplier values; Suslov's q-accelerations
    depend on the split (they are the vakonomic ones at lambda = -p of the split's own
    dependent momenta, (32), and -p_(2) != A2^T (-p_(1))), so (26) is not without loss of
    generality."""
    s1 = rolling_disk()
    s2 = s1.with_split(["phi", "y"])
    J = s1.J
    rnd = random.Random(26)
    params = {R: f30(1.3), I1: f30(0.7), I2: f30(0.4)}
    vals = manifold_state(s1, rnd, params=params)
    # keep away from cos(psi) = 0, where split 2 is singular
    assert abs(sp.cos(vals[J.q[3]])) > 0.1

    def q_acc(system, principle, lam_values=()):
        eom = system.equations(principle, "embedded" if principle != "chetaev" else None)
        acc = eom.accelerations()
        # Suslov's accelerations do not depend on the multipliers: any values do
        v = {**vals, **dict(zip(eom.multipliers, lam_values or [f30(0.5)] * 2))}
        return [num(acc[a], v) for a in J.qdd]

    c1, c2 = q_acc(s1, "chetaev"), q_acc(s2, "chetaev")
    for a, b in zip(c1, c2):
        assert_close(a, b)
    lam1 = [f30(0.3), f30(-0.2)]
    N = s2.jacobian_dependent.T.xreplace(vals)
    lam2 = list(N * sp.Matrix(lam1))
    v1, v2, v2_naive = (q_acc(s1, "vakonomic", lam1), q_acc(s2, "vakonomic", lam2),
                        q_acc(s2, "vakonomic", lam1))
    for a, b in zip(v1, v2):
        assert_close(a, b)
    assert max(abs(a - b) for a, b in zip(v1, v2_naive)) > 1e-3
    u1, u2 = q_acc(s1, "suslov"), q_acc(s2, "suslov")
    for a, b in zip(u1, c1):                 # split (x, y): Chaplygin, Suslov = Chetaev
        assert_close(a, b)
    assert max(abs(a - b) for a, b in zip(u1, u2)) > 1e-3
