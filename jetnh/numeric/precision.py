"""High-precision reference values of kernel expressions, with a rounding-error bound.

``reference(exprs, values, dps=50, intermediates=())`` evaluates sympy expressions with
mpmath at ``dps`` digits on exact binary64 inputs (``values``: Symbol -> float) and
returns, for each, the value and a first-order running error bound (Higham, *Accuracy
and Stability of Numerical Algorithms*, 2002, sections 3.3 and 4.2) of evaluating the
expression tree in binary64: ``|fl(e) - e| <~ bound``.  Each operation contributes one
rounding of its result, a sum of m terms ``m - 1`` roundings of the sum of their
magnitudes, a function ``f(x)`` its derivative times the error of ``x`` plus one rounding;
so ``bound / |e|`` is large exactly where the evaluation amplifies rounding:
cancellation in a sum (``sum |a_i| >> |sum a_i|``), a division by a small difference, a
function at an ill-conditioned argument.  ``intermediates``: ``[(Symbol, expr), ...]``
computed first and used by name, as the kernels compute the dependent velocities before
the rest (so that no simplification merges the two stages).  The kernels evaluate the
same trees after ``cse``, so a kernel error well above the bound is not rounding.

``cancellation(expr, values)`` names the sum with the largest ratio ``sum |a_i| / |sum
a_i|`` -- the usual cause of a large bound.
"""

from __future__ import annotations

import mpmath
import sympy as sp

from ..errors import JetnhError

U = 2.0 ** -53

_DERIVATIVES = {
    sp.sin: lambda x: mpmath.cos(x), sp.cos: lambda x: -mpmath.sin(x),
    sp.tan: lambda x: 1 / mpmath.cos(x) ** 2, sp.exp: mpmath.exp,
    sp.log: lambda x: 1 / x, sp.sinh: mpmath.cosh, sp.cosh: mpmath.sinh,
    sp.tanh: lambda x: 1 / mpmath.cosh(x) ** 2, sp.atan: lambda x: 1 / (1 + x * x),
    sp.asin: lambda x: 1 / mpmath.sqrt(1 - x * x), sp.acos: lambda x: -1 / mpmath.sqrt(1 - x * x),
    sp.asinh: lambda x: 1 / mpmath.sqrt(1 + x * x),
}
_FUNCTIONS = {sp.sin: mpmath.sin, sp.cos: mpmath.cos, sp.tan: mpmath.tan, sp.exp: mpmath.exp,
              sp.log: mpmath.log, sp.sinh: mpmath.sinh, sp.cosh: mpmath.cosh,
              sp.tanh: mpmath.tanh, sp.atan: mpmath.atan, sp.asin: mpmath.asin,
              sp.acos: mpmath.acos, sp.asinh: mpmath.asinh}


class _Evaluator:
    """Memoized (value, error bound) over the expression DAG, in mpmath."""

    def __init__(self, values):
        self.values = {s: mpmath.mpf(float(v)) for s, v in values.items()}
        self.memo = {}

    def __call__(self, e):
        if e in self.memo:
            return self.memo[e]
        out = self._eval(e)
        self.memo[e] = out
        return out

    def _eval(self, e):
        if e.is_Symbol:
            if e not in self.values:
                raise JetnhError(f"no value for {e} in the reference evaluation")
            return self.values[e], mpmath.mpf(0)
        if e.is_Number:
            v = mpmath.mpf(e.p) / e.q if e.is_Rational else mpmath.mpf(e)
            return v, (mpmath.mpf(0) if mpmath.mpf(float(v)) == v else abs(v))
        if e.is_Add:
            parts = [self(a) for a in e.args]
            v = mpmath.fsum(p[0] for p in parts)
            size = mpmath.fsum(abs(p[0]) for p in parts)
            return v, mpmath.fsum(p[1] for p in parts) + (len(parts) - 1) * size
        if e.is_Mul:
            parts = [self(a) for a in e.args]
            v = mpmath.fprod(p[0] for p in parts)
            err = (len(parts) - 1) * abs(v)
            for i, (_, ei) in enumerate(parts):
                if ei:
                    err += ei * abs(mpmath.fprod(p[0] for j, p in enumerate(parts) if j != i))
            return v, err
        if e.is_Pow:
            (b, eb), x = self(e.base), e.exp
            if not x.is_Number:
                raise JetnhError(f"reference evaluation: non-numeric exponent in {e}")
            xv = mpmath.mpf(x.p) / x.q if x.is_Rational else mpmath.mpf(x)
            v = mpmath.power(b, xv)
            ops = abs(int(x)) if x.is_Integer else 2     # products, a division, a sqrt
            return v, abs(xv * mpmath.power(b, xv - 1)) * eb + ops * abs(v)
        f = type(e)
        if f in _FUNCTIONS and len(e.args) == 1:
            a, ea = self(e.args[0])
            return _FUNCTIONS[f](a), abs(_DERIVATIVES[f](a)) * ea + abs(_FUNCTIONS[f](a))
        raise JetnhError(f"reference evaluation does not know {f.__name__} (in {e})")


def reference(exprs, values, dps=50, intermediates=()) -> list[tuple[float, float]]:
    """``[(value, bound), ...]`` of ``exprs`` at ``values`` (Symbol -> float): the value
    computed with ``dps`` digits, rounded to float, and the rounding-error bound of its
    binary64 evaluation (absolute).  See the module docstring."""
    with mpmath.workdps(dps):
        ev = _Evaluator(values)
        for sym, e in intermediates:
            ev.memo[sym] = ev(sp.sympify(e, strict=True))
        return [(float(v), float(err * U)) for v, err in (ev(sp.sympify(e, strict=True)) for e in exprs)]


def cancellation(expr, values, dps=50, intermediates=()) -> tuple[float, sp.Expr | None]:
    """The sum in ``expr`` (or in ``intermediates``) with the largest cancellation ratio
    ``sum |a_i| / |sum a_i|``, as ``(ratio, subexpression)`` (``(0.0, None)`` without
    sums)."""
    with mpmath.workdps(dps):
        ev = _Evaluator(values)
        for sym, e in intermediates:
            ev.memo[sym] = ev(sp.sympify(e, strict=True))
        ev(sp.sympify(expr, strict=True))
        best, where = 0.0, None
        for e, (v, _) in list(ev.memo.items()):
            if e.is_Add:
                size = mpmath.fsum(abs(ev(a)[0]) for a in e.args)
                ratio = float(size / abs(v)) if v else float("inf")
                if ratio > best:
                    best, where = ratio, e
    return best, where
