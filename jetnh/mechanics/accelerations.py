"""Accelerations: every principle's equations as one linear system in q'' and the
multiplier rates, solved by blocks (what ``Equations.accelerations()`` returns).

The rows ``jetnh.mechanics.equations`` derives from (13) are affine in the accelerations and the
multiplier rates.  With::

    [L]_s   = r_s - H_sr q''^r           H = d2L / dqdot^s dqdot^r
    [f^a]_s = g^a_s - G^a_sr q''^r       G^a = d2f^a / dqdot^s dqdot^r
    D f^a   = A_as q''^s + b^a            A = df / dqdot

every principle's rows read::

    (r + kappa_a g^a)_s - (H + kappa_a G^a)_sr q''^r - A_as mu'_a = 0            (*)

    chetaev            kappa = 0, rows projected on ker A (Maggi), no rates;
    vakonomic, holder  kappa = lambda, mu' = lambda' (E_s of (13), i.e. (15));
    suslov             kappa = -A_dep^-T p_dep: in (29) the commutator term P_alpha c^alpha
                       with c = A_dep^-1 [f] eta, (10), cancels lambda_a [f^a]_s.

Generalized forces Q_s (``System.Q``) enter every row beside [L]_s: r_s becomes r_s + Q_s.

The explicit forms ((17)-(20), (29)-(31)) use the constraints qdot^alpha - phi^alpha.
When f is affine these are S f with S = A_dep^-1, and on f = 0::

    [S f]_s = S ([f]_s + (D A_dep) S A_s),

so (*) holds with kappa = S^T lambda~ (vakonomic) or -S^T p_dep (suslov), and the rates
of the explicit multipliers are mu' = (rows at lambda~' = 0)_dep + (D A_dep)^T kappa:
the solved phi (nested for long chains) is never differentiated.

The solve: D f = 0 gives q'' = P u + w (u the independent accelerations, P = [I; Phi],
Phi = -A_dep^-1 A_ind, w = -A_dep^-1 b); P^T A^T = 0 removes the rates, so that
(P^T H' P) u = P^T (r' - H' w); the dependent rows then give the rates.  Coefficients
come from L and f alone; the solved expressions are only ever built (never
differentiated, substituted into or simplified), so they share their subexpressions,
ready for ``cse``.
"""

from __future__ import annotations

import weakref
from typing import NamedTuple

import symengine as se
import sympy as sp
from sympy.core.cache import clear_cache
from sympy.core.function import AppliedUndef
from sympy.matrices.utilities import dotprodsimp

from ..algebra import dag, linalg, zero
from ..errors import LagrangianError
from ..frozen import FrozenDict

KAPPA = ("none", "multipliers", "momenta")
#: id(system) -> (weak reference, {(F, hessian): parts}): by identity, never by equality
#: (equal systems built apart must not share nodes: comparing them walks trees)
_PARTS: dict = {}
#: the key, in a system's entry of ``_PARTS``, of the conversions its parts share
_CONVERTED = object()


class Accelerations(FrozenDict):
    """What ``Equations.accelerations()`` returns: a read-only dict, q''^s and the
    multiplier rates (Symbols) -> sympy expressions, whose repr keeps to the text budget:
    an expression whose printed tree would be large (counted on its shared graph, never
    printed) shows as its size and symbols, and entries past the budget are counted."""

    __slots__ = ()

    def __repr__(self):
        from ..display import TEXT_BUDGET, TREE_CAP, tree_size

        parts, used = [], 0
        for i, (s, e) in enumerate(self.items()):
            if tree_size(e) <= TREE_CAP:
                text = f"{s}: {e}"
            else:
                syms = sorted(x.name for x in dag.free_symbols(e))
                text = (f"{s}: <expression of {dag.size(e)} distinct parts in "
                        f"{', '.join(syms[:8])}{', ...' if len(syms) > 8 else ''}>")
            if used + len(text) > TEXT_BUDGET - 100:
                parts.append(f"... ({len(self) - i} more)")
                break
            parts.append(text)
            used += len(text) + 2
        return "{" + ", ".join(parts) + "}"

    __str__ = __repr__

    def __reduce__(self):
        return Accelerations, (dict(self),)


