"""The sums of an explicit Runge-Kutta step, written out for one method.

A step of an ``ExplicitRK`` method is three kinds of sums over its stages: the stage
arguments ``y + h sum_r A[s, r] K[r]``, the new state ``y + (h / b_den) sum_r B[r] K[r]``
and the error estimate (rows ``E``, ``E3``).  ``functions(method)`` writes them as Python
source with the method's nonzero coefficients as literals (a coefficient 1 as no
product), one statement per stage, and compiles them to helpers that the loop inlines
(``loop._specialised``).  Zero coefficients are not multiplied (RK4's stages have one
term each, DOP853's tableau is half zeros), which a loop over the tableau, even with the
tableau a compile-time constant, cannot skip: ``0 * x`` is not foldable in IEEE
arithmetic.

Rounding: every sum keeps the order of the tableau loop it replaces (``acc = 0; acc +=
A[s, r] K[r]`` for r = 0, 1, ...), and adding ``0 * x = +-0`` or multiplying by 1 is
exact, so the results are those of the tableau loop bit for bit, up to the sign of a zero
sum; only where a stage is infinite or NaN do the two differ in which later quantity
first turns non-finite (the step is refused as non-finite either way).
"""

from __future__ import annotations

import math

import numpy as np

from ._common import inline

#: error estimators (the ``ExplicitRK.error`` codes: none, embedded, DOP853's pair)
NONE, EMBEDDED, DOP853 = 0, 1, 2


def _sum(coefficients, row="K[{r}, i]") -> str:
    """``c_0 K[0, i] + c_2 K[2, i] + ...`` over the nonzero coefficients, left to right
    (``0.0`` if there is none)."""
    terms = []
    for r, c in enumerate(np.asarray(coefficients, dtype=float)):
        if c == 0.0:
            continue
        k = row.format(r=r)
        terms.append(k if c == 1.0 else f"{float(c)!r} * {k}")
    return " + ".join(terms) if terms else "0.0"


def source(method) -> str:
    """The helpers of ``method`` (an ``ExplicitRK``) as Python source:

    ``stages(rhs, t, h, y, K, ytmp, p)``: stages 1 .. n_stages - 1 (K[0] is given);
    ``new_state(h, y, K, y_new)``; ``error(h, y, y_new, K, rtol, atol)``: the scaled error
    of the step (<= 1: accept), over the stages and K[n_stages] = f(t + h, y_new)."""
    ns = method.n_stages
    C, A = np.asarray(method.C, dtype=float), np.asarray(method.A, dtype=float)
    lines = ["def stages(rhs, t, h, y, K, ytmp, p):"]
    for s in range(1, ns):
        node = "h" if C[s] == 1.0 else f"{float(C[s])!r} * h"
        lines += ["    for i in range(y.shape[0]):",
                  f"        ytmp[i] = y[i] + h * ({_sum(A[s, :s])})",
                  f"    rhs(t + {node}, ytmp, p, K[{s}])"]
    lines += ["    return None", "",
              "def new_state(h, y, K, y_new):",
              f"    hb = h / {float(method.b_den)!r}",
              "    for i in range(y.shape[0]):",
              f"        y_new[i] = y[i] + hb * ({_sum(method.B)})", "",
              "def error(h, y, y_new, K, rtol, atol):"]
    E = np.asarray(method.E, dtype=float)[:ns + 1]
    if method.error == DOP853:
        E3 = np.asarray(method.E3, dtype=float)[:ns + 1]
        lines += ["    n = y.shape[0]",
                  "    e5 = 0.0",
                  "    e3 = 0.0",
                  "    for i in range(n):",
                  f"        a5 = {_sum(E)}",
                  f"        a3 = {_sum(E3)}",
                  "        sc = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol",
                  "        e5 += (a5 / sc) ** 2",
                  "        e3 += (a3 / sc) ** 2",
                  "    if e5 == 0.0 and e3 == 0.0:",
                  "        return 0.0",
                  "    return abs(h) * e5 / math.sqrt((e5 + 0.01 * e3) * n)"]
    elif method.error == EMBEDDED:
        lines += ["    n = y.shape[0]",
                  "    err = 0.0",
                  "    for i in range(n):",
                  f"        e = {_sum(E)}",
                  "        sc = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol",
                  "        err += (h * e / sc) ** 2",
                  "    return math.sqrt(err / n)"]
    else:
        lines += ["    return 0.0"]
    return "\n".join(lines) + "\n"


def functions(method) -> dict:
    """``{"stages": ..., "new_state": ..., "error": ...}``: the helpers of ``source``,
    compiled to be inlined into the loop that calls them."""
    namespace = {"math": math}
    exec(compile(source(method), f"<jetnh sums of {method.name}>", "exec"), namespace)
    return {name: inline(namespace[name]) for name in ("stages", "new_state", "error")}
