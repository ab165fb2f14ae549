"""The schema of a model file: its keys, their types, the names it declares, and the
``Model`` it describes (the format: ``jetnh.modelfile``).

``from_dict`` checks already-parsed TOML data key by key, parses every expression with
``parse_expression`` (one budget for the whole file) and builds the ``System``, without
solving its constraints.
"""

from __future__ import annotations

import keyword
import math
import re
import unicodedata
from pathlib import Path

import sympy as sp

from ..errors import JetnhError, ModelFileError, PrincipleError
from ..geometry.jet import JetSpace
from ..mechanics import principles
from ..mechanics.system import System
from . import assumptions, limits
from .expression import CONSTANTS, FUNCTIONS, Budget, parse_expression, real_somewhere
from .model import Model
from .text import refuse_non_ascii, shorten

TIME = "t"

TOP_KEYS = {"name", "description", "coordinates", "dependent", "lagrangian", "constraints",
            "forces", "dissipation", "branch", "principle", "convention", "parameters",
            "initial", "multipliers", "integrals", "simulation", "assumptions"}
REQUIRED_KEYS = ("coordinates", "lagrangian")
SIMULATION_KEYS = {"t_start": "number", "t_end": "number", "method": "string",
                   "rtol": "number", "atol": "number", "points": "integer"}

_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9]*(?:_[A-Za-z0-9]+)*$")
_JET = re.compile(r"^(.+?)_(t+)$")


def _type_name(v) -> str:
    return {str: "a string", int: "an integer", float: "a number", bool: "a boolean",
            list: "a list", dict: "a table"}.get(type(v), type(v).__name__)


def _expect(where, value, kind):
    ok = {"string": lambda v: isinstance(v, str),
          "number": lambda v: isinstance(v, (int, float)) and not isinstance(v, bool),
          "integer": lambda v: isinstance(v, int) and not isinstance(v, bool),
          "boolean": lambda v: isinstance(v, bool),
          "table": lambda v: isinstance(v, dict),
          "list of strings": lambda v: isinstance(v, list) and all(isinstance(x, str) for x in v),
          }[kind](value)
    if not ok:
        raise ModelFileError(f"{where} must be {'an' if kind[0] in 'aeiou' else 'a'} {kind}, "
                             f"got {_type_name(value)} ({shorten(repr(value))})")
    if kind == "number":
        try:
            finite = math.isfinite(float(value))
        except OverflowError:                  # an int beyond double precision
            finite = False
        if not finite:
            raise ModelFileError(f"{where} must be finite (a number within double "
                                 f"precision), got {shorten(repr(value))}")
    return value


_BIDI = set(range(0x202A, 0x202F)) | set(range(0x2066, 0x206A))


def _check_text(where, text: str, allowed: str):
    """Free text (name, description): any Unicode but control characters (terminal
    escapes) and bidirectional overrides (text that displays other than it reads)."""
    for i, ch in enumerate(text):
        if ch not in allowed and (unicodedata.category(ch) == "Cc" or ord(ch) in _BIDI):
            raise ModelFileError(f"{where}: the control character U+{ord(ch):04X} at "
                                 f"position {i + 1} is not allowed in text; remove it")


def _check_name(where, name, reserved):
    if not isinstance(name, str):
        raise ModelFileError(f"{where}: names are strings, got {_type_name(name)} "
                             f"({shorten(repr(name))})")
    refuse_non_ascii(name, f"{where}: the name {shorten(name)!r}")
    if not _NAME.fullmatch(name) or keyword.iskeyword(name):
        raise ModelFileError(
            f"{where}: {name!r} is not a usable name (letters, digits and single underscores, "
            "starting with a letter; not a Python keyword)")
    if name in reserved:
        raise ModelFileError(f"{where}: the name {name!r} is reserved ({reserved[name]})")


def _check_keys(data, S):
    """Every key of the TOML data is a str of ASCII characters (names are ASCII)."""
    stack = [("", data)]
    while stack:
        prefix, table = stack.pop()
        for k, v in table.items():
            if not isinstance(k, str):
                raise ModelFileError(f"{S}: the key {shorten(repr(k))} is a "
                                     f"{type(k).__name__}; keys are names (strings)")
            refuse_non_ascii(k, f"{S}: the key {prefix}{shorten(k)!r}")
            if isinstance(v, dict):
                stack.append((f"{prefix}{k}.", v))