class EulerParts(NamedTuple):
    """[F]_s = r_s - H_sr q''^r and D F = p_s q''^s + v, for first-order F."""

    p: list                      # dF/dqdot^s
    H: sp.Matrix | None          # dp_s/dqdot^r (None when not asked for)
    r: sp.Matrix | None          # dF/dq^s - dp_s/dt - dp_s/dq^r qdot^r (None: not asked for)
    v: sp.Expr                   # dF/dt + dF/dq^s qdot^s


def euler_parts(J, F, hessian: bool = True, rest: bool = True,
                converted: dict | None = None) -> EulerParts:
    """The parts of [F] and D F for first-order F (``EulerParts``; without ``rest``, r
    is not computed: the principles whose multipliers do not weigh [f] need only p, v).

    The derivatives are taken by symengine (tens of times faster than sympy's diff on
    a long chain's Lagrangian) and returned as sympy expressions in the original
    symbols, each distinct subexpression converted once (``_to_sympy``); expressions of
    undefined functions (``jetnh.mechanics.proof``) stay with sympy.  ``converted`` (a
    dict, filled here) carries the conversions over several calls (the parts of one
    system's Lagrangian and constraints share subexpressions: converted once, one object).
    """
    n = J.n
    if F.has(AppliedUndef, sp.Derivative, sp.Subs):
        p, H, r, v = _parts(F, J.t, J.q, J.qd, hessian, rest, sp.S.Zero, sp.Add)
    else:
        syms = [se.Symbol(v.name) for v in (J.t, *J.q, *J.qd)]
        parts = _parts(se.sympify(F), syms[0], syms[1:n + 1], syms[n + 1:], hessian, rest,
                       se.Integer(0), se.Add)
        originals = {v.name: v for v in F.free_symbols | {J.t, *J.q, *J.qd}}
        flat = []
        for x in parts:
            if isinstance(x, list):
                flat += [e for row in x for e in (row if isinstance(row, list) else [row])]
            elif x is not None:
                flat.append(x)
        out = iter(_to_sympy(flat, originals, converted))
        p = [next(out) for _ in range(n)]
        H = [[next(out) for _ in range(n)] for _ in range(n)] if hessian else None
        r = [next(out) for _ in range(n)] if rest else None
        v = next(out)
    return EulerParts(list(p), None if H is None else sp.Matrix(n, n, lambda a, b: H[a][b]),
                      None if r is None else sp.Matrix(r), v)


def _to_sympy(exprs, originals: dict, memo: dict | None = None) -> list:
    """symengine expressions as sympy ones, each distinct subexpression converted once
    (symengine's own conversion walks the tree) by the constructor symengine's would
    call; symbols become ``originals[name]`` (the user's, with their assumptions).
    ``memo`` (a dict, filled here) carries the conversions over calls whose symbols
    agree (a call with another Symbol of a name converted before starts afresh)."""
    memo = {} if memo is None else memo
    done, names = memo.setdefault("nodes", {}), memo.setdefault("names", {})
    if any(names.get(k, v) is not v for k, v in originals.items()):
        done, names = {}, {}
    names.update(originals)
    for root in exprs:
        stack = [(root, False)]
        while stack:
            e, expanded = stack.pop()
            if e in done:
                continue
            args = e.args
            if not args:
                x = sp.sympify(e, strict=True)
                done[e] = originals.get(x.name, x) if isinstance(x, sp.Symbol) else x
            elif not expanded:
                stack.append((e, True))
                stack.extend((a, False) for a in args if a not in done)
            else:
                head = (sp.Add if isinstance(e, se.Add) else sp.Mul if isinstance(e, se.Mul)
                        else sp.Pow if isinstance(e, se.Pow) else None)
                if head is None:        # a function: symengine's conversion, one level
                    dummies = [se.Symbol(f"_{i}") for i in range(len(args))]
                    head = sp.sympify(e.func(*dummies), strict=True).func
                done[e] = dag.build(head, [done[a] for a in args])
    return [done[e] for e in exprs]


