"""Model files: a constrained system as TOML data, read without executing anything.

A model file (DESIGN.md section 4)::

    name = "vertical rolling disk"
    coordinates = ["x", "y", "phi", "psi"]
    dependent = ["x", "y"]                       # optional: chosen automatically
    lagrangian = "(x_t**2 + y_t**2)/2 + (I1*phi_t**2 + I2*psi_t**2)/2"
    constraints = ["x_t - R*cos(psi)*phi_t", "y_t - R*sin(psi)*phi_t"]
    principle = "chetaev"                        # optional: the default of derive/simulate
    [parameters]
    R = 1.0
    I1 = 0.5
    I2 = 0.25
    [initial]                                    # states not given start at 0
    phi_t = 1.0
    psi_t = 0.7

Optional keys: ``description`` (text), ``branch`` (which solution of nonlinear
constraints, an integer), ``convention`` ("paper" | "imposed"), ``[multipliers]``
(initial values of the multipliers lambda_<dependent> of the vakonomic, Hoelder and
Suslov principles; they may also stand in ``[initial]``), ``[integrals]`` (name =
expression: first integrals for ``jetnh simulate`` to monitor; they may use the
multipliers) and ``[simulation]`` (``t_start``, ``t_end``, ``method``, ``rtol``,
``atol``, ``points``).  Any other key is an error.

Expressions
-----------
An expression is parsed with ``ast.parse(text, mode="eval")`` and the syntax tree is
turned into sympy objects node by node; nothing is evaluated, executed, imported or
sympified.  Allowed:

- numbers: integers (at most ``MAX_INT_DIGITS`` digits) and finite decimals;
- ``+ - * / **``, unary ``+ -`` and parentheses;
- calls of the elementary functions in ``FUNCTIONS`` with positional arguments;
- the constant ``pi``; ``t`` (time);
- declared names: the coordinates, their velocities ``<coordinate>_t``, the parameters
  (and, in ``[integrals]``, the multipliers ``lambda_<dependent>``).

Everything else is refused with a ``ModelFileError`` that quotes the offending text and
its line and column: attribute access, calls of anything but the listed functions,
keyword or starred arguments, undeclared names, names with double underscores,
strings, f-strings, lambdas, comprehensions, subscripts, comparisons, boolean and bit
operators, ``//`` and ``%``, complex numbers, and accelerations (``x_tt``: the
Lagrangian and the constraints are first order).

Limits (pathological input is refused, never run): ``MAX_CHARS`` characters per
expression, ``MAX_NODES`` syntax nodes, nesting depth ``MAX_DEPTH`` (chains of ``+``
or ``*`` count once), integer exponents of absolute value at most ``MAX_EXPONENT``
(after sympy combines equal bases), exact numbers of at most ``MAX_NUMBER_DIGITS``
digits (so ``9**9**9`` is refused before it is computed), every constant
subexpression finite in double precision (``exp(exp(exp(100)))`` is refused: sympy's
own evaluation of it does not return), at most ``MAX_TERMS`` terms when expanded
(estimated from the syntax: ``((x_t + 1)**64 + 1)**64`` is refused), at most
``MAX_COORDINATES`` coordinates, and files of at most ``MAX_FILE_BYTES`` bytes.  An
expression that is infinite, undefined or complex (``1/0``, ``log(0)``, ``sqrt(-1)``)
is refused too.
"""

from __future__ import annotations

import ast
import keyword
import math
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import sympy as sp

from .constraints import PRINCIPLES, System
from .errors import JetnhError, ModelFileError
from .jet import JetSpace

MAX_CHARS = 20_000
MAX_NODES = 5_000
MAX_DEPTH = 100
MAX_EXPONENT = 64
MAX_INT_DIGITS = 40
MAX_NUMBER_DIGITS = 200
MAX_FILE_BYTES = 1_000_000
MAX_TERMS = 10_000
MAX_COORDINATES = 500

