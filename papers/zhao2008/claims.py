"""Checks of the claims the paper makes in words (kind "claim")."""

from __future__ import annotations

import sympy as sp

from jetnh import JetSpace, System
from jetnh.mechanics.equations import chetaev_admissible, derive
from jetnh.mechanics.equivalence import compare
from jetnh.geometry.forms import Form, d, interior
from jetnh.mechanics.proof import is_zero
from jetnh.algebra.zero import vanishes
from jetnh.mechanics.variations import defect, euler_of_constraints, make

from .items import ERRATUM, NOT_CHECKABLE, VERIFIED, Outcome, eqs, item


def claim(label, printed):
    return item(label, kind="claim", printed=printed)


@claim("Sec. 1: conditions incompatible",
       r"\delta f^c = 0,\ [d,\delta] = 0,\ \frac{\partial f^c}{\partial\dot q^i}\delta q^i = 0"
       r"\ \text{cannot in general hold together}")
def _c_incompatible(ctx):
    s = ctx.disk
    h = make(s, "holder")
    eta = chetaev_admissible(s, h.eta)
    nonzero = not all(vanishes(x) for x in defect(s, eta, h.J))
    return Outcome(VERIFIED if nonzero else ERRATUM,
                   "For the rolling disk the defect [f]_s delta q^s is nonzero for Chetaev-"
                   "admissible delta q, so by (8) a Hoelder variation moves off the constraints: "
                   "the three conditions do not hold together.",
                   evidence=[f"defect nonzero on the Chetaev subspace (disk): {nonzero}"])


@claim("Sec. 1: Chetaev and vakonomic models differ",
       r"\text{Chetaev and vakonomic models are in general not equivalent for nonintegrable constraints}")
def _c_models(ctx):
    c = compare(ctx.disk, "chetaev", "vakonomic")
    return Outcome(VERIFIED if not c.identical else ERRATUM,
                   f"Rolling disk: {c}.", evidence=[str(c)])


@claim("After (11): (11) is weaker than [f]=0",
       r"\text{(11) is not equivalent to } [f^a]_\delta = 0 \text{ since the } \delta q^s "
       r"\text{ are not independent}")
def _c_defect(ctx):
    s = ctx.particle
    F = euler_of_constraints(s)
    nonzero_F = not all(vanishes(s.on_constraints(e)) for e in F)
    # eta in ker(df/dqdot) and ker([f]) exists at a generic point when n - k > k
    A = s.jacobian
    stacked = A.col_join(F)
    ker = len(s.J.q) - stacked.rank(simplify=False) > 0
    return Outcome(VERIFIED if nonzero_F and ker else ERRATUM,
                   "Nonholonomic particle zdot = y xdot: [f]_s != 0, yet Chetaev-admissible "
                   "variations with [f]_s delta q^s = 0 exist (the kernel of the stacked rows "
                   "df/dqdot, [f] is nonzero), so (11) can hold with [f] != 0.",
                   evidence=[f"[f] nonzero: {nonzero_F}", f"common kernel nonempty: {ker}"])


@claim("After (11): [f]=0 vs integrability",
       r"[f^a]_\delta = 0\ \text{is neither sufficient nor necessary for integrability}")
