"""Each multiplier lambda_<q> belongs to the constraint solved for q, in every form.

The a-th constraint is paired with ``System.dependent[a]`` (a coordinate whose velocity
it contains), whatever order the constraints and ``dependent`` were given in; the
multiplier form multiplies the a-th constraint by lambda_<dependent[a]>, the explicit
forms multiply qdot^a - phi^a by it.  For constraints already in explicit form the two
are the same multiplier, so the two forms must give the same equations and the same
multiplier rates.
"""

import sympy as sp
from hypothesis import given, strategies as st

import jetnh as jn


def _audit_system(constraints_order, dependent):
    J = jn.JetSpace("x y z w")
    x, y, z, w = J.q
    xd, yd, zd, wd = J.qd
    cons = {"z": zd - y * xd, "w": wd - x * yd}
    L = sum(v**2 for v in J.qd) / 2
    return J, jn.System(J, L, [cons[c] for c in constraints_order], dependent=dependent)


def _rate_equals_minus_acceleration(J, eom, name):
    """L = |qdot|^2/2 with a constraint qdot^q - (...) : the row of q reads
    -lambda_q_t - q_tt = 0, so lambda_q + q_t is conserved (no other lambda there)."""
    q = next(s for s in J.q if s.name == name)
    lam = sp.Symbol(f"lambda_{name}")
    acc = eom.accelerations()
    return sp.expand(acc[J.jet(lam, 1)] + acc[J.jet(q, 2)]) == 0


def test_audit_order_user_split():
    J, s = _audit_system(("z", "w"), dependent=["w", "z"])
    assert [q.name for q in s.dependent] == ["z", "w"]
    for form in ("multiplier", "explicit", "reduced", "embedded"):
        eom = s.equations("vakonomic", form=form)
        assert tuple(m.name for m in eom.multipliers) == ("lambda_z", "lambda_w")
        for name in ("z", "w"):
            assert _rate_equals_minus_acceleration(eom.J, eom, name), (form, name)
    rows = s.equations("vakonomic").expressions
    lw_t, w_tt = sp.Symbol("lambda_w_t"), sp.Symbol("w_tt")
    assert sp.expand(rows[3] - (-lw_t - w_tt)) == 0


def test_audit_order_automatic_split():
    J, s = _audit_system(("w", "z"), dependent=None)
    assert [q.name for q in s.dependent] == ["w", "z"]
    eom = s.equations("vakonomic")
    for name in ("z", "w"):
        assert _rate_equals_minus_acceleration(eom.J, eom, name)


def test_dependent_paired_with_constraints():
    J = jn.JetSpace("x y z w")
    x, y, z, w = J.q
    xd, yd, zd, wd = J.qd
    s = jn.System(J, sum(v**2 for v in J.qd) / 2, [wd - x * yd, xd - sp.cos(w) * yd])
    for f, q in zip(s.constraints, s.dependent):
        assert sp.diff(f, J.jet(q, 1)) != 0


@st.composite
def shuffled_explicit_systems(draw):
    """Constraints qdot^alpha - phi^alpha(q, qdot^mu), listed in a random order, with the
    dependent coordinates in another random order."""
    n = draw(st.integers(3, 4))
    k = draw(st.integers(2, n - 1))
    J = jn.JetSpace(" ".join(f"q{i}" for i in range(n)))
    dep = draw(st.permutations(range(n)))[:k]
    ind = [i for i in range(n) if i not in dep]
    cons = []
    for a in dep:
        i = draw(st.sampled_from(ind))
        j = draw(st.sampled_from(range(n)))
        c = draw(st.integers(-2, 2).filter(bool))
        cons.append(J.qd[a] - c * J.q[j] * J.qd[i])
    order = draw(st.permutations(range(k)))
    given_dep = draw(st.permutations([J.q[a] for a in dep]))
    masses = [draw(st.integers(1, 3)) for _ in range(n)]
    L = sum(m * v**2 for m, v in zip(masses, J.qd)) / 2
    return J, jn.System(J, L, [cons[o] for o in order], dependent=list(given_dep))


@given(shuffled_explicit_systems())
def test_forms_agree_on_every_multiplier(data):
    J, s = data
    for f, q in zip(s.constraints, s.dependent):
        assert sp.diff(f, J.jet(q, 1)) == 1
    mult = s.equations("vakonomic")
    expl = s.equations("vakonomic", form="explicit")
    assert mult.multipliers == expl.multipliers
    for a, b in zip(mult.expressions, expl.expressions):
        assert sp.expand(a - b) == 0
    am, ae = mult.accelerations(), expl.accelerations()
    for key in am:
        assert sp.expand(am[key] - ae[key]) == 0, key


def test_scene_state_lambda_w_is_ws_multiplier():
    """The audit's Scene: lambda_w + w_t is conserved (w's row), lambda_z + z_t too, and
    the initial value keyed lambda_w goes to w's multiplier."""
    import numpy as np

    J, s = _audit_system(("z", "w"), dependent=["w", "z"])
    x, y, z, w = J.q
    xd, yd = J.qd[:2]
    lw, lz = sp.Symbol("lambda_w"), sp.Symbol("lambda_z")
    sc = jn.Scene(s, "vakonomic", initial={x: 0.1, y: 0.2, z: 0, w: 0, xd: 1.0, yd: 0.5,
                                           lw: 0.3, lz: -0.2}, t_span=(0, 2))
    tr = sc.run()
    assert tr["lambda_w"][0] == 0.3 and tr["lambda_z"][0] == -0.2
    assert np.ptp(tr["lambda_w"] + tr["w_t"]) < 1e-9
    assert np.ptp(tr["lambda_z"] + tr["z_t"]) < 1e-9
    assert np.ptp(tr["lambda_w"] + tr["z_t"]) > 1e-2


def test_atlas_splits_are_paired_and_distinct():
    """Every split of the atlas once, in the order ``with_split`` pairs it (the chart
    change maps multipliers by that order)."""
    from jetnh.numeric.atlas import splits

    J, s = _audit_system(("w", "z"), dependent=None)
    out = splits(s)
    assert out[0] == ("w", "z")
    assert len({frozenset(x) for x in out}) == len(out)
    for names in out:
        assert tuple(q.name for q in s.with_split(list(names)).dependent) == names