def _parts(F, t, q, qd, hessian, rest, zero, add):
    """``euler_parts`` on sympy or symengine expressions (``zero`` and ``add`` of the
    library); only derivatives by symbols that occur are taken, those of the momenta
    on symengine by one walk per symbol (``_together``)."""
    n = len(q)

    def d(e, x, syms):
        return e.diff(x) if x in syms else zero

    fs = F.free_symbols
    p = [d(F, x, fs) for x in qd]
    ps = [e.free_symbols for e in p]
    def by(x, upto=n):              # [d(p[s], x, ps[s]) for s < upto]
        live = [s for s in range(upto) if x in ps[s]]
        out = [zero] * upto
        got = (_together([p[s] for s in live], x) if add is se.Add and len(live) > 1
               else [p[s].diff(x) for s in live])
        for s, e in zip(live, got):
            out[s] = e
        return out
    H = None
    if hessian:
        H = [[zero] * n for _ in range(n)]
        for r in range(n):
            for s, h in enumerate(by(qd[r], r + 1)):
                H[s][r] = H[r][s] = h
    rem = None
    if rest:
        dq = [by(x) for x in q]
        rem = [d(F, q[s], fs) - d(p[s], t, ps[s])
               - add(*[dq[j][s] * v for j, v in enumerate(qd)]) for s in range(n)]
    v = d(F, t, fs) + add(*[d(F, x, fs) * xd for x, xd in zip(q, qd)])
    return p, H, rem, v


def _together(exprs, x) -> list:
    """``[e.diff(x) for e in exprs]`` for symengine expressions, by one derivative of
    sum_i m_i e_i (fresh symbols m_i, read off the terms): symengine remembers the
    derivatives of the subexpressions within one call only, and the momenta of a
    chain share most of theirs."""
    marks = [se.Dummy() for _ in exprs]
    index = {m: i for i, m in enumerate(marks)}
    terms: list = [[] for _ in exprs]
    total = se.Add(*[m * e for m, e in zip(marks, exprs)]).diff(x)
    for term in (total.args if isinstance(total, se.Add) else (total,)):
        if term in index:
            terms[index[term]].append(se.Integer(1))
            continue
        for m in term.args:
            if m in index:
                terms[index[m]].append(term / m)
                break
    return [se.Add(*t) for t in terms]


def cached_parts(system, F, hessian=True, rest=False) -> EulerParts:
    """``euler_parts`` of the system's Lagrangian or constraints, once per system; r only
    with ``rest`` (the parts with r serve a later call without)."""
    key = id(system)
    entry = _PARTS.get(key)
    if entry is None or entry[0]() is not system:
        def forget(ref, key=key):
            if _PARTS.get(key, (None,))[0] is ref:
                del _PARTS[key]
        entry = _PARTS[key] = (weakref.ref(system, forget), {})
    cache = entry[1]
    found = cache.get((F, hessian))
    if found is None or (rest and found.r is None):
        cache[F, hessian] = found = euler_parts(system.J, F, hessian, rest,
                                                cache.setdefault(_CONVERTED, {}))
    return found


def _weighted(M: sp.Matrix, weights, parts) -> sp.Matrix:
    """M + sum_a weights[a] parts[a] (parts None skipped), each entry one Add of its terms
    (adding the matrices one by one re-flattens every partial sum: quadratic in the
    number of constraints); zero products left out (sympy's w * 0 asks whether w is
    finite, walking its tree)."""
    return sp.Matrix(M.rows, M.cols, lambda i, j: dag.build(sp.Add, [
        M[i, j], *[dag.mul(w, X[i, j]) for w, X in zip(weights, parts)
                   if X is not None and w != 0 and X[i, j] != 0]]))


@dag.collector_paused()
def solve(system, kappa: str = "none", explicit: bool = False, multipliers=(),
          rates=()) -> dict:
    """q''^s (and the ``rates`` of ``multipliers``) of the rows (*) on the constraints.

    ``kappa``: "none" (Chetaev), "multipliers" (vakonomic, Hoelder) or "momenta"
    (Suslov); ``explicit``: the multipliers belong to the explicit constraints;
    ``rates``: the multiplier rates to solve for (none for Chetaev and the imposed
    convention, whose rows are projected).
    """
    # sympy's construction cache would hand back equal but distinct copies of nodes built
    # by an earlier derivation; comparing such copies (sympy's __eq__ walks the tree, not
    # the graph) costs time exponential in the nesting of the solve
    clear_cache()
    # no cancel() inside matrix products (hot path); pivots of large solves are chosen by
    # their values at random points on the constraint manifold
    with dotprodsimp(False), linalg.completing(lambda v: zero.on_constraints(system, v)):
        return _solve(system, kappa, explicit, tuple(multipliers), tuple(rates))


