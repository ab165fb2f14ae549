"""Numeric checks for symbolic claims: does an expression vanish at random points?

A nonzero analytic expression vanishes at randomly drawn points with probability zero
(the Schwartz-Zippel idea), so evaluation at a few random points decides identities that
``expand`` cannot (trigonometric, radical) without calling ``simplify``.
"""

from __future__ import annotations

import random

import sympy as sp

TOL = 1e-9


def random_point(symbols, rng: random.Random, low: float = 0.2, high: float = 1.3) -> dict:
    """Random Float values for ``symbols``."""
    return {s: sp.Float(rng.uniform(low, high), 30) for s in symbols}


def on_manifold_point(system, symbols, rng: random.Random) -> dict:
    """Random values with the dependent velocities of ``system`` computed from phi."""
    dep_vel = set(system.dependent_velocities)
    syms = set(symbols)
    for phi in system.phi.values():
        syms |= sp.sympify(phi).free_symbols
    vals = random_point(sorted(syms - dep_vel, key=lambda s: s.name), rng)
    for v in system.dependent_velocities:
        vals[v] = sp.sympify(system.phi[v]).xreplace(vals)
    return vals


def value(expr, point: dict) -> complex:
    """``expr`` evaluated at ``point`` (30 digits, returned as complex)."""
    return complex(sp.sympify(expr).xreplace(point).evalf(30))


def vanishes(expr, system=None, points: int = 3, seed: int = 0, tol: float = TOL) -> bool:
    """Whether ``expr`` is zero at ``points`` random points (on the constraint manifold of
    ``system`` when one is given), relative to the size of its terms."""
    expr = sp.sympify(expr)
    if expr == 0:
        return True
    rng = random.Random(seed)
    terms = sp.Add.make_args(expr)
    for _ in range(points):
        pt = (on_manifold_point(system, expr.free_symbols, rng) if system is not None
              else random_point(expr.free_symbols, rng))
        scale = max([1.0] + [abs(value(t, pt)) for t in terms[:50]])
        if not abs(value(expr, pt)) <= tol * scale:
            return False
    return True