FUNCTIONS = {
    "sin": (sp.sin, 1), "cos": (sp.cos, 1), "tan": (sp.tan, 1), "cot": (sp.cot, 1),
    "sec": (sp.sec, 1), "csc": (sp.csc, 1),
    "asin": (sp.asin, 1), "acos": (sp.acos, 1), "atan": (sp.atan, 1), "atan2": (sp.atan2, 2),
    "sinh": (sp.sinh, 1), "cosh": (sp.cosh, 1), "tanh": (sp.tanh, 1),
    "asinh": (sp.asinh, 1), "acosh": (sp.acosh, 1), "atanh": (sp.atanh, 1),
    "exp": (sp.exp, 1), "log": (sp.log, 1), "sqrt": (sp.sqrt, 1),
    "Abs": (sp.Abs, 1), "abs": (sp.Abs, 1), "sign": (sp.sign, 1),
}
CONSTANTS = {"pi": sp.pi}
TIME = "t"

TOP_KEYS = {"name", "description", "coordinates", "dependent", "lagrangian", "constraints",
            "branch", "principle", "convention", "parameters", "initial", "multipliers",
            "integrals", "simulation"}
REQUIRED_KEYS = ("coordinates", "lagrangian")
SIMULATION_KEYS = {"t_start": "number", "t_end": "number", "method": "string",
                   "rtol": "number", "atol": "number", "points": "integer"}

_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9]*(?:_[A-Za-z0-9]+)*$")
_JET = re.compile(r"^(.+?)_(t+)$")

_REFUSED = {
    ast.Attribute: "attribute access is", ast.Subscript: "subscripts are",
    ast.Lambda: "lambdas are", ast.ListComp: "comprehensions are",
    ast.SetComp: "comprehensions are", ast.DictComp: "comprehensions are",
    ast.GeneratorExp: "comprehensions are", ast.JoinedStr: "f-strings are",
    ast.FormattedValue: "f-strings are", ast.Starred: "starred arguments are",
    ast.Compare: "comparisons are", ast.BoolOp: "boolean operators ('and', 'or') are",
    ast.IfExp: "conditional expressions are", ast.List: "lists are", ast.Tuple: "tuples are",
    ast.Set: "sets are", ast.Dict: "dictionaries are",
    ast.NamedExpr: "assignment expressions are", ast.Await: "await is",
    ast.Yield: "yield is", ast.YieldFrom: "yield is", ast.Slice: "slices are",
}
_OPS = {ast.FloorDiv: "//", ast.Mod: "%", ast.MatMult: "@", ast.LShift: "<<",
        ast.RShift: ">>", ast.BitOr: "|", ast.BitXor: "^", ast.BitAnd: "&"}


def _sign(x):
    return math.copysign(1.0, x) if x else 0.0


# double-precision shadows of the functions: every symbol-free subexpression is also
# evaluated in floats, so that overflow and domain errors are refused before sympy sees
# them (sympy's own evaluation of exp(exp(exp(100))) does not return)
_FLOAT = {
    "sin": math.sin, "cos": math.cos, "tan": math.tan, "cot": lambda x: 1 / math.tan(x),
    "sec": lambda x: 1 / math.cos(x), "csc": lambda x: 1 / math.sin(x),
    "asin": math.asin, "acos": math.acos, "atan": math.atan, "atan2": math.atan2,
    "sinh": math.sinh, "cosh": math.cosh, "tanh": math.tanh, "asinh": math.asinh,
    "acosh": math.acosh, "atanh": math.atanh, "exp": math.exp, "log": math.log,
    "sqrt": math.sqrt, "Abs": abs, "abs": abs, "sign": _sign,
}
_BAD = (sp.zoo, sp.nan, sp.oo, -sp.oo)


