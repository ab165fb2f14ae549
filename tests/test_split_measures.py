"""One measure of how regular a split is: m_beta = det(A_beta)^2 / det(A A^T), A =
df/dqdot, computed in one place (``atlas.measures_at``) for the charts a run switches
between (``Atlas.measures``) and for the split of largest measure among every choice of
k coordinates (``regular.best``, where a system's own split is singular).  Second
routes: LAPACK's determinants and the Cauchy-Binet formula (the measures of all
choices sum to 1).
"""

from __future__ import annotations

from itertools import combinations
from types import SimpleNamespace

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st

import jetnh as jn
from jetnh.algebra import dag
from jetnh.numeric import atlas, regular


def _stub(k, n):
    """What ``regular.best`` reads of a system: its coordinates' names and k."""
    return SimpleNamespace(J=SimpleNamespace(q=[sp.Symbol(f"q{i}") for i in range(n)]), k=k)


@settings(deadline=None)
@given(k=st.integers(1, 4), extra=st.integers(0, 2), seed=st.integers(0, 2**32 - 1))
def test_measures_against_lapack_cauchy_binet_and_best(k, extra, seed):
    n = k + extra
    A = np.random.default_rng(seed).normal(size=(k, n))
    choices = list(combinations(range(n), k))
    m = atlas.measures_at(A, choices)
    gram = np.linalg.det(A @ A.T)
    want = [np.linalg.det(A[:, list(c)]) ** 2 / gram for c in choices]
    assert np.allclose(m, want, rtol=1e-9, atol=1e-13)
    assert sum(m) == pytest.approx(1.0, abs=1e-12)
    split, top = regular.best(_stub(k, n), A)
    i = int(np.argmax(m))
    assert top == m[i] and split == [f"q{c}" for c in choices[i]]
    assert atlas.measures_at(np.zeros((k, n)), choices) == [0.0] * len(choices)


def test_best_is_the_largest_of_the_atlas_measures_to_the_bit():
    """The 2-trailer (k = 3 of n = 5) with its dependent coordinates out of order: at
    random points the split ``regular.best`` picks and its measure are the largest of
    ``Atlas.measures`` exactly; the choices outside the atlas (minors identically
    zero) measure 0 there."""
    from jetnh.models import initial, n_trailer

    base = n_trailer()
    sys_ = base.with_split([s.name for s in reversed(base.dependent)])
    at = atlas.Atlas(jn.Scene(sys_, "chetaev", initial=_initial(sys_, base, initial),
                              t_span=(0.0, 1.0)))
    J = sys_.J
    names = [q.name for q in J.q]
    rng = np.random.default_rng(5)
    for _ in range(8):
        point = {s: v for s, v in zip([*J.q, *J.qd], rng.uniform(-2, 2, 2 * J.n))}
        point.update({s: float(v) for s, v in sys_.defaults.items()})
        A = np.array([float(v) for v in dag.evaluate_numpy(list(sys_.jacobian), point)]
                     ).reshape(sys_.k, J.n)
        m = at.measures(A)
        split, top = regular.best(sys_, A)
        i = int(np.argmax(m))
        assert top == m[i]
        assert split == sorted(at.splits[i], key=names.index)
        every = dict(zip(combinations(range(J.n), sys_.k),
                         atlas.measures_at(A, list(combinations(range(J.n), sys_.k)))))
        for cols, mb in zip(at.columns, m):
            assert every[tuple(cols)] == mb
        assert sum(every.values()) == pytest.approx(1.0, abs=1e-12)


def _initial(sys_, base, initial):
    """The catalogue's initial values of ``base`` in the split of ``sys_``."""
    values = dict(initial("n_trailer"))
    return {k: v for k, v in values.items()
            if k in {s.name for s in (*sys_.J.q, *sys_.independent_velocities)}}
