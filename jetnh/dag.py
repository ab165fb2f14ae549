"""Expressions as shared graphs: size, free symbols, atoms and substitution in time
linear in the number of *distinct* subexpressions.

Solved equations share their subexpressions (the accelerations of a chain of k
constraints nest k solves), so as trees they are exponentially larger than as graphs.
sympy's ``free_symbols``, ``atoms``, ``has`` and ``xreplace`` walk the tree; these walk
the graph once, remembering every node they have seen (by identity).
"""

from __future__ import annotations

import sympy as sp


def nodes(expr, cap: int | None = None) -> list:
    """The distinct subexpressions of ``expr``, children before parents (at most ``cap``)."""
    order, seen, stack = [], set(), [(sp.sympify(expr), False)]
    while stack:
        e, expanded = stack.pop()
        if expanded:
            order.append(e)
            if cap is not None and len(order) >= cap:
                break
            continue
        if id(e) in seen:
            continue
        seen.add(id(e))
        stack.append((e, True))
        stack.extend((a, False) for a in e.args if id(a) not in seen)
    return order


def size(expr, cap: int | None = None) -> int:
    """The number of distinct subexpression objects (counted up to ``cap``)."""
    return len(nodes(expr, cap))


def free_symbols(expr) -> set:
    """The free symbols (Symbols among the atoms; no bound variables are expected)."""
    return {e for e in nodes(expr) if isinstance(e, sp.Symbol)}


def atoms(expr, *types) -> set:
    """The subexpressions that are instances of ``types``."""
    return {e for e in nodes(expr) if isinstance(e, types)}


def xreplace(expr, rule: dict):
    """``expr.xreplace(rule)``, rebuilding each distinct subexpression once."""
    done: dict = {}
    for e in nodes(expr):
        if e in rule:
            done[id(e)] = rule[e]
        elif e.args:
            args = tuple(done[id(a)] for a in e.args)
            done[id(e)] = e.func(*args) if any(
                a is not b for a, b in zip(args, e.args)) else e
        else:
            done[id(e)] = e
    return done[id(sp.sympify(expr))]