# ====================================================================== expressions
class _Parser:
    """Builds one sympy expression from one syntax tree; see the module docstring.

    Every ``build`` returns ``(expr, value, size)``: the sympy expression; when it
    contains no symbol, its value in double precision (else None); and an upper bound of
    the number of terms of its expansion (sums add, products multiply, an integer power
    n of s terms has at most C(s + n - 1, n)), since jetnh and sympy expand expressions
    (``expand`` of ((x_t + 1)**64 + 1)**64 would not return).
    """

    def __init__(self, text: str, names: dict, where: str, hint: dict | None = None,
                 offset_map=None):
        self.text = text
        self.names = names
        self.where = where
        self.hint = hint or {}
        self.offset_map = offset_map

    # ------------------------------------------------------------------ errors
    def fail(self, node, what: str):
        seg = None
        line, col = getattr(node, "lineno", None), getattr(node, "col_offset", None)
        if line is not None:
            try:
                seg = ast.get_source_segment(self.text, node)
            except Exception:                          # pragma: no cover - defensive
                seg = None
            col = _char_column(self.text, line, col)
            if self.offset_map is not None:
                line, col = self.offset_map(col)
        quote = f" {_shorten(seg)!r}" if seg else ""
        at = f" at line {line}, column {col + 1}" if line is not None else ""
        raise ModelFileError(f"{self.where}: {what}{quote}{at}")

    # ------------------------------------------------------------------ building
    def build(self, node, depth=0):
        if depth > MAX_DEPTH:
            self.fail(node, f"nesting deeper than {MAX_DEPTH} levels is refused:")
        kind = type(node)
        if kind is ast.Expression:
            return self.build(node.body, depth)
        if kind is ast.Constant:
            return self.constant(node)
        if kind is ast.Name:
            return self.name(node)
        if kind is ast.UnaryOp:
            if isinstance(node.op, (ast.USub, ast.UAdd)):
                e, v, n = self.build(node.operand, depth + 1)
                if isinstance(node.op, ast.UAdd):
                    return e, v, n
                return -e, (None if v is None else -v), n
            self.fail(node, f"the operator {'not' if isinstance(node.op, ast.Not) else '~'} "
                      "is not allowed:")
        if kind is ast.BinOp:
            return self.binop(node, depth)
        if kind is ast.Call:
            return self.call(node, depth)
        what = _REFUSED.get(kind, f"{kind.__name__} syntax is")
        self.fail(node, f"{what} not allowed:")

    def constant(self, node):
        v = node.value
        if isinstance(v, bool) or v is None or v is Ellipsis:
            self.fail(node, f"the constant {v!r} is not a number:")
        if isinstance(v, int):
            if abs(v).bit_length() > 3.33 * MAX_INT_DIGITS:
                self.fail(node, f"integers of more than {MAX_INT_DIGITS} digits are refused:")
            return sp.Integer(v), float(v), 1
        if isinstance(v, float):
            if not math.isfinite(v):
                self.fail(node, "the number is not finite:")
            return sp.Float(v), v, 1
        if isinstance(v, complex):
            self.fail(node, "complex numbers are not allowed:")
        if isinstance(v, (str, bytes)):
            self.fail(node, "strings are not allowed:")
        self.fail(node, f"the constant {type(v).__name__} is not allowed:")

    def name(self, node):
        n = node.id
        if "__" in n:
            self.fail(node, "names with double underscores are not allowed:")
        if n in self.names:
            return self.names[n], None, 1
        if n in CONSTANTS:
            return CONSTANTS[n], float(CONSTANTS[n]), 1
        if n in FUNCTIONS:
            self.fail(node, f"{n} is a function; call it, e.g. {n}(x):")
        if n in self.hint:
            self.fail(node, self.hint[n])
        known = ", ".join(sorted(self.names)) or "none"
        self.fail(node, f"unknown name (declared names: {known}; declare parameters "
                  "under [parameters]):")

    def number(self, node, value, what="the value"):
        """A double-precision shadow value, or a refusal if it is not a finite real."""
        if isinstance(value, complex) or not math.isfinite(value):
            self.fail(node, f"{what} is not a finite real number:")
        return value

    def binop(self, node, depth):
        op = type(node.op)
        if op in _OPS:
            self.fail(node, f"the operator {_OPS[op]} is not allowed:")
        if op in (ast.Add, ast.Sub):
            first, parts = self._chain(node, (ast.Add, ast.Sub))
            e, v, n = self.build(first, depth + 1)
            terms, total, size = [e], v, n
            for o, right in parts:
                e, v, n = self.build(right, depth + 1)
                terms.append(e if o is ast.Add else -e)
                if total is not None and v is not None:
                    total = self.number(node, total + v if o is ast.Add else total - v)
                else:
                    total = None
                size = self.size(node, size + n)
            return self.check(node, sp.Add(*terms)), total, size
        if op in (ast.Mult, ast.Div):
            first, parts = self._chain(node, (ast.Mult, ast.Div))
            e, v, n = self.build(first, depth + 1)
            out, total, size = e, v, n
            for o, right in parts:
                e, v, n = self.build(right, depth + 1)
                size = self.size(node, size * n)
                if o is ast.Div and (e == 0 or v == 0.0):
                    self.fail(node, "division by zero:")
                if total is not None and v is not None:
                    total = self.number(node, total * v if o is ast.Mult else total / v)
                else:
                    total = None
                out = out * e if o is ast.Mult else out / e
                out = self.check(node, out)
            return out, total, size
        if op is ast.Pow:
            base, bv, bn = self.build(node.left, depth + 1)
            exp_, ev, en = self.build(node.right, depth + 1)
            return self.power(node, base, bv, bn, exp_, ev, en)
        self.fail(node, f"the operator {op.__name__} is not allowed:")  # pragma: no cover

    @staticmethod
    def _chain(node, ops):
        """Flatten a left-nested chain a op b op c ... iteratively: (a, [(op, b), ...])."""
        parts = []
        while isinstance(node, ast.BinOp) and type(node.op) in ops:
            parts.append((type(node.op), node.right))
            node = node.left
        return node, list(reversed(parts))

    def size(self, node, n):
        if n > MAX_TERMS:
            self.fail(node, f"the expansion of this expression would have more than "
                      f"{MAX_TERMS} terms; refused:")
        return n

    def power(self, node, base, bv, bn, exp_, ev, en):
        if exp_.is_Integer and abs(int(exp_)) > MAX_EXPONENT:
            self.fail(node, f"integer exponents beyond +-{MAX_EXPONENT} are refused:")
        value = None
        if bv is not None and ev is not None:
            if bv == 0.0 and ev <= 0:
                self.fail(node, "0 to a non-positive power is undefined:")
            try:
                value = math.pow(bv, ev)
            except OverflowError:
                self.fail(node, "the value overflows double precision:")
            except ValueError:
                self.fail(node, "the value is not real:")
            self.number(node, value)
            if base.is_Number and exp_.is_Rational:
                est = _digits(base) * abs(int(exp_.p)) / int(exp_.q)
                if est > MAX_NUMBER_DIGITS:
                    self.fail(node, f"exact numbers of more than {MAX_NUMBER_DIGITS} digits "
                              "are refused:")
        if exp_.is_Integer:
            k = abs(int(exp_))
            size = math.comb(bn + k - 1, k) if k else 1
        else:
            size = bn * en               # not expanded by sympy: opaque, but both parts count
        size = self.size(node, size)
        return self.check(node, sp.Pow(base, exp_)), value, size

    def call(self, node, depth):
        f = node.func
        if not isinstance(f, ast.Name):
            if isinstance(f, ast.Attribute):
                self.fail(node, "attribute access is not allowed:")
            self.fail(node, f"calls of expressions are not allowed (only the functions "
                      f"{_fnames()}):")
        n = f.id
        if "__" in n:
            self.fail(f, "names with double underscores are not allowed:")
        if n not in FUNCTIONS:
            if n in self.names or n in CONSTANTS:
                self.fail(node, f"{n} is not a function; only {_fnames()} can be called:")
            self.fail(node, f"{n}() is not an allowed function; the functions are "
                      f"{_fnames()}:")
        if node.keywords:
            self.fail(node, "keyword arguments are not allowed:")
        for a in node.args:
            if isinstance(a, ast.Starred):
                self.fail(a, "starred arguments are not allowed:")
        func, arity = FUNCTIONS[n]
        if len(node.args) != arity:
            self.fail(node, f"{n} takes {arity} argument{'s' if arity > 1 else ''}, "
                      f"got {len(node.args)}:")
        built = [self.build(a, depth + 1) for a in node.args]
        value = None
        if all(v is not None for _, v, _ in built):
            try:
                value = _FLOAT[n](*(v for _, v, _ in built))
            except OverflowError:
                self.fail(node, "the value overflows double precision:")
            except (ValueError, ZeroDivisionError):
                self.fail(node, f"the argument is outside the domain of {n}:")
            self.number(node, value)
        size = self.size(node, sum(k for _, _, k in built))
        return self.check(node, func(*(e for e, _, _ in built))), value, size

    # ------------------------------------------------------------------ checks
    def check(self, node, e):
        """Local checks of a freshly built node (cheap: e and its top-level args)."""
        parts = (e,) + (e.args if e.is_Mul or e.is_Pow else ())
        for p in parts:
            if p in _BAD:
                self.fail(node, "the expression is infinite or undefined:")
            if p.is_Number and _digits(p) > MAX_NUMBER_DIGITS:
                self.fail(node, f"exact numbers of more than {MAX_NUMBER_DIGITS} digits are "
                          "refused:")
            if p.is_Pow and p.exp.is_Integer and abs(int(p.exp)) > MAX_EXPONENT:
                self.fail(node, f"the integer exponent {p.exp} (after combining equal bases) "
                          f"is beyond +-{MAX_EXPONENT}:")
        if e.is_Add and any(a in _BAD for a in e.args):
            self.fail(node, "the expression is infinite or undefined:")
        return e


