"""Symbolic proofs of the paper's general identities for generic systems, n <= 4, k < n.

Each proof uses undefined functions L(t, q, qdot), f^a(t, q, qdot), phi^alpha(t, q, qdot^mu)
or B^alpha_rho(t, q) (``jetnh.mechanics.proof.generic_system``), so it holds for every smooth system
of that size, and records the steps it used.  Identities: (3), (6), (8), (10), (11), (13),
(19), the passage (29) -> (30) -> (31), (32) with the rate of lambda + p on its branch, and
(39).  Inferences drawn from the checked identities are recorded as remarks (not
machine-checked).
"""

from __future__ import annotations

import time

import sympy as sp

from jetnh.mechanics.equations import action_variation, chetaev_admissible, derive, multiplier_symbols, null_basis
from jetnh.mechanics.equivalence import frobenius_T, obstructions
from jetnh.geometry.frobenius import frobenius
from jetnh.mechanics.proof import Proof, generic_system
from jetnh.mechanics.variations import Variation, defect, identity_residual, make, printed_identity_residual, reduced_identity_residual


def _arbitrary(s, kind):
    """The variation with an arbitrary commutator c^s (symbols)."""
    v = make(s, "free")
    return Variation(kind, s, v.J, v.eta, sp.symbols(f"c1:{s.J.n + 1}"), {}, "")


def _chetaev(s, v):
    A = s.jacobian
    return [sp.Add(*[A[a, i] * v.eta[i] for i in range(s.J.n)]) for a in range(s.k)]


def prove_3(n, k):
    s = generic_system(n, k, "implicit")
    p = Proof("(3): delta f + f_qdot c - D(f_qdot eta) = [f] eta, c arbitrary", n, k)
    v = _arbitrary(s, "free")
    p.step("expand delta f = f_q eta + f_qdot (D eta - c) and D(f_qdot eta); collect",
           identity_residual(v))
    p.refute("the printed form, with df/dq^s multiplying c, is not an identity",
             printed_identity_residual(v))
    return p


def prove_6_8_10(n, k):
    s = generic_system(n, k, "implicit")
    p = Proof("(6), (8), (10): the identity reduced by each variation's conditions", n, k)
    for kind, extra, text in (
            ("vakonomic", lambda v: [v.delta(f) + sp.Add(*[s.jacobian[a, i] * v.c[i]
                                                          for i in range(n)])
                                     for a, f in enumerate(s.constraints)],
             "(6) residual = delta f + f_qdot c: zero under (5) (delta f = 0, c = 0)"),
            ("holder", lambda v: [v.J.D(ch) - sp.Add(*[s.jacobian[a, i] * v.c[i]
                                                       for i in range(n)])
                                  for a, ch in enumerate(_chetaev(s, v))],
             "(8) residual = D(f_qdot eta) - f_qdot c: zero under (7) (c = 0, Chetaev)"),
            ("suslov", lambda v: [v.J.D(ch) - v.delta(f) for ch, f in
                                  zip(_chetaev(s, v), s.constraints)],
             "(10) residual = D(f_qdot eta) - delta f: zero under (9) (delta f = 0, Chetaev)")):
        v = _arbitrary(s, kind)
        p.step(text, [r - e for r, e in zip(reduced_identity_residual(v), extra(v))])
    return p


def prove_11(n, k):
    s = generic_system(n, k, "explicit")
    p = Proof("(11): on the Chetaev subspace the variations coincide iff [f]_s eta^s = 0", n, k)
    eta = chetaev_admissible(s, make(s, "free").eta)
    h = make(s, "holder", eta=eta)
    su = make(s, "suslov", eta=eta)
    dfe = defect(s, eta, h.J)
    p.step("eta = P eta^mu satisfies the Chetaev condition identically", _chetaev(s, h))
    p.step("Hoelder (c = 0): delta_H f = [f] eta", [h.delta(f) - x
                                                    for f, x in zip(s.constraints, dfe)])
    p.step("Suslov (delta f = 0): f_qdot c_S = [f] eta",
           [sp.Add(*[s.jacobian[a, i] * su.c[i] for i in range(n)]) - dfe[a] for a in range(k)])
    p.remark("so delta_H f = 0 iff c_S = 0 iff [f] eta = 0, and with it delta_V = delta_H = "
             "delta_S (f_qdot of full rank)")
    return p


def prove_13(n, k):
    s = generic_system(n, k, "implicit")
    lams = multiplier_symbols(s)
    v = make(s, "free", extra_fields=[m.name for m in lams])
    v = Variation("general", s, v.J, v.eta, sp.symbols(f"c1:{n + 1}"), {}, "")
    p = Proof("(13): delta(L + lambda f) = (E_s eta^s - P_s c^s) + D(P_s eta^s)", n, k)
    p.step("expand and integrate by parts; boundary term P_s eta^s",
           [action_variation(s, v, lams).residual()])
    return p


def _projected(s, E):
    P = null_basis(s)
    return [sp.Add(*[P[r, m] * E[r] for r in range(s.J.n)]) for m in range(P.cols)]