def _c_integrability(ctx):
    # not necessary: an integrable constraint with [f] != 0 on the constraints
    J = JetSpace("x y")
    x, y = J.q
    xd, yd = J.qd
    f = (1 + x**2) * (yd - 2 * x * xd)
    s = System(J, (xd**2 + yd**2) / 2, [f], [y])
    not_necessary = s.is_integrable() and not all(
        vanishes(s.on_constraints(e)) for e in euler_of_constraints(s))
    # sufficient when [f] = 0 identically: f is then affine, f = a_s qdot^s + b, and
    # [f]_s = 0 says exactly that omega = a_s dq^s + b dt is closed (generic a, b, n = 3)
    J3 = JetSpace("q1 q2 q3")
    t, q, qd = J3.t, J3.q, J3.qd
    a = [sp.Function(f"a{i}")(t, *q) for i in range(3)]
    b = sp.Function("b")(t, *q)
    f3 = sp.Add(*[a[i] * qd[i] for i in range(3)]) + b
    E = J3.euler(f3)
    omega = Form(J3, 1, {(q[i],): a[i] for i in range(3)}) + Form(J3, 1, {(t,): b})
    contracted = interior({t: 1, **dict(zip(q, qd))}, d(omega))
    closed_iff_null = all(is_zero(E[i] + contracted[(q[i],)]) for i in range(3))
    return Outcome(ERRATUM,
                   "Half true: 'not sufficient' fails when [f]_s = 0 holds identically. Not necessary: f = (1 + x^2)(ydot - 2x xdot) is integrable "
                   "(y = x^2 + c) but [f]_s != 0 on the constraints. Not sufficient is false if "
                   "[f]_s = 0 holds identically on J^1M: then d^2f/dqdot^2 = 0 (the coefficient "
                   "of qddot), so f = a_s qdot^s + b, and [f]_s is the contraction of d omega, "
                   "omega = a_s dq^s + b dt, with (1, qdot); [f] = 0 makes omega closed, "
                   "hence locally exact, omega = dg, and the constraint is g = const: "
                   "integrable (null-Lagrangian theorem). Only a reading of [f] = 0 on the "
                   "constraint manifold alone could keep the paper's statement; the text does "
                   "not say so.",
                   r"[f^a]_s \equiv 0 \Rightarrow f^a = \frac{d g^a}{dt}\ \text{(integrable)};"
                   r"\quad \text{integrable} \not\Rightarrow [f^a]_s = 0",
                   [f"integrable with [f] != 0: {not_necessary}",
                    f"[f]_s == -(i_V d omega)_s, V = d_t + qdot^s d_s (generic a, b): "
                    f"{closed_iff_null}"])


@claim("After (15): using (6) in (13)",
       r"\text{using (6) in (13) would give the equations of the unconstrained system}")
def _c_use6(ctx):
    s = ctx.implicit
    e = eqs(s, "vakonomic", "multiplier")
    J, lams = e.J, e.multipliers
    # replace lambda_a [f^a]_s eta^s by -lambda_a D(f_qdot eta) (6), integrate by parts:
    # +lambda_dot_a f_qdot eta; so E_s eta^s becomes [L]_s eta^s
    from jetnh.mechanics.variations import eta_symbols
    eta = eta_symbols(s.J)
    Jf = J
    A = s.jacobian
    integrand = sp.Add(*[e.expressions[i] * eta[i] for i in range(s.J.n)])
    fe = sp.Add(*[lams[a] * euler_of_constraints(s, Jf)[a, i] * eta[i]
                  for a in range(s.k) for i in range(s.J.n)])
    chet = [sp.Add(*[A[a, i] * eta[i] for i in range(s.J.n)]) for a in range(s.k)]
    after = integrand - fe + sp.Add(*[Jf.jet(lams[a], 1) * chet[a] for a in range(s.k)])
    free = Jf.euler(after, wrt=eta)
    ok = all(is_zero(free[i] - s.J.euler(s.L)[i]) for i in range(s.J.n))
    return Outcome(VERIFIED if ok else ERRATUM,
                   "Substituting (6) for lambda [f] delta q and integrating by parts cancels "
                   "every multiplier term: what remains is [L]_s = 0 (generic L, f).",
                   evidence=[f"result == [L]_s: {ok}"])


@claim("Sec. 3.2: Hoelder gives the vakonomic equations",
       r"\text{the Hoelder variation gives the vakonomic equations; (20) also holds under it}")
