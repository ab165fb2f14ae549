"""Numbers at 30 digits for the tests that compare two routes at random points."""

import sympy as sp

PREC = 30


def f30(x) -> sp.Float:
    """``x`` as a 30-digit sympy Float."""
    return sp.Float(x, PREC)


def num(expr, vals):
    """``expr`` at ``vals``, evaluated to 30 digits; it must be a finite number."""
    v = sp.sympify(expr).xreplace(vals).evalf(PREC)
    assert v.is_number and v.is_finite, f"not a finite number: {v}"
    return v
