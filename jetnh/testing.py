"""Numeric checks for symbolic claims: does an expression vanish at random points?

A nonzero analytic expression vanishes at randomly drawn points with probability zero
(the Schwartz-Zippel idea), so evaluation at a few random points decides identities that
``expand`` cannot (trigonometric, radical) without calling ``simplify``.
"""

from __future__ import annotations

import random

import mpmath
import sympy as sp

from . import dag

TOL = 1e-9


def random_point(symbols, rng: random.Random, low: float = 0.2, high: float = 1.3) -> dict:
    """Random Float values for ``symbols``."""
    return {s: sp.Float(rng.uniform(low, high), 30) for s in symbols}


def on_manifold_point(system, symbols, rng: random.Random) -> dict:
    """Random values with the dependent velocities of ``system`` computed from phi."""
    dep_vel = set(system.dependent_velocities)
    syms = set(symbols)
    for phi in system.phi.values():
        syms |= dag.free_symbols(phi)
    vals = random_point(sorted(syms - dep_vel, key=lambda s: s.name), rng)
    with mpmath.workdps(30):
        for v in system.dependent_velocities:
            vals[v] = dag.to_sympy(dag.evaluate(system.phi[v], vals))
    return vals


def value(expr, point: dict) -> complex:
    """``expr`` evaluated at ``point`` (30 digits, returned as complex)."""
    return complex(dag.evaluate(expr, point))


def vanishes(expr, system=None, points: int = 3, seed: int = 0, tol: float = TOL,
             derived=None) -> bool:
    """Whether ``expr`` is zero at ``points`` random points (on the constraint manifold of
    ``system`` when one is given), relative to the size of its terms.  ``derived`` maps
    symbols to expressions of the others, evaluated at each point (e.g. a branch of
    multiplier values)."""
    expr = sp.sympify(expr)
    if expr == 0:
        return True
    rng = random.Random(seed)
    terms = list(sp.Add.make_args(expr))[:50]
    syms = dag.free_symbols(expr)
    derived = dict(derived or {})
    for _ in range(points):
        pt = (on_manifold_point(system, syms, rng) if system is not None
              else random_point(syms, rng))
        for s, e in derived.items():
            pt[s] = dag.evaluate(e, pt)
        val, *parts = map(complex, dag.evaluate([expr, *terms], pt))
        scale = max([1.0] + [abs(v) for v in parts])
        if not abs(val) <= tol * scale:
            return False
    return True