def _c_holder(ctx):
    c = compare(ctx.disk, "vakonomic", "holder")
    s = ctx.explicit
    same = all(is_zero(a - b) for a, b in zip(eqs(s, "holder", "embedded").expressions,
                                              eqs(s, "vakonomic", "embedded").expressions))
    return Outcome(VERIFIED if c.identical and same else ERRATUM,
                   "In the paper's convention (delta q^s independent after using only [d, delta] = "
                   "0) the Hoelder and vakonomic variations give identical equations. With the "
                   "Chetaev condition imposed (convention='imposed') they do not: jetnh then gets "
                   "P^T([L] + lambda [f]) = 0 with lambda undetermined.",
                   evidence=[str(c), f"embedded forms identical (generic): {same}"])


@claim("After (31): Chetaev condition in explicit form",
       r"\delta_s q^a = \frac{\partial \varphi^a}{\partial q^\beta}\delta_s q^\beta")
def _c_chetaev_explicit(ctx):
    s = ctx.explicit2
    v = make(s, "holder")
    chet = v.conditions["Chetaev condition"]
    derived_ok = all(is_zero(chet[a] - (v.eta[s.dep_index[a]] - sp.Add(*[
        s.Phi[a, m] * v.eta[i] for m, i in enumerate(s.ind_index)]))) for a in range(s.k))
    return Outcome(ERRATUM if derived_ok else VERIFIED,
                   "For f = qdot^alpha - phi^alpha the Chetaev condition df/dqdot^s delta q^s = 0 "
                   "reads delta q^alpha = (dphi^alpha/dqdot^mu) delta q^mu: the printed "
                   "dphi/dq^beta delta q^beta is a misprint (beta is a dependent index).",
                   r"\delta_S q^\alpha = \frac{\partial\varphi^\alpha}{\partial\dot q^\mu}\delta_S q^\mu",
                   [f"jetnh's Chetaev condition == corrected form (generic): {derived_ok}"])


@claim("Sec. 3.4: two independent sets",
       r"\text{vakonomic and Hoelder equations coincide; the comparison is (20) against (31)}")
def _c_two_sets(ctx):
    c1 = compare(ctx.disk, "vakonomic", "holder")
    c2 = compare(ctx.disk, "vakonomic", "suslov")
    ok = c1.identical and not c2.identical
    return Outcome(VERIFIED if ok else ERRATUM, "Disk: " + str(c1) + "; " + str(c2) + ".",
                   evidence=[str(c1), str(c2)])


def _ah_branch(ctx):
    """Example 2's vakonomic singular branch, derived: (Comparison, the branch as text,
    checks).  The branch is the root in lambda_z of the factor of ``compare``'s singular
    set that has lambda_z; on it jetnh's vakonomic rows (44) hold for a whole line of
    accelerations (any component across the velocity: the motion is not unique), and
    lambda_z - a m |v| / b is constant along every vakonomic motion, by the rows (so the
    branch is invariant)."""
    s = ctx.appell_hamel
    J = s.J
    c = compare(s, "vakonomic", "suslov")
    e = eqs(s, "vakonomic", "embedded")
    lam = e.multipliers[0]
    lam_t = e.J.jet(lam, 1)
    m, g, a, b = sp.symbols("m g a b")
    xd, yd = J.qd[0], J.qd[1]
    v = sp.sqrt(xd**2 + yd**2)
    facs = [f for f in c.singular if lam in f.free_symbols]
    roots = [r for f in facs for r in sp.solve(f, lam)]
    stated = a * m * v / b
    found = len(roots) == 1 and vanishes(roots[0] - stated)
    # on the branch: accelerations p (along the velocity) and w (across), z'' from D f = 0
    p_, w_ = sp.symbols("p_par w_perp")
    acc = {J.qdd[0]: (p_ * xd - w_ * yd) / v, J.qdd[1]: (p_ * yd + w_ * xd) / v}
    rows = [s.on_constraints(r, prolonged=True).xreplace(acc).xreplace({lam: stated})
            for r in e.expressions]
    (rate,) = sp.solve(rows[0], lam_t)                       # (44c)
    (par,) = sp.solve(xd * rows[1] + yd * rows[2], p_)        # the rows along the velocity
    free = all(vanishes(r.xreplace({lam_t: rate, p_: par}), s) for r in rows[1:])
    growth = rate - (m * a / b) * (xd * acc[J.qdd[0]] + yd * acc[J.qdd[1]]) / v
    invariant = vanishes(growth.xreplace({p_: par}), s)
    text = "lambda_z = a m sqrt(xdot^2 + ydot^2) / b"
    checks = [f"the singular factor's root is {text}: {found}",
              f"on it (44) holds for every acceleration across the velocity: {free}",
              f"lambda_z - a m |v| / b constant by (44), so the branch is invariant: {invariant}"]
    return c, text, found and free and invariant, checks