def prove_19(n, k):
    s = generic_system(n, k, "explicit")
    J = s.J
    EL = J.euler(s.L)
    Lt = s.L_tilde
    ELt = J.euler(Lt, wrt=s.independent)
    T = s.T(on_constraints=False)
    res = []
    for m, i in enumerate(s.ind_index):
        lhs = EL[i] + sp.Add(*[s.Phi[a, m] * EL[j] for a, j in enumerate(s.dep_index)])
        rhs = ELt[m] + sp.Add(*[s.Phi[a, m] * sp.diff(Lt, q) + s.p_dependent[a] * T[a, m]
                                for a, q in enumerate(s.dependent)])
        res.append(s.on_constraints(lhs - rhs, prolonged=True))
    p = Proof("(19): [L]_mu + Phi[L]_alpha = [L~]_mu + Phi dL~/dq^alpha + p_alpha T^alpha_mu", n, k)
    p.step("chain rule for L~ = L(t, q, qdot^mu, phi); on qdot^alpha = phi^alpha, "
           "qddot^alpha = D phi^alpha", res)
    return p


def prove_29_31(n, k):
    s = generic_system(n, k, "explicit")
    p = Proof("(29) -> (30) -> (31): Suslov equations in reduced and embedded form", n, k)
    m29 = derive(s, "suslov", "multiplier")
    r30 = derive(s, "suslov", "reduced")
    e31 = derive(s, "suslov", "embedded")
    proj = _projected(s, m29.expressions)
    p.step("(30b) = (29b) + (dphi/dqdot^mu)(29a): the multiplier rates cancel",
           [a - b for a, b in zip(r30.expressions[k:], proj)])
    p.step("(31b) = (30b) rewritten by (19), on the prolonged constraints",
           [s.on_constraints(a - b, prolonged=True)
            for a, b in zip(e31.expressions, r30.expressions)])
    return p


def prove_32(n, k):
    s = generic_system(n, k, "explicit")
    v = derive(s, "vakonomic", "embedded")
    su = derive(s, "suslov", "embedded")
    T = s.T(on_constraints=False)
    lams = v.multipliers
    p = Proof("(32): (20b) - (31b) = (p_alpha + lambda_alpha) T^alpha_mu; on lambda = -p, "
              "(20a) gives d/dt(lambda_alpha + p_alpha) = dL~/dq^alpha", n, k)
    p.step("difference of the embedded vakonomic and Suslov equations",
           [s.on_constraints(v.expressions[k + m] - su.expressions[k + m] - sp.Add(*[
               (s.p_dependent[a] + lams[a]) * T[a, m] for a in range(k)]), prolonged=True)
            for m in range(n - k)])
    branch = {lams[a]: -s.p_dependent[a] for a in range(k)}
    p.step("(20a) on the branch lambda_alpha = -p_alpha: d/dt(lambda_alpha + p_alpha) = "
           "dL~/dq^alpha",
           [s.on_constraints((v.J.jet(lams[a], 1) + s.J.D(s.p_dependent[a]) + v.expressions[a])
                             .xreplace(branch) - sp.diff(s.L_tilde, q), prolonged=True)
            for a, q in enumerate(s.dependent)])
    p.remark("hence lambda_alpha = -p_alpha (32) makes the accelerations agree at an instant; "
             "it gives common solutions only where the branch is invariant, dL~/dq^alpha = 0 "
             "on the constraints (Chaplygin systems)")
    return p


def prove_39(n, k):
    s = generic_system(n, k, "affine")
    p = Proof("(39): T^alpha_mu = K^alpha_{rho mu} qdot^rho, K the Frobenius obstructions", n, k)
    p.step("T from its definition equals the contraction of K = X_rho B_sigma - X_sigma B_rho",
           list(s.T() - frobenius_T(s)))
    K = obstructions(s)
    fr = frobenius(s.J, s.B, s.dependent, s.independent, method="forms")
    p.step("K equals the obstructions read off d omega ^ omega^1 ^ ... ^ omega^k (forms route)",
           [K[key] - val for key, val in fr.obstructions.items()]
           + [v for key, v in K.items() if key not in fr.obstructions])
    p.remark("so T = 0 for all velocities iff the distribution is involutive (Frobenius)")
    return p


PROOFS = (prove_3, prove_6_8_10, prove_11, prove_13, prove_19, prove_29_31, prove_32, prove_39)


def run(max_n: int = 4, log=print) -> list[dict]:
    """Every proof for n = 2..max_n and k = 1..n-1."""
    out = []
    for n in range(2, max_n + 1):
        for k in range(1, n):
            for prove in PROOFS:
                t0 = time.perf_counter()
                p = prove(n, k)
                d = p.as_dict()
                d["seconds"] = round(time.perf_counter() - t0, 2)
                out.append(d)
                verdict = {True: "holds ", False: "FAILS "}.get(p.holds, "remarks only ")
                log(f"  n={n} k={k} {verdict}{p.statement[:60]}"
                    f" ({d['seconds']} s)")
    return out
