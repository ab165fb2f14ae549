"""The compiled pieces of connect against independent numpy routes.

- ``connect.small``: the one-sided Jacobi SVD, the Householder QR and the determinant
  against LAPACK through numpy (reconstruction and singular values to rounding, QR with
  LAPACK's signs where the columns are independent).
- ``verdicts.jacobi_measure`` (compiled over the rows) against its formula in numpy:
  QR of the fields, the subspace and column scalings, with and without frames.
- ``verdicts._gramian_sum`` against the RK4 propagators multiplied by numpy and
  Simpson's sum; ``verdicts._least_chart_measure`` against the permutations
  enumerated, unchanged by the units of rows and columns.
- The verdicts kernel (``codegen.verdicts``: L, df/dq, df/dqdot, dphi/dq, dphi/du) at
  states of a motion against the same derivatives evaluated on the expression graph
  (``dag.evaluate_numpy``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import jetnh as jn
from jetnh.algebra import dag
from jetnh.models import get
from jetnh.numeric.connect import small, verdicts

SEEDS = st.integers(0, 2**32 - 1)


def _matrix(seed, k, m, rank_deficient=False):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((k, m)) * 10.0 ** rng.integers(-3, 3, size=m)
    if rank_deficient and m > 1:
        A[:, -1] = 2.0 * A[:, 0]
    return A


@given(SEEDS, st.integers(1, 6), st.integers(1, 6), st.booleans())
def test_small_svd_reconstructs_and_matches_lapack(seed, k, m, deficient):
    A = _matrix(seed, k, m, deficient)
    U, s, Vt = small.thin_svd(A)
    ref = np.linalg.svd(A, compute_uv=False)
    assert np.all(np.diff(s) <= 0)
    assert np.max(np.abs(s - ref)) <= 1e-14 * ref[0]
    assert np.max(np.abs((U * s) @ Vt - A)) <= 1e-14 * ref[0]
    assert np.max(np.abs(Vt @ Vt.T - np.eye(len(s)))) < 1e-13


@given(SEEDS, st.integers(1, 6), st.integers(1, 6))
def test_small_qr_and_det_match_lapack(seed, k, m):
    k, m = max(k, m), min(k, m)
    A = _matrix(seed, k, m)
    Q, R = np.empty((k, m)), np.empty((m, m))
    small.qr(A, Q, R)
    Qr, Rr = np.linalg.qr(A)
    scale = np.abs(A).max()
    assert np.max(np.abs(Q - Qr)) < 1e-10 and np.max(np.abs(R - Rr)) < 1e-12 * scale
    S = A[:m]
    assert abs(small.det(S) - np.linalg.det(S)) <= 1e-12 * max(
        abs(np.linalg.det(S)), np.prod(np.linalg.norm(S, axis=0)))


def _jacobi_measure_numpy(X, nq, scale=None, frames=None):
    """``verdicts.jacobi_measure``'s formula, in numpy."""
    Q, R = np.linalg.qr(X)
    sign = np.sign(np.prod(np.diagonal(R, axis1=-2, axis2=-1), axis=-1))
    Qq, M = Q[..., :nq, :], X[..., :nq, :]
    if frames is not None:
        Tt = np.swapaxes(frames, -1, -2)
        Qq, M = Tt @ Qq, Tt @ M
        nq = frames.shape[-1]
    norms = np.linalg.norm(M, axis=-2, keepdims=True) if scale is None else scale
    M = M / np.where(norms > 0, norms, 1.0)
    s = np.maximum(np.linalg.svd(Qq, compute_uv=False)[..., -1],
                   np.linalg.svd(M, compute_uv=False)[..., -1])
    if X.shape[-1] != nq:
        return None, s
    d_sub, d_col = np.linalg.det(Qq) * sign, np.linalg.det(M)
    return np.where(np.abs(d_sub) >= np.abs(d_col), d_sub, d_col), s


def _chart_measure_numpy(F, cols):
    """``verdicts._least_chart_measure``'s formula: the least |det| over the largest
    |product| over every permutation (enumerated by ``itertools``) and row."""
    import itertools

    B = F[:, :, cols]
    k = B.shape[1]
    top = max(np.prod(np.abs(B[:, np.arange(k), list(p)]), axis=1).max()
              for p in itertools.permutations(range(k)))
    return np.abs(np.linalg.det(B)).min() / top if top > 0 else 0.0