@claim("(32): necessary and sufficient",
       r"\lambda_\alpha = -\frac{\partial L}{\partial \dot q^\alpha}\ \text{is necessary and "
       r"sufficient for common solutions}")
def _c_32_iff(ctx):
    c, branch, ok, checks = _ah_branch(ctx)
    return Outcome(ERRATUM,
                   "Sufficient, not necessary: the equations differ by (p_alpha + lambda_alpha) T^alpha_mu "
                   "(proven in (32)), which vanishes for lambda = -p but also wherever T vanishes "
                   "along the motion; and lambda = -p gives common solutions only where the motion "
                   "keeps it, dL~/dq^alpha = 0 on the constraints (d/dt(lambda + p) = "
                   "dL~/dq^alpha on the branch, proven under (32)). Appell-Hamel: T^3_mu is "
                   "proportional to xddot ydot - xdot "
                   "yddot, zero on the motion, and jetnh finds: " + str(c) + ". So the "
                   "vakonomic and Suslov motions coincide for every lambda_z except on the "
                   f"invariant branch {branch}, where the vakonomic acceleration system is "
                   "singular and its motion not unique (jetnh derives the branch: "
                   f"{'yes' if ok else 'NO'}). Necessity holds only where T^alpha_mu has rank k "
                   "along the motion.",
                   r"(p_\alpha + \lambda_\alpha)T^\alpha_\mu = 0\ \text{(necessary and sufficient);}"
                   r"\ \lambda_\alpha = -p_\alpha\ \text{is sufficient where } \partial\tilde L/"
                   r"\partial q^\alpha = 0\text{. Appell-Hamel: common "
                   r"solutions for every } \lambda_z \ne a m\sqrt{\dot x^2+\dot y^2}/b",
                   [str(c), *checks, *_branch_witness(ctx)])


def _branch_witness(ctx) -> list:
    """The branch (32) is invariant for the disk, and not once a spring -k x^2/2 acts on
    its dependent x (dL~/dx = -k x): there vakonomic and Suslov agree at an instant only."""
    s = ctx.disk
    k = sp.Symbol("k")
    x = s.dependent[0]
    spring = System(s.J, s.L - k * x**2 / 2, list(s.constraints), dependent=list(s.dependent))
    c = compare(spring, "vakonomic", "suslov")
    return [f"disk: branch (32) invariant: "
            f"{compare(s, 'vakonomic', 'suslov').branch_invariant}",
            f"disk with a spring on x: same accelerations on the branch {c.on_branch_32}, "
            f"branch invariant {c.branch_invariant}"]


@claim("(32): Chaplygin systems satisfy it",
       r"\text{Chaplygin nonholonomic systems satisfy condition (32)}")