def _fnames() -> str:
    return ", ".join(sorted(FUNCTIONS))


def _digits(n) -> int:
    """Decimal digits of an exact number (the larger of numerator and denominator)."""
    if n.is_Rational:
        bits = max(abs(int(n.p)).bit_length(), int(n.q).bit_length())
        return int(bits * 0.30103) + 1
    return 0


def _shorten(s: str, limit: int = 60) -> str:
    s = " ".join(s.split())
    return s if len(s) <= limit else s[:limit - 3] + "..."


def _char_column(text: str, line: int, byte_col: int | None) -> int:
    """ast gives UTF-8 byte offsets; report characters."""
    if byte_col is None:
        return 0
    lines = text.splitlines() or [""]
    if 1 <= line <= len(lines):
        return len(lines[line - 1].encode("utf-8")[:byte_col].decode("utf-8", "replace"))
    return byte_col


def _line_col(text: str, offset: int) -> tuple[int, int]:
    """(line, column), both from the start of ``text``, of a character offset."""
    before = text[:offset]
    line = before.count("\n") + 1
    return line, offset - (before.rfind("\n") + 1)


def parse_expression(text, names: dict, where: str = "expression", hint: dict | None = None):
    """The sympy expression written in ``text``, with ``names`` (str -> Symbol) declared.

    Raises ``ModelFileError`` for anything outside the language of the module docstring.
    ``hint`` maps names to a specific refusal message (e.g. accelerations).  Line breaks
    count as spaces (multi-line TOML strings), positions refer to the text as given.
    """
    if not isinstance(text, str):
        raise ModelFileError(f"{where}: expected an expression in a string, got "
                             f"{type(text).__name__} ({_shorten(repr(text))})")
    if len(text) > MAX_CHARS:
        raise ModelFileError(f"{where}: the expression has {len(text)} characters; the limit "
                             f"is {MAX_CHARS}")
    if "\x00" in text:
        raise ModelFileError(f"{where}: the expression contains a NUL character")
    if not text.strip():
        raise ModelFileError(f"{where}: the expression is empty")
    # one line, same offsets: a line break is white space in an expression
    flat = text.replace("\r", " ").replace("\n", " ").replace("\t", " ")
    lead = len(flat) - len(flat.lstrip())
    body = flat.strip()
    try:
        tree = ast.parse(body, mode="eval")
    except SyntaxError as exc:
        # offset 0: the expression ended too early; point just past its end
        offset = min(exc.offset or len(body) + 1, len(body) + 1)
        line, col = _line_col(text, lead + offset - 1)
        at = f" at line {line}, column {col + 1}"
        raise ModelFileError(f"{where}: not a valid expression ({exc.msg}){at}: "
                             f"{_shorten(text)!r}") from None
    except (RecursionError, MemoryError, ValueError) as exc:
        raise ModelFileError(f"{where}: the expression is too deeply nested or too large "
                             f"to parse ({type(exc).__name__})") from None
    count = 0
    for _ in ast.walk(tree):
        count += 1
        if count > MAX_NODES:
            raise ModelFileError(f"{where}: the expression has more than {MAX_NODES} syntax "
                                 "nodes; split it or raise jetnh.modelfile.MAX_NODES")
    parser = _Parser(body, names, where, hint, lambda col: _line_col(text, lead + col))
    try:
        expr, _, _ = parser.build(tree)
    except RecursionError:
        raise ModelFileError(f"{where}: the expression is too deeply nested") from None
    if expr.has(*_BAD):
        raise ModelFileError(f"{where}: the expression is infinite or undefined")
    if expr.has(sp.I):
        raise ModelFileError(f"{where}: the expression is complex (jetnh works with real "
                             "expressions)")
    return expr