@given(SEEDS, st.integers(1, 4), st.integers(0, 3), st.integers(1, 9), st.booleans())
def test_least_chart_measure_matches_permutations_and_ignores_units(seed, k, extra, rows,
                                                                     deficient):
    """``verdicts._least_chart_measure`` (compiled: dynamic programming over column sets,
    ``small.det``) against the permutations enumerated and numpy's determinants,
    rank-deficient rows included; the same after scaling rows (the constraints' units)
    and columns (the coordinates' units) by powers of ten up to 1e8; and
    ``small.max_abs`` against numpy."""
    n = k + extra
    rng = np.random.default_rng(seed)
    F = rng.standard_normal((rows, k, n)) * 10.0 ** rng.integers(-2, 2, size=(rows, 1, n))
    if deficient and k > 1:
        F[rows // 2, -1] = 3.0 * F[rows // 2, 0]
    cols = np.sort(rng.choice(n, size=k, replace=False)).astype(np.int64)
    want = float(_chart_measure_numpy(F, cols))
    got = verdicts._compiled("edge")(F, cols)
    assert abs(got - want) <= 1e-9 * max(1.0, want)
    assert 0.0 <= got <= math.factorial(k)             # |det| <= k! times the largest term
    scaled = (F * 10.0 ** rng.integers(-8, 9, size=(1, k, 1))
              * 10.0 ** rng.integers(-8, 9, size=(1, 1, n)))
    assert abs(verdicts._compiled("edge")(scaled, cols) - got) <= 1e-9 * max(1.0, got)
    if deficient and k > 1:
        assert got < 1e-12
    M = F[0]
    assert small.max_abs(M, n - extra) == float(np.abs(M[:, :n - extra]).max())


@given(SEEDS, st.integers(1, 4), st.integers(1, 12), st.booleans(), st.booleans())
def test_jacobi_measure_matches_its_numpy_formula(seed, nq, rows, scaled, framed):
    rng = np.random.default_rng(seed)
    m = int(rng.integers(1, nq + 1))
    X = rng.standard_normal((rows, 2 * nq, m)) * 10.0 ** rng.integers(-3, 3, size=m)
    scale = np.abs(rng.standard_normal((1, m))) + 0.1 if scaled else None
    frames = None
    if framed and nq > 1:
        frames = np.linalg.qr(rng.standard_normal((rows, nq, nq)))[0][:, :, :nq - 1]
    d, s = verdicts.jacobi_measure(X, nq, scale, frames)
    d_ref, s_ref = _jacobi_measure_numpy(X, nq, scale, frames)
    assert np.allclose(s, s_ref, rtol=1e-12, atol=1e-14)
    assert (d is None) == (d_ref is None)
    if d is not None:
        assert np.allclose(d, d_ref, rtol=1e-11, atol=1e-13)
    # one point, without the batch dimension
    d1, s1 = verdicts.jacobi_measure(X[0], nq, scale,
                                     None if frames is None else frames[0])
    assert np.shape(s1) == () and abs(s1 - s_ref[0]) <= 1e-12 * max(1.0, s_ref[0])


@given(SEEDS, st.integers(1, 4), st.integers(1, 3))
def test_gramian_sum_matches_numpy_products(seed, n, m):
    rng = np.random.default_rng(seed)
    steps, h = 20, 0.05
    A = rng.standard_normal((2 * steps + 1, n, n))
    B = rng.standard_normal((2 * steps + 1, n, m))
    W = np.empty((n, n))
    verdicts._compiled("gramian")(A, B, h, W)
    I = np.eye(n)
    A0, Am, A1 = A[0:-1:2], A[1::2], A[2::2]
    K2 = Am @ (I + 0.5 * h * A0)
    K3 = Am @ (I + 0.5 * h * K2)
    K4 = A1 @ (I + h * K3)
    P = I + h / 6.0 * (A0 + 2 * K2 + 2 * K3 + K4)
    G = [I]
    for Pj in P[::-1]:
        G.append(G[-1] @ Pj)
    G = np.array(G[::-1])                          # Phi(t1, s_j)
    w = np.full(steps + 1, 2.0)
    w[1::2] = 4.0
    w[0] = w[-1] = 1.0
    GB = G @ B[::2]
    ref = np.einsum("j,jac,jbc->ab", w * h / 3.0, GB, GB)
    assert np.allclose(W, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())


@pytest.mark.parametrize("model, principle, end", [
    ("rolling_disk", "vakonomic", {"x": 0.0, "y": 0.3, "phi": 0.0, "psi": 0.0}),
    ("heisenberg", "vakonomic", {"x": 1.0, "y": 0.5, "z": 0.2}),
])
def test_verdicts_kernel_matches_the_graph(model, principle, end):
    system = get(model)
    start = {c: 0.0 for c in end} if model == "rolling_disk" else {
        "x": 0.0, "y": 0.0, "z": 0.0}
    c = jn.connect(system, principle, start, end, (0.0, 1.0))
    tr = c.trajectory
    scene = tr.scene
    values = verdicts._entries(scene, tr.t, tr.y, tr._p)
    # the graph at the same states: the dependent velocities from the aux kernel
    J = system.J
    aux = np.empty((len(tr.t), tr.layout.n_aux))
    tr._kernels.aux_rows(tr.t, np.ascontiguousarray(tr.y), tr._p, aux)
    col = {n: i for i, n in enumerate(scene.state_names)}
    point = {J.t: tr.t, **{s: tr.y[:, col[s.name]] for s in J.q},
             **{v: tr.y[:, col[v.name]] for v in system.independent_velocities},
             **{v: aux[:, a] for a, v in enumerate(system.dependent_velocities)},
             **{s: scene.params[s.name] for s in system.parameters}}
    q, us = list(J.q), list(system.independent_velocities)
    phis = [system.phi[v] for v in system.dependent_velocities]
    exprs = ([system.L] + list(dag.jacobian(list(system.constraints), q))
             + list(system.jacobian) + list(dag.jacobian(phis, q))
             + list(dag.jacobian(phis, us)))
    ref = np.stack([np.broadcast_to(np.asarray(v, dtype=float), tr.t.shape)
                    for v in dag.evaluate_numpy(exprs, point)], axis=-1)
    assert values.shape[1] == ref.shape[1]          # no holonomic block here
    assert np.allclose(values, ref, rtol=1e-12, atol=1e-12)


@given(SEEDS, st.integers(1, 5), st.integers(1, 3), st.booleans())
def test_kinetic_weights_match_numpy(seed, n, m, per_row):
    """``verdicts._kinetic_weights`` (compiled) against B / sqrt(the path's mean of
    |diag(B^T H B)|) in numpy, one H for every row or one per row; a zero column of B
    is code 2 (the caller reads the whole of K), a NaN in H code 1 (no weighting)."""
    rng = np.random.default_rng(seed)
    rows = 9
    B = rng.standard_normal((rows, n, m)) * 10.0 ** rng.integers(-3, 3, size=m)
    H = rng.standard_normal((rows if per_row else 1, n, n))
    H = H + np.swapaxes(H, 1, 2)
    out = np.empty_like(B)
    assert verdicts._compiled("kinetic")(B, H, out) == 0
    K = np.swapaxes(B, 1, 2) @ H @ B
    ref = B / np.sqrt(np.abs(np.diagonal(K, axis1=1, axis2=2)).mean(axis=0))
    assert np.allclose(out, ref, rtol=1e-11, atol=0.0)
    zero = B.copy()
    zero[:, :, -1] = 0.0
    assert verdicts._compiled("kinetic")(zero, H, out) == 2
    bad = H.copy()
    bad[0, 0, -1] = np.nan
    assert verdicts._compiled("kinetic")(B, bad, out) == 1


@pytest.mark.parametrize("model, start, end, constant", [
    ("heisenberg", {"x": 0.0, "y": 0.0, "z": 0.0}, {"x": 1.0, "y": 0.5, "z": 0.2}, True),
    ("chaplygin_sleigh", {"x": 0.0, "y": 0.0, "theta": 0.0},
     {"x": 0.5, "y": 0.1, "theta": 0.3}, False),       # mass matrix depends on theta
])
def test_hessian_values_and_input_weights_match_the_graph(model, start, end, constant):
    """``verdicts._hessian_values`` (a Hessian of the parameters alone evaluated once
    per scene) against ``dag.evaluate_numpy`` of the Hessian at every sample of the
    motion, bit for bit; the Gramian's weighted inputs (``_weighted_inputs``, compiled)
    against B / sqrt(``_diagonal_scale``(B^T H B)'s mean) in numpy."""
    c = jn.connect(get(model), "vakonomic", start, end, (0.0, 1.0))
    tr, samples = c.trajectory, c._samples
    scene, times, ys = tr.scene, samples.grid, samples.grid_y
    system = scene.system
    aux = np.empty((times.size, tr.layout.n_aux))
    tr._kernels.aux_rows(times, np.ascontiguousarray(ys), tr._p, aux)
    for multipliers in (False, True):
        states, v, H = verdicts._hessian(scene, multipliers)
        point = {system.J.t: times, **{s: scene.params[s.name] for s in system.parameters},
                 **{s: ys[:, i] for i, s in enumerate(states) if s is not None},
                 **{s: aux[:, a] for a, s in enumerate(system.dependent_velocities)}}
        n = len(v)
        ref = np.stack([np.broadcast_to(np.asarray(h, dtype=float), times.shape)
                        for h in dag.evaluate_numpy(H, point)], axis=-1).reshape(-1, n, n)
        ref = 0.5 * (ref + np.swapaxes(ref, 1, 2))
        got = verdicts._hessian_values(tr, times, ys, multipliers)
        assert (got.ndim == 2) == constant      # (f linear in the velocities here)
        assert np.array_equal(np.broadcast_to(got, ref.shape), ref)
    A, B = verdicts._linearized(tr, times, ys)
    H = verdicts._hessian_values(tr, times, ys, multipliers=False)
    K = np.swapaxes(B, 1, 2) @ H @ B
    ref = B / np.sqrt(verdicts._diagonal_scale(K).mean(axis=0))
    got = verdicts._weighted_inputs(tr, times, ys, np.ascontiguousarray(B))
    assert np.allclose(got, ref, rtol=1e-12, atol=0.0)