def _c_chaplygin(ctx):
    s = ctx.disk
    ok = True
    for principle in ("vakonomic", "suslov"):
        e = eqs(s, principle, "embedded")
        for a, i in enumerate(s.dep_index):
            # d/dt(lambda_alpha + p_alpha) along the equations (dependent rows)
            rate = e.J.jet(e.multipliers[a], 1) + s.J.D(s.p_dependent[a])
            ok &= vanishes(s.on_constraints(rate + e.expressions[a], prolonged=True))
    return Outcome(ERRATUM,
                   "Only on the branch C = 0: for Chaplygin systems lambda_alpha + p_alpha is "
                   "conserved, so (32) holds iff it holds initially. For Chaplygin systems (L and B free of q^alpha) both (20a) "
                   "and (31a) give d/dt(lambda_alpha + p_alpha) = 0, so lambda_alpha + p_alpha = "
                   "C_alpha is constant, and (32) holds exactly when C = 0 initially; the paper's "
                   "own Example 1 carries arbitrary C1, C2. jetnh checks the conservation law "
                   "on the disk.",
                   r"\text{Chaplygin: } \frac{d}{dt}(\lambda_\alpha + p_\alpha) = 0;\ (32)\ "
                   r"\text{holds iff } \lambda_\alpha(t_0) = -p_\alpha(t_0)",
                   [f"lambda + p conserved under both (disk): {ok}"])


@claim("Sec. 3.4: T = 0 gives equivalence",
       r"T^\mu_\alpha = 0\ \Rightarrow\ \text{the two sets are formally equivalent}")
def _c_T0(ctx):
    return Outcome(VERIFIED, "By the identity (20b) - (31b) = (p + lambda) T proven under (32). "
                   "(The printed T^mu_alpha has its indices exchanged; T^alpha_mu is meant.)")


@claim("After (38): lambda = +p",
       r"\lambda_\alpha = \frac{\partial L}{\partial \dot q^\alpha}\ \Rightarrow\ (37) \iff (38)")
def _c_38_sign(ctx):
    s = ctx.witness
    v = eqs(s, "vakonomic", "embedded")
    su = eqs(s, "suslov", "embedded")
    lam = v.multipliers
    rows = lambda sub: [s.on_constraints(a.xreplace(sub) - b, prolonged=True)  # noqa: E731
                        for a, b in zip(v.expressions[s.k:], su.expressions[s.k:])]
    plus = all(vanishes(r) for r in rows({lam[0]: s.p_dependent[0]}))
    minus = all(vanishes(r) for r in rows({lam[0]: -s.p_dependent[0]}))
    return Outcome(ERRATUM if minus and not plus else VERIFIED,
                   "Sign misprint: the affine equations coincide for lambda_alpha = -dL/dqdot^alpha, "
                   "as in (32), not +dL/dqdot^alpha (witness zdot = (y+z) xdot).",
                   r"\lambda_\alpha = -\frac{\partial L}{\partial\dot q^\alpha}",
                   [f"coincide for lambda = +p: {plus}", f"coincide for lambda = -p: {minus}"])


@claim("After (39): (39) gives equivalence",
       r"\text{when the integrability condition (39) holds the two sets are formally equivalent}")
def _c_39(ctx):
    J = JetSpace("x y z")
    x, y, z = J.q
    s = System(J, sum(v**2 for v in J.qd) / 2, [J.qd[2] - 2 * x * J.qd[0] - J.qd[1]], [z])
    integrable = s.is_integrable()
    c = compare(s, "vakonomic", "suslov")
    return Outcome(VERIFIED if integrable and c.identical else ERRATUM,
                   "With (39) read as the Frobenius condition, T vanishes identically and so does "
                   "(p + lambda) T. Integrable example zdot = 2x xdot + ydot: " + str(c) + ".",
                   evidence=[f"integrable: {integrable}", str(c)])


@claim("Example 1: B coefficients",
       r"B^3_{[1;2]} = -\tfrac12 (R\sin\psi)\dot\psi,\ B^4_{[1;2]} = \tfrac12(R\cos\psi)\dot\psi,"
       r"\ B^\alpha_{\rho;\beta} = 0")