# ====================================================================== model files
@dataclass
class Model:
    """A model read from a file: the System and the data around it."""

    system: System
    name: str
    description: str = ""
    initial: dict = field(default_factory=dict)        # names -> floats (states and lambdas)
    principle: str | None = None
    convention: str | None = None
    integrals: dict = field(default_factory=dict)      # name -> sympy expression
    simulation: dict = field(default_factory=dict)
    source: str = "<string>"

    @property
    def parameters(self) -> dict:
        return {s.name: v for s, v in self.system.defaults.items()}


def _type_name(v) -> str:
    return {str: "a string", int: "an integer", float: "a number", bool: "a boolean",
            list: "a list", dict: "a table"}.get(type(v), type(v).__name__)


def _expect(where, value, kind):
    ok = {"string": lambda v: isinstance(v, str),
          "number": lambda v: isinstance(v, (int, float)) and not isinstance(v, bool),
          "integer": lambda v: isinstance(v, int) and not isinstance(v, bool),
          "table": lambda v: isinstance(v, dict),
          "list of strings": lambda v: isinstance(v, list) and all(isinstance(x, str) for x in v),
          }[kind](value)
    if not ok:
        raise ModelFileError(f"{where} must be {'an' if kind[0] in 'aeiou' else 'a'} {kind}, "
                             f"got {_type_name(value)} ({_shorten(repr(value))})")
    if kind == "number" and not math.isfinite(float(value)):
        raise ModelFileError(f"{where} must be finite, got {value!r}")
    return value