def from_dict(data: dict, source: str = "<string>") -> Model:
    """A ``Model`` from already-parsed TOML data (a dict)."""
    try:
        return _from_dict(data, source)
    except JetnhError:
        raise
    except RecursionError:
        raise ModelFileError(f"{source}: the model is nested too deeply to read") from None
    except (MemoryError, OverflowError, ArithmeticError, ValueError) as exc:
        raise ModelFileError(f"{source}: the model cannot be built ({type(exc).__name__}: "
                             f"{shorten(str(exc))}); simplify it") from None
    except Exception as exc:
        raise ModelFileError(f"{source}: the model cannot be read (internal: "
                             f"{type(exc).__name__}: {shorten(str(exc))})") from exc


def _from_dict(data: dict, source: str) -> Model:
    S = source
    if not isinstance(data, dict):
        raise ModelFileError(f"{S}: a model file is a TOML table")
    _check_keys(data, S)
    unknown = sorted(set(data) - TOP_KEYS)
    if unknown:
        raise ModelFileError(f"{S}: unknown key{'s' if len(unknown) > 1 else ''} "
                             f"{', '.join(map(repr, unknown))}; the keys are "
                             f"{', '.join(sorted(TOP_KEYS))}")
    missing = [k for k in REQUIRED_KEYS if k not in data]
    if missing:
        raise ModelFileError(f"{S}: missing key{'s' if len(missing) > 1 else ''} "
                             f"{', '.join(map(repr, missing))}")
    name = _expect(f"{S}: 'name'", data.get("name", Path(S).stem if S != "<string>" else ""),
                   "string")
    description = _expect(f"{S}: 'description'", data.get("description", ""), "string")
    _check_text(f"{S}: 'name'", name, "")
    _check_text(f"{S}: 'description'", description, "\n\t")

    # ---------------------------------------------------------------- names
    coords = _expect(f"{S}: 'coordinates'", data["coordinates"], "list of strings")
    if not coords:
        raise ModelFileError(f"{S}: 'coordinates' is empty; give at least one name")
    if len(coords) > limits.MAX_COORDINATES:
        raise ModelFileError(f"{S}: {len(coords)} coordinates; the limit is "
                             f"{limits.MAX_COORDINATES} (reading builds the constraint "
                             "Jacobian); raise jetnh.modelfile.MAX_COORDINATES to read larger "
                             "models")
    reserved = {TIME: "time", **{f: "a function" for f in FUNCTIONS},
                **{c: "a constant" for c in CONSTANTS}}
    for c in coords:
        _check_name(f"{S}: coordinates", c, reserved)
        m = _JET.match(c)
        if m:
            raise ModelFileError(f"{S}: coordinates: {c!r} ends in '_{m.group(2)}', which "
                                 "marks velocities (x_t); rename the coordinate")
    if len(set(coords)) != len(coords):
        dup = sorted({c for c in coords if coords.count(c) > 1})
        raise ModelFileError(f"{S}: coordinates: {', '.join(dup)} given twice")
    try:
        J = JetSpace(coords)
    except JetnhError as exc:
        raise ModelFileError(f"{S}: coordinates: {exc}") from None
    names = {TIME: J.t}
    names.update({q.name: q for q in J.q})
    names.update({v.name: v for v in J.qd})
    reserved.update({n: "a coordinate or velocity" for n in names if n != TIME})

    params_in = _expect(f"{S}: [parameters]", data.get("parameters", {}), "table")
    params = {}
    for k, v in params_in.items():
        _check_name(f"{S}: [parameters]", k, reserved)
        if _JET.match(k):
            raise ModelFileError(f"{S}: [parameters]: {k!r} ends in '_t...', which marks "
                                 "velocities; rename the parameter")
        params[k] = float(_expect(f"{S}: [parameters] {k}", v, "number"))
    names.update(_parameter_symbols(S, params, _expect(f"{S}: [assumptions]",
                                                       data.get("assumptions", {}), "table")))
    hint = {}
    for q in J.q:
        for order in (2, 3, 4):
            hint[f"{q.name}_{'t' * order}"] = (
                "accelerations and higher jets are not allowed here (the Lagrangian and "
                "the constraints are first order):")

    # ---------------------------------------------------------------- expressions
    budget = Budget()
    L = parse_expression(data["lagrangian"], names, f"{S}: lagrangian", hint, budget)
    cons_in = data.get("constraints", [])
    _expect(f"{S}: 'constraints'", cons_in, "list of strings")
    if len(cons_in) > limits.MAX_CONSTRAINTS:
        raise ModelFileError(f"{S}: {len(cons_in)} constraints; the limit is "
                             f"{limits.MAX_CONSTRAINTS} (reading checks their rank and chooses the "
                             "split); raise jetnh.modelfile.MAX_CONSTRAINTS to read larger "
                             "models")
    if len(coords) * len(cons_in) > limits.MAX_SPLIT_COST:
        raise ModelFileError(f"{S}: {len(coords)} coordinates times {len(cons_in)} "
                             f"constraints is {len(coords) * len(cons_in)}, more than "
                             f"{limits.MAX_SPLIT_COST} (reading tests the rank of the constraints "
                             "for each candidate split); give a smaller model or raise "
                             "jetnh.modelfile.MAX_SPLIT_COST")
    before = budget.used_nodes
    cons = [parse_expression(c, names, f"{S}: constraints[{i}]", hint, budget)
            for i, c in enumerate(cons_in)]
    jac = len(coords) * (budget.used_nodes - before)
    if jac > limits.MAX_JACOBIAN_COST:
        raise ModelFileError(
            f"{S}: constraints: {len(coords)} coordinates times "
            f"{budget.used_nodes - before} syntax nodes of constraints is {jac}, more than "
            f"{limits.MAX_JACOBIAN_COST} (reading differentiates every constraint by every "
            "velocity); write shorter constraints or raise jetnh.modelfile.MAX_JACOBIAN_COST")
    forces_in = _expect(f"{S}: [forces]", data.get("forces", {}), "table")
    forces = {}
    for k, v in forces_in.items():
        refuse_non_ascii(k, f"{S}: [forces] {shorten(k)!r}")
        if k not in coords:
            raise ModelFileError(f"{S}: [forces]: {k!r} is not one of the coordinates "
                                 f"{coords} (a generalized force Q_s is keyed by its "
                                 "coordinate)")
        forces[k] = parse_expression(_expect(f"{S}: [forces] {k}", v, "string"), names,
                                     f"{S}: [forces] {k}", hint, budget)
    dissipation = None
    if "dissipation" in data:
        dissipation = parse_expression(_expect(f"{S}: 'dissipation'", data["dissipation"],
                                               "string"), names, f"{S}: dissipation", hint,
                                       budget)
    used = set().union(L.free_symbols, *(c.free_symbols for c in cons),
                       *(f.free_symbols for f in forces.values()),
                       dissipation.free_symbols if dissipation is not None else set())
    unused = sorted(k for k in params if names[k] not in used)
    if unused:
        raise ModelFileError(f"{S}: [parameters]: {', '.join(unused)} "
                             f"{'is' if len(unused) == 1 else 'are'} used neither in the "
                             "Lagrangian, the constraints nor the forces")

    # jetnh decides the rank of the constraints at random points; where they are never
    # real it falls back to symbolic linear algebra, which can take unbounded time
    if cons and not real_somewhere(cons, set().union(*(c.free_symbols for c in cons))):
        raise ModelFileError(
            f"{S}: constraints: the constraints are not all finite and real at any of "
            f"{limits.SAMPLE_POINTS} random points (every coordinate, velocity, parameter and t in "
            "[0.31, 1.37]); jetnh works with real expressions: check the domains of the "
            "functions (e.g. acos(3 + x**2) is complex everywhere, log(x - 5) there)")

    dependent = data.get("dependent")
    if dependent is not None:
        _expect(f"{S}: 'dependent'", dependent, "list of strings")
        for d in dependent:
            refuse_non_ascii(d, f"{S}: dependent: {shorten(d)!r}")
            if d not in coords:
                raise ModelFileError(f"{S}: dependent: {d!r} is not one of the coordinates "
                                     f"{coords}")
    branch = data.get("branch")
    if branch is not None:
        _expect(f"{S}: 'branch'", branch, "integer")
        if branch < 0:
            raise ModelFileError(f"{S}: 'branch' must be >= 0, got {branch}")
    principle = data.get("principle")
    if principle is not None:
        _expect(f"{S}: 'principle'", principle, "string")
        try:
            principle = principles.canonical(principle)
        except PrincipleError:
            raise ModelFileError(
                f"{S}: 'principle' must be one of {', '.join(principles.PRINCIPLES)} (or an "
                f"alias, jetnh.mechanics.principles); got {shorten(principle)!r}") from None
    convention = data.get("convention")
    if convention is not None:
        _expect(f"{S}: 'convention'", convention, "string")
        if convention not in ("paper", "imposed"):
            raise ModelFileError(f"{S}: 'convention' must be 'paper' or 'imposed', got "
                                 f"{convention!r}")

    try:
        # the branch unchecked: System checks a branch by solving the constraints, which
        # takes sympy unbounded time (a general quartic, two coupled quadratics); reading
        # never solves, the branch is checked when the equations are first derived
        system = System(J, L, cons, dependent,
                        defaults={names[k]: v for k, v in params.items()}, name=name,
                        forces=forces, dissipation=dissipation, branch=branch,
                        check_branch=False)
    except JetnhError as exc:
        raise ModelFileError(f"{S}: {exc}") from None
    except RecursionError:
        raise ModelFileError(f"{S}: the model is nested too deeply to build") from None
    except Exception as exc:
        raise ModelFileError(f"{S}: the system cannot be built ({type(exc).__name__}: "
                             f"{shorten(str(exc))})") from None

    # ---------------------------------------------------------------- data
    lams = [m.name for m in principles.multiplier_symbols(system)]
    states = set(names) - {TIME} - set(params)
    initial = {}
    for table in ("initial", "multipliers"):
        given = _expect(f"{S}: [{table}]", data.get(table, {}), "table")
        allowed = (states | set(lams)) if table == "initial" else set(lams)
        for k, v in given.items():
            if k not in allowed:
                what = ("coordinates, velocities (name_t) and multipliers"
                        if table == "initial" else "multipliers")
                raise ModelFileError(
                    f"{S}: [{table}]: {k!r} is not one of the {what}: "
                    f"{', '.join(sorted(allowed)) or 'none'}")
            if k in initial:
                raise ModelFileError(f"{S}: {k!r} is given in [initial] and in [multipliers]")
            initial[k] = float(_expect(f"{S}: [{table}] {k}", v, "number"))

    ints_in = _expect(f"{S}: [integrals]", data.get("integrals", {}), "table")
    int_names = dict(names)
    int_names.update({n: sp.Symbol(n) for n in lams})
    integrals = {}
    for k, v in ints_in.items():
        _check_name(f"{S}: [integrals]", k, {})
        integrals[k] = parse_expression(v, int_names, f"{S}: [integrals] {k}", hint, budget)

    sim = _expect(f"{S}: [simulation]", data.get("simulation", {}), "table")
    for k, v in sim.items():
        if k not in SIMULATION_KEYS:
            raise ModelFileError(f"{S}: [simulation]: unknown key {k!r}; the keys are "
                                 f"{', '.join(sorted(SIMULATION_KEYS))}")
        _expect(f"{S}: [simulation] {k}", v, SIMULATION_KEYS[k])
    if sim.get("points") is not None and not 2 <= sim["points"] <= 10_000_000:
        raise ModelFileError(f"{S}: [simulation] points must be between 2 and 10000000")
    for k in ("rtol", "atol"):
        if k in sim and not sim[k] > 0:
            raise ModelFileError(f"{S}: [simulation] {k} must be positive")
    _check_run_settings(S, sim)

    return Model(system, name, description, initial, principle, convention, integrals,
                 dict(sim), S)


