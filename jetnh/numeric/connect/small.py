"""Small dense matrices in compiled code, for connect's few-row matrices (the shooting
Jacobian, the Jacobi fields at one time), where a LAPACK call costs more in its set-up
and copies than in its arithmetic: the singular value decomposition by one-sided Jacobi
rotations (``svd``: Hestenes's method, backward stable, its small singular values as
accurate as LAPACK's), the QR decomposition by Householder reflections (``qr``, LAPACK's
sign convention) and the determinant by Gaussian elimination with partial pivoting
(``det``).  Helpers of compiled callers (``levenberg.step``, ``verdicts``), which
compile them into their own machine code."""

from __future__ import annotations

import functools
import math

import numpy as np

from ..methods._common import entry_point, jit

#: a rotation is skipped where two columns are orthogonal to this relative level
_EPS = 2.220446049250313e-16
#: sweeps of rotations at most (a few suffice for a handful of columns)
_SWEEPS = 60


@jit
def _orthogonalize(W, V, accumulate):
    """Rotate pairs of columns of ``W`` (rows >= columns) in place until all are
    orthogonal; with ``accumulate``, the rotations accumulated in ``V`` (identity on
    entry)."""
    rows, cols = W.shape
    tol = _EPS * rows
    for _ in range(_SWEEPS):
        rotated = False
        for p in range(cols - 1):
            for q in range(p + 1, cols):
                a, b, g = 0.0, 0.0, 0.0
                for i in range(rows):
                    a += W[i, p] * W[i, p]
                    b += W[i, q] * W[i, q]
                    g += W[i, p] * W[i, q]
                if g == 0.0 or abs(g) <= tol * math.sqrt(a) * math.sqrt(b):
                    continue
                rotated = True
                zeta = (b - a) / (2.0 * g)
                t = math.copysign(1.0, zeta) / (abs(zeta) + math.hypot(1.0, zeta))
                c = 1.0 / math.sqrt(1.0 + t * t)
                s = c * t
                for i in range(rows):
                    wp, wq = W[i, p], W[i, q]
                    W[i, p] = c * wp - s * wq
                    W[i, q] = s * wp + c * wq
                if accumulate:
                    for i in range(cols):
                        vp, vq = V[i, p], V[i, q]
                        V[i, p] = c * vp - s * vq
                        V[i, q] = s * vp + c * vq
        if not rotated:
            return


@jit
def _load(A, W):
    """``A`` (k x m) into ``W`` with its long side down (``A^T`` where k < m)."""
    k, m = A.shape
    for i in range(k):
        for j in range(m):
            if k < m:
                W[j, i] = A[i, j]
            else:
                W[i, j] = A[i, j]


@jit
def _norm(W, j) -> float:
    c = 0.0
    for i in range(W.shape[0]):
        c += W[i, j] * W[i, j]
    return math.sqrt(c)


@jit
def svd(A, U, s, V):
    """The thin singular value decomposition of ``A`` (k x m): writes ``U`` (k x r),
    ``s`` (r, largest first) and ``V`` (m x r), r = min(k, m), with A = U diag(s) V^T
    (the columns of U for zero singular values are zero).  Scaled inputs (entries far
    from overflow) only: the column norms are plain sums of squares."""
    k, m = A.shape
    wide = k < m
    rows, cols = (m, k) if wide else (k, m)
    W = np.empty((rows, cols))
    _load(A, W)
    R = np.zeros((cols, cols))
    for j in range(cols):
        R[j, j] = 1.0
    _orthogonalize(W, R, True)
    norms = np.empty(cols)
    for j in range(cols):
        norms[j] = _norm(W, j)
    order = np.argsort(-norms, kind="mergesort")
    for a in range(cols):
        j = order[a]
        c = norms[j]
        s[a] = c
        inv = 1.0 / c if c > 0 else 0.0
        # A = W R^T (or its transpose): W's normalised columns on the long side
        for i in range(rows):
            if wide:
                V[i, a] = W[i, j] * inv
            else:
                U[i, a] = W[i, j] * inv
        for i in range(cols):
            if wide:
                U[i, a] = R[i, j]
            else:
                V[i, a] = R[i, j]


@jit
def smallest_singular_value(A, W) -> float:
    """The smallest of the min(k, m) singular values of ``A`` (k x m; ``W`` a workspace
    of max(k, m) x min(k, m))."""
    _load(A, W)
    _orthogonalize(W, W, False)
    least = math.inf
    for j in range(W.shape[1]):
        least = min(least, _norm(W, j))
    return least if W.shape[1] else 0.0


@jit
def _reflect(H, j, b, X, c):
    """Column ``c`` of ``X`` times the Householder reflection I - b v v^T, v the rows j..
    of column ``j`` of ``H`` (rows above j untouched), in place."""
    dot = 0.0
    for i in range(j, H.shape[0]):
        dot += H[i, j] * X[i, c]
    dot *= b
    for i in range(j, H.shape[0]):
        X[i, c] -= dot * H[i, j]


