"""What a System prints keeps to the text budget; T() keeps the shared structure.

The N-trailer's expressions are shared graphs whose printed trees grow exponentially
with N: repr(System) and repr(System.phi) show large expressions as their size and
symbols and count the entries past the budget."""

import pickle

import pytest
import sympy as sp

import jetnh as jn
from jetnh import models
from jetnh.algebra import dag
from jetnh.display import TEXT_BUDGET
from jetnh.errors import FrozenError


def test_system_repr_within_budget():
    s = models.get("n_trailer", N=32)
    r = repr(s)
    assert len(r) <= TEXT_BUDGET + 200
    assert r.startswith("System(L=") and "theta32" in r and "more)" not in r.split("dependent")[1]


def test_phi_repr_within_budget_and_read_only():
    s = models.get("n_trailer", N=8)
    assert len(repr(s.phi)) <= TEXT_BUDGET + 200
    assert "distinct parts" in repr(s.phi)
    with pytest.raises(FrozenError):
        s.phi[s.J.qd[0]] = 0
    back = pickle.loads(pickle.dumps(s.phi))
    assert back == s.phi and type(back) is type(s.phi)


def test_small_system_prints_in_full():
    J = jn.JetSpace("x y th")
    x, y, th = J.q
    xd, yd, thd = J.qd
    s = jn.System(J, (xd**2 + yd**2 + thd**2) / 2, [sp.sin(th) * xd - sp.cos(th) * yd],
                  dependent=[y])
    assert repr(s) == (f"System(L={s.L}, constraints=[{s.constraints[0]}], dependent=['y'])")
    assert repr(s.phi) == f"{{y_t: {s.phi[yd]}}}"


@pytest.mark.parametrize("N", [2, 3])
def test_T_equals_the_tree_route(N):
    s = models.get("n_trailer", N=N)
    shared = s.T()
    tree = s.T(on_constraints=False).applyfunc(lambda e: e.xreplace(s.phi))
    point = {sym: sp.Rational(3 + i, 7 + 2 * i) for i, sym in enumerate(
        sorted(set().union(*(dag.free_symbols(e) for e in tree)), key=str))}
    for a, b in zip(shared, tree):
        va, vb = dag.evaluate(a, point), dag.evaluate(b, point)
        assert abs(va - vb) <= 1e-20 * (1 + abs(vb))
    assert not any(v in dag.free_symbols(e) for e in shared for v in s.dependent_velocities)
