"""Free end coordinates on random systems (``jetnh.strategies``): the vakonomic or
Hoelder answer to an end that leaves one coordinate q^i free meets its transversality
condition, and the action it reaches is stationary in q^i(t1).

Each case is built with a known answer: a state at t1 (random coordinates, velocities
and multipliers, one multiplier then solved so that the momentum P_i = d(L + lambda
f)/dqdot^i vanishes there) run backwards to t0 gives the start; connect to the other
coordinates' values at t1, from that answer's unknowns moved by 2 %, must find a motion
with P_i(t1) = 0.  Two routes that do not share connect's code check it:

- P_i at the answer's end from sympy (the derivative of L + sum_a lambda_a f_a by the
  velocity of q^i, the dependent velocities replaced by phi), not from the boundary
  term of the action's variation that connect uses;
- where t1 is not conjugate (the neighbouring ends are reached), the fixed-end action
  C(x) -- connects with q^i(t1) = x named -- has the derivative P_i(t1) (the first
  variation's boundary term), so C(x + h) - C(x - h) = h (P_i(x - h) + 4 P_i(x) +
  P_i(x + h)) / 3 up to O(h^5) (Simpson's rule; the neighbours' P_i by sympy), with
  P_i(x) = 0 at the answer's x: a nonzero momentum there would show as 4 h P_i / 3.
  (The slope alone, by central differences, carries an O(h^2) error that is large
  where dq(t1)/du is nearly singular.)
"""

import numpy as np
import sympy as sp
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import jetnh as jn
from jetnh import strategies as jst
from jetnh.mechanics import principles

T = 1.0
H = 1e-4
#: the ends met to this (the fixed coordinates' momenta times a missed end would
#: otherwise show in the actions compared)
TOL = 1e-12


def _momentum(system, principle, i):
    """P_i = d(L + sum_a lambda_a f_a)/d qdot^i with qdot^alpha = phi^alpha."""
    mults = principles.get(principle).multiplier_symbols(system)
    composite = system.L + sum(lam * f for lam, f in zip(mults, system.constraints))
    P = sp.diff(composite, system.J.qd[i]).xreplace(dict(system.phi))
    args = (*system.J.q, *system.independent_velocities, *mults)
    return P, args, mults


def _value(expr, args, state, params):
    return float(expr.xreplace({**dict(zip(args, state)), **params}))


@settings(max_examples=6)
@given(jst.systems(min_n=3, max_n=3, affine=True), st.sampled_from(["vakonomic", "holder"]),
       st.data())
def test_free_end_meets_transversality_and_is_stationary(system, principle, data):
    n = len(system.J.q)
    # a distribution of rank one is integrable (the end fixed on a curve)
    assume(len(system.independent_velocities) >= 2)
    # every constraint with the independent velocities and the configuration: one
    # without the velocities (qdot^a = phi(t, q)) or without q (integrable, as qdot^a =
    # c qdot^mu + g(t)) fixes a combination of the coordinates' ends, so there are no
    # neighbouring fixed ends to compare with (the extremals are abnormal)
    assume(all(set(e.free_symbols) & set(system.independent_velocities)
               and set(e.free_symbols) & set(system.J.q) for e in system.phi.values()))
    i = data.draw(st.integers(0, n - 1), label="free coordinate")
    P, args, mults = _momentum(system, principle, i)
    assume(mults)
    # the parameters' values and t = t1
    params = {system.J.t: T, **{s: system.defaults.get(s, 1.0) for s in system.parameters}}
    value = st.floats(-0.5, 0.5, allow_nan=False, allow_infinity=False)
    state = np.array([data.draw(value) for _ in args])
    # one multiplier solved for P_i = 0 at t1 (P_i is affine in the multipliers)
    k = len(args) - len(mults)
    B = np.array([float(sp.diff(P, lam).xreplace(
        {**dict(zip(args, state)), **params})) for lam in mults])
    a = int(np.argmax(np.abs(B)))
    assume(abs(B[a]) > 0.1)
    state[k + a] = 0.0
    state[k + a] = -_value(P, args, state, params) / B[a]
    assume(abs(state[k + a]) < 5.0)
    names = [s.name for s in args]
    back = jn.Scene(system, principle, initial=dict(zip(names, state)), t_span=(T, 0.0))
    try:
        run = back.run(rtol=1e-12, atol=1e-13)
    except jn.JetnhError:
        assume(False)
    assume(run.status == 0 and np.all(np.abs(run.y[-1]) < 10.0))
    coords = [q.name for q in system.J.q]
    start = {c: float(run[c][-1]) for c in coords}
    end = {c: float(state[j]) for j, c in enumerate(coords) if j != i}
    answer = np.array([float(run[u][-1]) for u in names[n:]])
    c = jn.connect(system, principle, start, end, (0.0, T), guess=1.02 * answer, tol=TOL)
    assert c.residual < 1e-9
    assert c.conditions[-1] == f"p_{coords[i]}"
    tr = c.trajectory
    final = [float(tr[s][-1]) for s in names]
    assert abs(_value(P, args, final, params)) < 1e-8        # transversality, by sympy
    # the neighbouring fixed ends are reached where dq(t1)/du has full rank (t1 is not
    # conjugate; a holonomic coordinate, say, has no neighbouring end)
    assume(T not in c.conjugate_times)

    def fixed(qi):
        """The fixed-end action and P_i(t1) (by sympy) with q^i(t1) = qi."""
        d = jn.connect(system, principle, start, {**end, coords[i]: qi}, (0.0, T),
                       guess=[c.initial[u] for u in c.unknowns], tol=TOL)
        return d.cost, _value(P, args, [float(d.trajectory[s][-1]) for s in names], params)

    qi = float(tr[coords[i]][-1])
    (a, pa), (b, pb) = fixed(qi - H), fixed(qi + H)
    # C(q + h) - C(q - h) = int P_i dq^i(t1) by Simpson's rule, the middle value the
    # answer's P_i = 0 (were it not zero, off by 4 h P_i / 3)
    assert abs(b - a - H * (pa + pb) / 3) < 1e-9 * (1.0 + abs(c.cost))