def _c_ex1_B(ctx):
    s = ctx.disk
    from .items import B_antisym, B_d
    psi = s.J.q[3]
    R = sp.Symbol("R")
    vals = [sp.simplify(B_antisym(s, a, 1, 2)) for a in range(2)]
    ok = (sp.simplify(vals[0] + R * sp.sin(psi) / 2) == 0
          and sp.simplify(vals[1] - R * sp.cos(psi) / 2) == 0)
    zero = all(B_d(s, a, r, qb) == 0 for a in range(2) for r in range(3) for qb in s.dependent)
    return Outcome(ERRATUM if ok else VERIFIED,
                   "B^3_1 = R cos psi, B^4_1 = R sin psi, B^alpha_2 = 0 and B_{rho;beta} = 0 are "
                   "right, but B^alpha_{[1;2]} is a coefficient of q^0 = t, q^mu only: "
                   "B^3_{[1;2]} = -(R sin psi)/2, B^4_{[1;2]} = (R cos psi)/2, without the factor "
                   "psidot (which belongs to the contraction B_{[mu;rho]} qdot^rho).",
                   r"B^3_{[1;2]} = -\tfrac12 R\sin\psi,\quad B^4_{[1;2]} = \tfrac12 R\cos\psi",
                   [f"jetnh B_[1;2]: {vals}", f"B_rho;beta = 0: {zero}"])


@claim("Example 1: L~",
       r"\tilde L = \tfrac12 (R^2 + I_1)\dot\phi^2 + \tfrac12 I_2\dot\psi^2,\ "
       r"\partial\tilde L/\partial x = \partial\tilde L/\partial y = 0")
def _c_ex1_L(ctx):
    s = ctx.disk
    R, I1, I2 = sp.symbols("R I1 I2")
    phid, psid = s.J.qd[2], s.J.qd[3]
    ok = vanishes(s.L_tilde - ((R**2 + I1) * phid**2 + I2 * psid**2) / 2)
    ok &= all(sp.diff(s.L_tilde, q) == 0 for q in s.dependent)
    return Outcome(VERIFIED if ok else ERRATUM, "jetnh's embedded Lagrangian of the disk.",
                   evidence=[f"L~ as printed: {ok}"])


@claim("Example 1: equivalence for C = 0",
       r"C_1 = C_2 = 0\ \Rightarrow\ \text{(41) and (42) are equivalent}")
def _c_ex1_C0(ctx):
    c = compare(ctx.disk, "vakonomic", "suslov")
    return Outcome(VERIFIED if c.on_branch_32 and c.branch_invariant else ERRATUM,
                   "C = 0 is the branch (32), invariant for the disk (dL~/dx = dL~/dy = 0); "
                   "jetnh: " + str(c) + ". The simulations show the "
                   "paths part for C != 0 and coincide for C = 0.", evidence=[str(c)])


@claim("Example 2: intermediate quantities",
       r"[L]_x = -m\ddot x,\ [\tilde L]_x = -m(1 + b^2/a^2)\ddot x,\ \partial\tilde L/\partial z = "
       r"-mg,\ \partial L/\partial\dot z = m\frac{b}{a}\sqrt{\dot x^2+\dot y^2},\ \ldots")
def _c_ex2_values(ctx):
    s = ctx.appell_hamel
    J = s.J
    m, g, a, b = sp.symbols("m g a b")
    xd, yd = J.qd[0], J.qd[1]
    sq = sp.sqrt(xd**2 + yd**2)
    EL = J.euler(s.L)
    ELt = J.euler(s.L_tilde, wrt=s.independent)
    checks = [EL[0] + m * J.qdd[0], EL[1] + m * J.qdd[1], EL[2] + m * g + m * J.qdd[2],
              ELt[0] + m * (1 + b**2 / a**2) * J.qdd[0], ELt[1] + m * (1 + b**2 / a**2) * J.qdd[1],
              sp.diff(s.L_tilde, J.q[2]) + m * g,
              s.on_constraints(s.p_dependent[0]) - m * b / a * sq,
              s.Phi[0, 0] - b / a * xd / sq, s.Phi[0, 1] - b / a * yd / sq]
    ok = all(vanishes(c) for c in checks)
    L_ok = vanishes(s.L_tilde - (m * (1 + b**2 / a**2) * (xd**2 + yd**2) / 2 - m * g * J.q[2]))
    return Outcome(VERIFIED if ok and L_ok else ERRATUM, "All printed intermediate values "
                   "of Example 2 agree with jetnh's.", evidence=[f"values: {ok}", f"L~: {L_ok}"])