def _solve(system, kappa, explicit, multipliers, rates):
    J = system.J
    n, k = J.n, system.k
    qdd = J.qdd
    ind, dep = list(system.ind_index), list(system.dep_index)
    transform = explicit and system.is_affine
    cons = system.explicit_constraints if explicit and not transform else system.constraints
    p, H, r, _ = cached_parts(system, system.L, rest=True)
    # the constraints' r only where the multipliers weigh [f] (kappa)
    cparts = [cached_parts(system, f, hessian=not system.is_affine, rest=kappa != "none")
              for f in cons]
    A = sp.Matrix([c.p for c in cparts]) if k else sp.zeros(0, n)
    b = sp.Matrix([c.v for c in cparts]) if k else sp.zeros(0, 1)
    A_dep = A[:, dep]

    if kappa == "none":
        kap = [sp.S.Zero] * k
    elif kappa == "multipliers":
        kap = list(linalg.solve(A_dep.T, sp.Matrix(multipliers))) if transform else list(multipliers)
    elif kappa == "momenta":
        kap = list(linalg.neg(linalg.solve(A_dep.T, sp.Matrix([p[i] for i in dep]))))
    else:
        raise ValueError(f"kappa must be one of {KAPPA}, not {kappa!r}")
    H1, r1 = H, r
    if system.forced:                 # Q_s stands beside [L]_s in every row
        r1 = r1 + sp.Matrix(system.Q)
    if any(c != 0 for c in kap):
        r1 = _weighted(r1, kap, [c.r for c in cparts])
        if any(c.H is not None for c in cparts):
            H1 = _weighted(H1, kap, [c.H for c in cparts])

    if not (system.L.free_symbols & set(J.qd)):
        raise LagrangianError(
            f"the Lagrangian {system.L} contains no velocity: it has no kinetic energy, so no "
            "principle determines the accelerations. Add the kinetic energy, e.g. "
            "L = m*J.qd[0]**2/2 - V")
    rank = linalg.reduced_rank(H1, A, ind, dep,
                               complete=lambda v: zero.on_constraints(system, v),
                               symbols=set().union(*(f.free_symbols for f in system.constraints)))
    if rank < n - k:
        raise LagrangianError(
            f"the reduced Hessian P^T H P on the constraint distribution (H = d^2L/dqdot^2, "
            f"plus the constraint Hessians the principle's multipliers weigh) is singular: "
            f"rank {rank} < {n - k} on the constraints, so this principle does not determine the "
            "accelerations. Check the kinetic energy (it must be positive on the admissible "
            "velocities), or use another principle")

    X = linalg.solve(A_dep, linalg.neg(A[:, ind].row_join(b))) if k else sp.zeros(0, n + 1)
    Phi, w = X[:, :n - k], X[:, n - k]
    P = linalg.embed(Phi, ind, dep)   # q'' = P u + w_full
    w_full = sp.zeros(n, 1)
    for a, i in enumerate(dep):
        w_full[i] = w[a]
    HP = linalg.matmul(H1, P)
    K = linalg.matmul(P.T, HP)
    rhs = linalg.matmul(P.T, linalg.sub(r1, linalg.matmul(H1, w_full)))
    u = linalg.solve(K, rhs)
    q2 = linalg.add(linalg.matmul(P, u), w_full)
    acc = {qdd[s]: q2[s] for s in range(n)}
    if rates:
        R = linalg.sub(r1, linalg.matmul(H1, q2)).extract(dep, [0])
        if transform:
            graph: dict = {}          # the entries' shared parts differentiated once
            DA = A_dep.applyfunc(lambda e: J.D(e, graph))
            mu = linalg.add(R, linalg.matmul(DA.T, sp.Matrix(kap)))
        else:
            mu = linalg.solve(A_dep.T, R)
        acc.update({rate: mu[a] for a, rate in enumerate(rates)})
    return acc