def _check_name(where, name, reserved):
    if not _NAME.match(name) or keyword.iskeyword(name):
        raise ModelFileError(
            f"{where}: {name!r} is not a usable name (letters, digits and single underscores, "
            "starting with a letter; not a Python keyword)")
    if name in reserved:
        raise ModelFileError(f"{where}: the name {name!r} is reserved ({reserved[name]})")


def loads(text: str, source: str = "<string>") -> Model:
    """A ``Model`` from the text of a model file."""
    if not isinstance(text, str):
        raise ModelFileError(f"{source}: a model file is text, got {type(text).__name__}")
    if len(text.encode("utf-8", "replace")) > MAX_FILE_BYTES:
        raise ModelFileError(f"{source}: the file is larger than {MAX_FILE_BYTES} bytes")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ModelFileError(f"{source}: not valid TOML: {exc}") from None
    except RecursionError:
        raise ModelFileError(f"{source}: not valid TOML: nested too deeply") from None
    return from_dict(data, source)


def load(path) -> Model:
    """A ``Model`` from a model file on disk."""
    p = Path(path)
    try:
        size = p.stat().st_size
        if size > MAX_FILE_BYTES:
            raise ModelFileError(f"{p}: the file has {size} bytes; the limit is {MAX_FILE_BYTES}")
        raw = p.read_bytes()
    except ModelFileError:
        raise
    except FileNotFoundError:
        raise ModelFileError(f"{p}: no such file") from None
    except IsADirectoryError:
        raise ModelFileError(f"{p}: is a directory, not a model file") from None
    except OSError as exc:
        raise ModelFileError(f"{p}: cannot read the file ({exc.strerror or exc})") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ModelFileError(f"{p}: not UTF-8 text (byte {exc.start})") from None
    return loads(text, str(p))


