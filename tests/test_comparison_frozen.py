"""A ``Comparison`` is immutable as every result: its ``choice`` (the free multipliers'
values, Hoelder "imposed") and ``defects`` (the acceleration differences) refuse
writes, read, copy and pickle as dicts, and the verdict stays what it was."""

import copy
import pickle

import pytest
import sympy as sp

import jetnh as jn
from jetnh.errors import FrozenError


def particle():
    J = jn.JetSpace("x y z")
    x, y, z = J.q
    xd, yd, zd = J.qd
    return jn.System(J, (xd**2 + yd**2 + zd**2) / 2, [zd - y * xd], dependent=[z])


@pytest.mark.parametrize("a, b, convention", [("chetaev", "holder", "imposed"),
                                              ("vakonomic", "holder", "imposed"),
                                              ("vakonomic", "suslov", None)])
def test_choice_and_defects_are_read_only(a, b, convention):
    s = particle()
    kw = {} if convention is None else {"convention": convention}
    c = jn.compare(s, a, b, **kw)
    text = str(c)
    lam = sp.Symbol("lambda_new")
    for name in ("choice", "defects"):
        m = getattr(c, name)
        if m is None:
            continue
        before = dict(m)
        with pytest.raises(FrozenError):
            m[lam] = 1
        with pytest.raises(FrozenError):
            m.update({lam: 1})
        with pytest.raises(FrozenError):
            m.clear()
        assert dict(m) == before and dict(copy.copy(m)) == before
        back = getattr(pickle.loads(pickle.dumps(c)), name)
        assert dict(back) == before
        with pytest.raises(FrozenError):
            back[lam] = 1
    assert str(c) == text
    if c.free:
        assert c.choice and all(k in c.free for k in c.choice)
    assert set(c.defects) == set(s.J.qdd)