@claim("Example 2: T and equivalence",
       r"\ddot x\dot y - \dot x\ddot y = 0,\ T^3_1 = T^3_2 = 0,\ \text{the two sets are equivalent}")
def _c_ex2_T(ctx):
    s = ctx.appell_hamel
    J = s.J
    a, b = sp.symbols("a b")
    xd, yd = J.qd[0], J.qd[1]
    W = J.qdd[0] * yd - xd * J.qdd[1]
    sq3 = (xd**2 + yd**2) ** sp.Rational(3, 2)
    T = s.T()
    T_ok = vanishes(T[0, 0] - b / a * yd * W / sq3) and vanishes(T[0, 1] - b / a * xd * (-W) / sq3)
    acc = derive(s, "suslov").accelerations()
    W_on = vanishes(W.xreplace(acc), s)
    c, branch, branch_ok, checks = _ah_branch(ctx)
    ok = T_ok and W_on and c.identical and branch_ok
    return Outcome(VERIFIED if ok else ERRATUM,
                   "The printed T^3_mu equal jetnh's; along the Suslov accelerations "
                   "xddot ydot - xdot yddot = 0; and jetnh finds: " + str(c) + ". The "
                   "equivalence holds off the invariant branch " + branch + ", where the "
                   "vakonomic acceleration system is singular: there (44) leaves the "
                   "acceleration across the velocity free, so the vakonomic motion is not "
                   "unique and contains motions that are not Suslov's.",
                   evidence=[f"T as printed: {T_ok}", f"W = 0 on the motion: {W_on}", str(c),
                             *checks])


@claim("Conclusion: two independent sets",
       r"\text{only two of the three sets of equations are independent}")
def _c_concl(ctx):
    c = compare(ctx.particle, "vakonomic", "holder")
    d_ = compare(ctx.particle, "vakonomic", "suslov")
    return Outcome(VERIFIED if c.identical and not d_.identical else ERRATUM,
                   "Nonholonomic particle: " + str(c) + "; " + str(d_) + ".",
                   evidence=[str(c), str(d_)])


@claim("Conclusion: geodesics and extremal properties",
       r"\text{vakonomic solutions of Chaplygin systems are geodesics of a Riemann-Cartan "
       r"manifold; the Suslov equations also have an extremal property}")
def _c_geodesics(ctx):
    s = ctx.particle
    c = compare(s, "chetaev", "suslov")
    return Outcome(NOT_CHECKABLE,
                   "Cited from other work ([18]); outside what jetnh derives. Related finding: the "
                   "paper's Suslov equations (31) are Chetaev's (Voronets) equations exactly when "
                   "p_alpha T^alpha_mu = 0 on the constraints. That holds for both examples, but "
                   "for the nonholonomic particle zdot = y xdot jetnh finds: " + str(c) + ".",
                   evidence=[str(c)])


@claim("Sec. 3.4: no ideal-constraint assumption",
       r"\text{only the commutation relations were used, so no ideal-constraint assumption is needed}")
def _c_ideal(ctx):
    return Outcome(NOT_CHECKABLE, "A statement about the derivation's assumptions, not a "
                   "mathematical claim; jetnh makes the choice explicit (convention='paper' "
                   "treats the delta q^s as independent, 'imposed' imposes the Chetaev condition).")
