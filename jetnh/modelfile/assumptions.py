"""Assumptions on parameters (``[assumptions]``, e.g. ``m = { positive = true }``): what
sympy may take as known about a parameter (``sp.Symbol("m", positive=True)``), so that
the singular sets of ``jetnh.compare`` leave out ``m = 0``.

A model file holds the facts of ``ASSUMPTIONS``, each true or false; reading builds the
symbol from these booleans (nothing is evaluated) and checks the parameter's value
against them; writing keeps the fewest facts that imply all of the symbol's.
"""

from __future__ import annotations

import sympy as sp

from ..errors import ModelFileError

#: the facts a model file may state about a parameter, the weakest first
ASSUMPTIONS = ("real", "nonzero", "nonnegative", "nonpositive", "integer", "positive",
               "negative")


def symbol(name: str, facts: dict, where: str) -> sp.Symbol:
    """The parameter ``name`` with ``facts`` (assumption -> bool, already type-checked)."""
    unknown = sorted(set(facts) - set(ASSUMPTIONS))
    if unknown:
        raise ModelFileError(f"{where}: {', '.join(map(repr, unknown))} "
                             f"{'is' if len(unknown) == 1 else 'are'} not an assumption a "
                             f"model file holds; the assumptions are {', '.join(ASSUMPTIONS)}")
    try:
        return sp.Symbol(name, **facts)
    except ValueError as exc:              # sympy's InconsistentAssumptions
        raise ModelFileError(f"{where}: the assumptions contradict each other ({exc}); "
                             "keep the ones that hold") from None


def check_value(sym: sp.Symbol, value: float, where: str) -> None:
    """``value`` of the parameter ``sym`` satisfies its assumptions."""
    number = sp.Integer(int(value)) if float(value).is_integer() else sp.Float(value)
    for fact in reversed(ASSUMPTIONS):               # the strongest named first
        want = getattr(sym, f"is_{fact}")
        if want is not None and getattr(number, f"is_{fact}") is not want:
            raise ModelFileError(f"{where}: {sym.name} = {value!r} is not {fact}"
                                 if want else f"{where}: {sym.name} = {value!r} is {fact}, "
                                 f"which its assumptions exclude ({fact} = false)")


def facts(sym: sp.Symbol, where: str) -> dict:
    """The fewest facts of ``ASSUMPTIONS`` that give ``sym``'s assumptions (``{}`` for a
    plain symbol); a ``ModelFileError`` when no such facts give them all."""
    target = sym.assumptions0
    kept = {f: v for f in ASSUMPTIONS if (v := getattr(sym, f"is_{f}")) is not None}
    for fact in ASSUMPTIONS:                  # drop what the stronger ones imply
        rest = {f: v for f, v in kept.items() if f != fact}
        if fact in kept and sp.Symbol(sym.name, **rest).assumptions0 == target:
            kept = rest
    if sp.Symbol(sym.name, **kept).assumptions0 != target:
        stated = ", ".join(f"{k}={v}" for k, v in sorted(target.items())
                           if k != "commutative" or not v)
        raise ModelFileError(f"{where}: the parameter {sym.name} has assumptions ({stated}) "
                             "that a model file cannot hold: it holds "
                             f"{', '.join(ASSUMPTIONS)}, each true or false")
    return kept