@jit
def qr(X, Q, R):
    """The thin QR decomposition of ``X`` (rows >= columns) by Householder reflections,
    with LAPACK's signs (R[j, j] = -sign(x_jj) |x_j|, x_jj itself where nothing is below
    it): writes ``Q`` (rows x columns, orthonormal columns) and ``R`` (columns x columns,
    upper triangular).  Entries far from overflow (below 1e150): the norms are plain
    sums of squares."""
    rows, cols = X.shape
    H = X.copy()                   # the reflectors' vectors below the diagonal
    beta = np.zeros(cols)
    for i in range(cols):
        for j in range(cols):
            R[i, j] = 0.0
    for j in range(cols):
        below = 0.0
        for i in range(j + 1, rows):
            below += H[i, j] * H[i, j]
        if below == 0.0:
            # nothing below the diagonal: no reflection (LAPACK's dlarfg), R[j, j] keeps
            # its sign; a zero column gives R[j, j] = 0
            for c in range(j, cols):
                R[j, c] = H[j, c]
            continue
        norm = math.sqrt(H[j, j] * H[j, j] + below)
        alpha = -math.copysign(norm, H[j, j])
        H[j, j] -= alpha
        vv = 0.0
        for i in range(j, rows):
            vv += H[i, j] * H[i, j]
        beta[j] = 2.0 / vv
        R[j, j] = alpha
        for c in range(j + 1, cols):
            _reflect(H, j, beta[j], H, c)
            R[j, c] = H[j, c]
    # Q = H_0 ... H_{cols-1} applied to the first columns of the identity
    for i in range(rows):
        for c in range(cols):
            Q[i, c] = 1.0 if i == c else 0.0
    for j in range(cols - 1, -1, -1):
        if beta[j] == 0.0:
            continue
        for c in range(cols):
            _reflect(H, j, beta[j], Q, c)


@jit
def det(A) -> float:
    """The determinant of the square matrix ``A`` (Gaussian elimination with partial
    pivoting, as LAPACK's getrf)."""
    return det_into(A.copy())


@jit
def det_into(M) -> float:
    """``det`` of the square matrix ``M``, overwriting it with its elimination (a
    caller's loop over many matrices allocates nothing)."""
    n = M.shape[0]
    out = 1.0
    for j in range(n):
        piv = j
        for i in range(j + 1, n):
            if abs(M[i, j]) > abs(M[piv, j]):
                piv = i
        if M[piv, j] == 0.0:
            return 0.0
        if piv != j:
            out = -out
            for c in range(n):
                M[j, c], M[piv, c] = M[piv, c], M[j, c]
        out *= M[j, j]
        for i in range(j + 1, n):
            f = M[i, j] / M[j, j]
            for c in range(j + 1, n):
                M[i, c] -= f * M[j, c]
    return out


def _svd_into(A, U, s, V):
    svd(A, U, s, V)


def _all_finite(a):
    for i in range(a.shape[0]):
        if not math.isfinite(a[i]):
            return False
    return True


def _max_abs(M, cols):
    top = 0.0
    for i in range(M.shape[0]):
        for j in range(cols):
            top = max(top, abs(M[i, j]))
    return top


@functools.cache
def compiled_parts():
    """``(svd, all_finite, max_abs)``: ``_svd_into``, ``_all_finite`` and ``_max_abs``
    compiled (or loaded from the signed store) on first use; ``precompile`` warms them
    as ``connect:small``."""
    from numba import types

    from ..kernels import loop_cache

    out2 = types.Array(types.float64, 2, "C")
    stamp = loop_cache.file_stamp(__file__)
    svd_ = loop_cache.signed_njit(
        _svd_into, types.void(types.Array(types.float64, 2, "A", readonly=True), out2,
                              types.Array(types.float64, 1, "C"), out2),
        stamp, error_model="numpy", nogil=True)
    finite = loop_cache.signed_njit(
        _all_finite, types.boolean(types.Array(types.float64, 1, "A", readonly=True)),
        stamp, error_model="numpy", nogil=True)
    top = loop_cache.signed_njit(
        _max_abs, types.float64(types.Array(types.float64, 2, "A", readonly=True),
                                types.int64), stamp, error_model="numpy", nogil=True)
    return svd_, finite, top


@functools.cache
def _entries():
    """The machine-code entries of ``compiled_parts`` (no type dispatch per call)."""
    return tuple(entry_point(d) for d in compiled_parts())


def all_finite(a) -> bool:
    """Whether every entry of the float64 vector ``a`` is finite (compiled: a third of
    ``np.isfinite(a).all()``, and no floating-point state switch)."""
    if type(a) is not np.ndarray or a.dtype != _FLOAT or a.ndim != 1:
        a = np.asarray(a, dtype=float).reshape(-1)
    return _entries()[1](a)


def finite_vector(a) -> bool:
    """``all_finite`` of a float64 array of one dimension, unchecked: for the caller's
    own arrays (a run's last row)."""
    return _entries()[1](a)


def max_abs(M, cols) -> float:
    """The largest |M[i, j]| over the first ``cols`` columns of the float64 matrix ``M``
    (finite entries: exactly ``np.abs(M[:, :cols]).max()``, 0 for none)."""
    if type(M) is not np.ndarray or M.dtype != _FLOAT or M.ndim != 2:
        M = np.asarray(M, dtype=float)
        if M.ndim != 2:
            raise ValueError(f"max_abs takes a matrix, got shape {M.shape}")
    return _entries()[2](M, min(max(int(cols), 0), M.shape[1]))


_FLOAT = np.dtype(float)


def thin_svd(A):
    """``(U, s, Vt)``: the thin singular value decomposition of the matrix ``A`` (``svd``
    called from Python: a few microseconds less than LAPACK's gesdd through scipy for a
    shooting Jacobian)."""
    A = np.asarray(A, dtype=float)
    if A.ndim != 2:
        raise ValueError(f"thin_svd takes a matrix, got shape {A.shape}")
    k, m = A.shape
    r = min(k, m)
    U, s, V = np.empty((k, r)), np.empty(r), np.empty((m, r))
    if r:
        _entries()[0](A, U, s, V)
    return U, s, V.T