def from_dict(data: dict, source: str = "<string>") -> Model:
    """A ``Model`` from already-parsed TOML data (a dict)."""
    S = source
    if not isinstance(data, dict):
        raise ModelFileError(f"{S}: a model file is a TOML table")
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

    # ---------------------------------------------------------------- names
    coords = _expect(f"{S}: 'coordinates'", data["coordinates"], "list of strings")
    if not coords:
        raise ModelFileError(f"{S}: 'coordinates' is empty; give at least one name")
    if len(coords) > MAX_COORDINATES:
        raise ModelFileError(f"{S}: {len(coords)} coordinates; the limit is "
                             f"{MAX_COORDINATES}")
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
    names.update({k: sp.Symbol(k) for k in params})
    hint = {}
    for q in J.q:
        for order in (2, 3, 4):
            hint[f"{q.name}_{'t' * order}"] = (
                "accelerations and higher jets are not allowed here (the Lagrangian and "
                "the constraints are first order):")

    # ---------------------------------------------------------------- expressions
    L = parse_expression(data["lagrangian"], names, f"{S}: lagrangian", hint)
    cons_in = data.get("constraints", [])
    _expect(f"{S}: 'constraints'", cons_in, "list of strings")
    cons = [parse_expression(c, names, f"{S}: constraints[{i}]", hint)
            for i, c in enumerate(cons_in)]
    used = set().union(L.free_symbols, *(c.free_symbols for c in cons))
    unused = sorted(k for k in params if sp.Symbol(k) not in used)
    if unused:
        raise ModelFileError(f"{S}: [parameters]: {', '.join(unused)} "
                             f"{'is' if len(unused) == 1 else 'are'} used neither in the "
                             "Lagrangian nor in the constraints")

    dependent = data.get("dependent")
    if dependent is not None:
        _expect(f"{S}: 'dependent'", dependent, "list of strings")
        for d in dependent:
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
        if principle not in PRINCIPLES:
            raise ModelFileError(f"{S}: 'principle' must be one of {', '.join(PRINCIPLES)}; "
                                 f"got {principle!r}")
    convention = data.get("convention")
    if convention is not None:
        _expect(f"{S}: 'convention'", convention, "string")
        if convention not in ("paper", "imposed"):
            raise ModelFileError(f"{S}: 'convention' must be 'paper' or 'imposed', got "
                                 f"{convention!r}")

    try:
        system = System(J, L, cons, dependent, branch=branch,
                        defaults={sp.Symbol(k): v for k, v in params.items()}, name=name)
    except JetnhError as exc:
        raise ModelFileError(f"{S}: {exc}") from None

    # ---------------------------------------------------------------- data
    lams = [f"lambda_{d.name}" for d in system.dependent]
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
        integrals[k] = parse_expression(v, int_names, f"{S}: [integrals] {k}", hint)

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

    return Model(system, name, description, initial, principle, convention, integrals,
                 dict(sim), S)


# ====================================================================== writing
class _Printer(sp.printing.str.StrPrinter):
    """sympy's str printer, restricted to what ``parse_expression`` reads back."""

    def _print_Float(self, expr):
        v = float(expr)
        if not math.isfinite(v):
            raise ModelFileError(f"the number {expr} cannot be written to a model file")
        return repr(v)

    def _print_Exp1(self, expr):
        return "exp(1)"

    def _print_ImaginaryUnit(self, expr):
        raise ModelFileError("complex numbers cannot be written to a model file")

    def _print_Function(self, expr):
        name = expr.func.__name__
        if name not in FUNCTIONS:
            raise ModelFileError(f"the function {name} is not in the model-file language "
                                 f"({_fnames()}); it cannot be written")
        return super()._print_Function(expr)


def expression_text(expr) -> str:
    """``expr`` as model-file text (refuses what the reader would refuse)."""
    return _Printer({"order": None}).doprint(expr)


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


def dumps(system: System, initial=None, *, params=None, principle=None, convention=None,
          description="", integrals=None, simulation=None) -> str:
    """The model file of ``system`` (its parameters' values: ``system.defaults``, updated
    by ``params``); ``initial`` may hold states and multipliers by name or Symbol.
    The text is checked by reading it back."""
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
                                               for f in system.constraints) + "]")
    if system._branch is not None:
        lines.append(f"branch = {int(system._branch)}")
    if principle:
        lines.append(f"principle = {_toml_string(principle)}")
    if convention:
        lines.append(f"convention = {_toml_string(convention)}")
    if values:
        lines.append("\n[parameters]")
        lines += [f"{k} = {_toml_number(v)}" for k, v in sorted(values.items())
                  if k in {p.name for p in system.parameters}]
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


__all__ = ["Model", "load", "loads", "from_dict", "dump", "dumps", "parse_expression",
           "expression_text", "FUNCTIONS", "MAX_CHARS", "MAX_NODES", "MAX_DEPTH",
           "MAX_EXPONENT", "MAX_INT_DIGITS", "MAX_NUMBER_DIGITS", "MAX_TERMS",
           "MAX_COORDINATES", "MAX_FILE_BYTES"]
