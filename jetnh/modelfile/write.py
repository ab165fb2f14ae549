"""Writing a model file: ``dumps`` and ``dump``, checked by reading the text back."""

from __future__ import annotations

import math
import os
from pathlib import Path

import sympy as sp

from ..errors import ModelFileError
from ..mechanics import principles
from ..mechanics.system import System
from . import assumptions
from .expression import expression_text
from .model import Model
from .read import loads
from .schema import SIMULATION_KEYS, TIME


def _toml_string(s: str) -> str:
    out = ['"']
    for ch in s:
        if ch == '"':
            out.append('\\"')
        elif ch == "\\":
            out.append("\\\\")
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def _toml_number(v) -> str:
    v = float(v)
    if not math.isfinite(v):
        raise ModelFileError(f"the value {v} cannot be written to a model file")
    return repr(v)


def dumps(system: System | Model, initial=None, *, params=None, principle=None,
          convention=None, description=None, integrals=None, simulation=None) -> str:
    """The model file of ``system`` (its parameters' values: ``system.defaults``, updated
    by ``params``); ``initial`` may hold states and multipliers by name or Symbol.  A
    ``Model`` gives its system and, for the arguments not given, its defaults.  The text
    is checked by reading it back."""
    if isinstance(system, Model):
        model, system = system, system.system
        initial = model.initial if initial is None else initial
        principle = principle or model.principle
        convention = convention or model.convention
        description = model.description if description is None else description
        integrals = model.integrals if integrals is None else integrals
        simulation = model.simulation if simulation is None else simulation
    J = system.J
    if J.fields:
        raise ModelFileError("a system on a jet space with fields cannot be written")
    if J.t.name != TIME:
        raise ModelFileError(f"model files use the time symbol 't', not {J.t.name!r}")

    def key(k):
        return k.name if isinstance(k, sp.Symbol) else str(k)
    values = {key(k): float(v) for k, v in system.defaults.items()}
    values.update({key(k): float(v) for k, v in (params or {}).items()})
    unknown = sorted(set(values) - {p.name for p in system.parameters})
    if unknown:
        raise ModelFileError(f"params has {', '.join(unknown)}, which the system does not "
                             "use")
    names = [p.name for p in system.parameters]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ModelFileError(f"the system has two parameters named {', '.join(twice)} "
                             "(with different assumptions); a model file names each once")
    facts = {p.name: assumptions.facts(p, "dumps") for p in system.parameters}
    missing = [p.name for p in system.parameters if p.name not in values]
    if missing:
        raise ModelFileError(f"the parameters {', '.join(missing)} have no values; give "
                             "them in params= (model files carry a value for each)")
    lines = []
    if system.name:
        lines.append(f"name = {_toml_string(system.name)}")
    if description:
        lines.append(f"description = {_toml_string(description)}")
    lines.append("coordinates = [" + ", ".join(_toml_string(q.name) for q in J.q) + "]")
    if system.dependent:
        lines.append("dependent = [" + ", ".join(_toml_string(d.name)
                                                 for d in system.dependent) + "]")
    lines.append(f"lagrangian = {_toml_string(expression_text(system.L))}")
    lines.append("constraints = [" + ", ".join(_toml_string(expression_text(f))
                                               for f in system.given_constraints) + "]")
    if system.dissipation != 0:
        lines.append(f"dissipation = {_toml_string(expression_text(system.dissipation))}")
    if system.branch is not None:
        lines.append(f"branch = {int(system.branch)}")
    if principle:
        lines.append(f"principle = {_toml_string(principles.canonical(principle))}")
    if convention:
        lines.append(f"convention = {_toml_string(convention)}")
    if values:
        lines.append("\n[parameters]")
        lines += [f"{k} = {_toml_number(v)}" for k, v in sorted(values.items())
                  if k in {p.name for p in system.parameters}]
    if any(facts.values()):
        lines.append("\n[assumptions]")
        lines += [f"{k} = {{ " + ", ".join(f"{f} = {str(v).lower()}" for f, v in held.items())
                  + " }" for k, held in sorted(facts.items()) if held]
    if system.forces:
        lines.append("\n[forces]")
        lines += [f"{q.name} = {_toml_string(expression_text(Q))}"
                  for q, Q in system.forces.items()]
    init = {key(k): float(v) for k, v in (initial or {}).items()}
    lam = {k: v for k, v in init.items() if k.startswith("lambda_")}
    st = {k: v for k, v in init.items() if k not in lam}
    if st:
        lines.append("\n[initial]")
        lines += [f"{k} = {_toml_number(v)}" for k, v in st.items()]
    if lam:
        lines.append("\n[multipliers]")
        lines += [f"{k} = {_toml_number(v)}" for k, v in lam.items()]
    if integrals:
        lines.append("\n[integrals]")
        lines += [f"{k} = {_toml_string(expression_text(sp.sympify(v, strict=True)))}"
                  for k, v in integrals.items()]
    if simulation:
        lines.append("\n[simulation]")
        for k, v in simulation.items():
            kind = SIMULATION_KEYS.get(k)
            text = (_toml_string(v) if kind == "string" else str(int(v)) if kind == "integer"
                    else _toml_number(v))
            lines.append(f"{k} = {text}")
    text = "\n".join(lines) + "\n"
    loads(text, "<written model>")        # what is written must read back
    return text


def dump(system: System, path, initial=None, **kw) -> Path:
    """Write ``dumps(system, initial, **kw)`` to ``path``; returns the path."""
    p = Path(path)
    text = dumps(system, initial, **kw)
    tmp = p.with_name(p.name + f".tmp{os.getpid()}")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(p)
    return p
