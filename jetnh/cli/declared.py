"""Defaults declared in jetnh's numerics, read from their source for the help text:
importing ``jetnh.numeric`` loads numba and scipy (about half a CPU second), which
``--help`` should not pay.  Runs read the same values by importing them."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

NUMERIC = Path(__file__).resolve().parents[1] / "numeric"


def declared(module: str, owner: str, name: str):
    """The default of ``name`` in ``owner`` (a class's field or a function's keyword) of
    ``jetnh.numeric.<module>``, read from the module's source; where the source does not
    give it as a literal, imported."""
    path = NUMERIC.joinpath(*module.split("."))
    path = path / "__init__.py" if path.is_dir() else path.with_suffix(".py")
    try:
        tree = ast.parse(path.read_text(encoding="utf-8"))
    except (OSError, SyntaxError):
        tree = None
    for node in tree.body if tree else ():
        if getattr(node, "name", None) != owner:
            continue
        if isinstance(node, ast.ClassDef):
            pairs = [(s.target.id, s.value) for s in node.body
                     if isinstance(s, ast.AnnAssign) and isinstance(s.target, ast.Name)]
        elif isinstance(node, ast.FunctionDef):
            a = node.args
            given = a.posonlyargs + a.args
            pairs = [(x.arg, d) for x, d in zip(given[len(given) - len(a.defaults):],
                                                a.defaults)]
            pairs += [(x.arg, d) for x, d in zip(a.kwonlyargs, a.kw_defaults)]
        else:
            continue
        for key, value in pairs:
            if key == name and value is not None:
                try:
                    return ast.literal_eval(value)
                except ValueError:
                    break
    return _imported(module, owner, name)


def _imported(module: str, owner: str, name: str):
    """The default by import (what a run reads)."""
    import inspect

    obj = getattr(importlib.import_module(f"jetnh.numeric.{module}"), owner)
    if inspect.isclass(obj):
        return getattr(obj, name)
    return inspect.signature(obj).parameters[name].default
