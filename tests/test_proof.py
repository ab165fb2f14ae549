"""jetnh.mechanics.proof: a step holds only when its residuals are checked exactly zero;
prose without residuals is a remark, never counted as proven."""

import sympy as sp

from jetnh.mechanics.proof import Proof


def test_a_step_without_residuals_is_a_remark_not_a_proof():
    x = sp.Symbol("x")
    p = Proof("statement", 2, 1)
    assert p.step("prose only") is None
    assert p.steps == [("prose only", None)] and p.checked == 0
    assert p.as_dict()["holds"] is None is p.holds           # nothing was checked
    assert p.as_dict()["steps"][0] == {"step": "prose only", "holds": None, "checked": False}
    assert p.step("an identity", [sp.sin(x) * 2 - 2 * sp.sin(x)]) is True
    assert p.as_dict()["holds"] is True is p.holds and p.checked == 1
    assert p.step("not an identity", [x - 1]) is False
    assert p.as_dict()["holds"] is False is p.holds
    assert p.remark("more prose") is None and p.holds is False
    q = Proof("refuted", 2, 1)
    q.remark("prose first")
    assert q.holds is None and q.refute("a false claim", [x - 1]) is True is q.holds


def test_the_32_rate_on_the_branch_for_a_generic_system():
    """On lambda = -p, (20a) gives d/dt(lambda + p) = dL~/dq^alpha (generic L, phi), and
    the branch being invariant is a remark, not a checked step."""
    from papers.zhao2008.proofs import prove_32

    p = prove_32(2, 1)
    d = p.as_dict()
    assert d["holds"] is True
    assert [s["checked"] for s in d["steps"]] == [True, True, False]