def _parameter_symbols(S, params: dict, given: dict) -> dict:
    """The parameters' symbols by name, with the ``[assumptions]`` given for them (a
    table of booleans per parameter, ``jetnh.modelfile.assumptions``), their values
    checked against them."""
    for k in given:
        if k not in params:
            raise ModelFileError(f"{S}: [assumptions]: {k!r} is not one of the parameters "
                                 f"({', '.join(sorted(params)) or 'none'}); only parameters "
                                 "carry assumptions")
    symbols = {}
    for k, v in params.items():
        where = f"{S}: [assumptions] {k}"
        facts = _expect(where, given.get(k, {}), "table")
        for fact, holds in facts.items():
            _expect(f"{where}: {fact}", holds, "boolean")
        symbols[k] = assumptions.symbol(k, facts, where)
        assumptions.check_value(symbols[k], v, f"{S}: [parameters]")
    return symbols


def _check_run_settings(S, sim):
    """The ``[simulation]`` values as a run checks them (``jetnh.numeric.arguments``,
    ``jetnh.numeric.methods.method``), so that a bad one is refused when the file is read,
    not after the kernels are derived and compiled."""
    from ..numeric import arguments
    from ..numeric.methods import method
    from ..numeric.options import StepControl

    get = sim.get
    rtol, atol = get("rtol", StepControl.rtol), get("atol", StepControl.atol)
    checks = (("method", ("method",), lambda: method(sim["method"])),
              ("rtol, atol", ("rtol", "atol"),
               lambda: arguments.tolerances(float(rtol), float(atol), 1)),
              ("t_start, t_end", ("t_end",),
               lambda: arguments.time_span((get("t_start", 0.0), sim["t_end"]))))
    for what, keys, check in checks:
        if any(k in sim for k in keys):
            try:
                check()
            except JetnhError as exc:
                raise ModelFileError(f"{S}: [simulation] {what}: {exc}") from None
