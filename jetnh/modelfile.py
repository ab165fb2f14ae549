"""Model files: a constrained system as TOML data, read without executing anything.

A model file::

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

A constraint without velocities (``"x**2 + y**2 - l**2"``) is holonomic: the system keeps
it at position level (``System.holonomic``), and the ``[initial]`` configuration must
satisfy it (a simulation refuses one off it, naming the residual).

Optional keys: ``[forces]`` (coordinate = expression: the non-potential generalized force
Q_s(t, q, qdot) on that coordinate, beside [L]_s in every principle's equations),
``dissipation`` (a Rayleigh function D(t, q, qdot): Q_s -= dD/dqdot^s), ``description``
(text), ``branch`` (which solution of nonlinear
constraints, an integer >= 0), ``principle`` (a name or an alias, ``jetnh.mechanics.principles``;
read as its canonical name), ``convention`` ("paper" | "imposed"), ``[multipliers]``
(initial values of the multipliers lambda_<dependent> of the vakonomic, Hoelder and
Suslov principles; they may also stand in ``[initial]``), ``[integrals]`` (name =
expression: first integrals for ``jetnh simulate`` to monitor; they may use the
multipliers) and ``[simulation]`` (``t_start``, ``t_end``, ``method``, ``rtol``,
``atol``, ``points``).  Any other key is an error.

What ``load``, ``loads`` and ``from_dict`` guarantee
----------------------------------------------------
Every failure is a ``ModelFileError`` (a ``JetnhError``) whose message names the problem
and the fix; no other exception escapes (an unexpected one from sympy or from building
the ``System`` is wrapped, its message marked "internal").  Nothing is evaluated,
executed, imported or sympified, and every documented input is read in a few seconds
(the limits below were measured so that the largest allowed models read in about 2 s).

The file (``load``): only a regular file is read (symbolic links are followed; the
target is checked with ``stat`` before opening and with ``fstat`` on the opened
descriptor, which is opened non-blocking, so FIFOs, devices, sockets and directories are
refused without blocking); at most ``MAX_FILE_BYTES`` + 1 bytes are read whatever the
size the file claims; it must be UTF-8 (a leading byte-order mark is skipped) without NUL
bytes; the position of a bad byte is reported.

The text (``loads``): valid TOML, at most ``MAX_FILE_BYTES`` bytes, no NUL character.
Every key, name (coordinates, ``dependent``, parameters, initial values, multipliers,
integrals) and expression is ASCII: Python's parser folds letters such as U+FF58
(fullwidth x) or U+1D465 (mathematical italic x) into ``x`` (NFKC normalisation), so a
name could silently mean another; the refusal names the character (checked on the raw
text, before ``ast.parse``).  Names are letters, digits and single underscores, starting
with a letter, not Python keywords.  ``name`` and ``description`` may hold any text but
control characters (terminal escapes; ``description`` may hold line breaks and tabs)
and bidirectional overrides.  Values have the documented types; numbers are finite.

Expressions
-----------
An expression is parsed with ``ast.parse(text, mode="eval")`` and the syntax tree is
turned into sympy objects node by node.  Allowed:

- numbers: integers (at most ``MAX_INT_DIGITS`` digits) and finite decimals;
- ``+ - * / **``, unary ``+ -`` and parentheses;
- calls of the elementary functions in ``FUNCTIONS`` with positional arguments
  (``Abs``/``abs`` and ``sign`` are kept by ``System`` as sqrt(u**2) and u/sqrt(u**2),
  whose kink u = 0 the integrators stop at);
- the constant ``pi``; ``t`` (time);
- declared names: the coordinates, their velocities ``<coordinate>_t``, the parameters
  (and, in ``[integrals]``, the multipliers ``lambda_<dependent>``).

Everything else is refused with a ``ModelFileError`` that quotes the offending text and
its line and column: attribute access, calls of anything but the listed functions,
keyword or starred arguments, undeclared names, names with double underscores,
strings, f-strings, lambdas, comprehensions, subscripts, comparisons, boolean and bit
operators, ``//`` and ``%``, complex numbers, non-ASCII characters, and accelerations
(``x_tt``: the Lagrangian and the constraints are first order).  An expression that is
infinite, undefined or complex (``1/0``, ``log(0)``, ``sqrt(-1)``) is refused too.

Limits
------
Pathological input is refused before it is built, from counts on the syntax tree:

- per expression: ``MAX_CHARS`` characters, ``MAX_NODES`` syntax nodes, nesting depth
  ``MAX_DEPTH`` (chains of ``+`` or ``*`` count once);
- per file: ``MAX_FILE_NODES`` syntax nodes in all expressions together;
- function calls (and powers whose exponent is not an integer literal) nested at most
  ``MAX_CALL_DEPTH`` deep; each costs ``CALL_COST_BASE**k`` units with ``k`` such calls
  nested inside it, at most ``MAX_CALL_COST`` units per file;
- ``sinh``, ``cosh``, ``tanh``: sympy decides whether they are real by expanding the real
  and imaginary parts of their argument, at a cost exponential in its nesting and steep
  in its size (the derivative of tanh of a sum of 100 terms takes minutes), so their
  argument holds no call (or non-integer power) and at most ``MAX_HYPERBOLIC_ARG``
  syntax nodes, and each costs ``HYPERBOLIC_COST`` units; write larger ones with ``exp``;
- integer exponents of absolute value at most ``MAX_EXPONENT`` (after sympy combines
  equal bases), exact numbers of at most ``MAX_NUMBER_DIGITS`` digits (so ``9**9**9`` is
  refused before it is computed), every constant subexpression finite in double
  precision (``exp(exp(exp(100)))`` is refused: sympy's own evaluation of it does not
  return), at most ``MAX_TERMS`` terms when expanded (estimated from the syntax:
  ``((x_t + 1)**64 + 1)**64`` is refused);
- the model: at most ``MAX_COORDINATES`` coordinates and ``MAX_CONSTRAINTS``
  constraints, coordinates times constraints at most ``MAX_SPLIT_COST`` (the automatic
  split tests ranks for each candidate coordinate), coordinates times the syntax nodes of
  all constraints at most ``MAX_JACOBIAN_COST`` (every constraint is differentiated by
  every velocity), and the constraints must all be finite and real at one of
  ``SAMPLE_POINTS`` random points with every symbol in [0.31, 1.37] (where jetnh decides
  ranks numerically; a model complex everywhere would send it to symbolic algebra).

Reading builds the ``System`` (checking the constraints' rank and choosing the split) but
never solves the constraints: ``branch`` is checked when the equations are first derived
(sympy's solution of a general quartic or of two coupled quadratics takes unbounded
time).  The limits are module attributes: a trusted caller may raise them.
"""

from __future__ import annotations

import ast
import codecs
import keyword
import math
import os
import random
import re
import stat
import tomllib
import unicodedata
from dataclasses import dataclass, field
from pathlib import Path

import sympy as sp

from .mechanics import principles
from .mechanics.system import System
from .errors import JetnhError, ModelFileError, PrincipleError
from .geometry.jet import JetSpace

MAX_CHARS = 20_000
MAX_NODES = 5_000
MAX_FILE_NODES = 20_000
MAX_DEPTH = 100
MAX_CALL_DEPTH = 5
MAX_CALL_COST = 2_000
CALL_COST_BASE = 3
HYPERBOLIC = frozenset({"sinh", "cosh", "tanh"})
HYPERBOLIC_COST = 20
MAX_HYPERBOLIC_ARG = 30
MAX_EXPONENT = 64
MAX_INT_DIGITS = 40
MAX_NUMBER_DIGITS = 200
MAX_FILE_BYTES = 1_000_000
MAX_TERMS = 10_000
MAX_COORDINATES = 100
MAX_CONSTRAINTS = 16
MAX_JACOBIAN_COST = 20_000
MAX_SPLIT_COST = 500

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
_NONSMOOTH = {"floor", "ceiling", "ceil", "frac", "round", "Heaviside", "heaviside",
              "DiracDelta", "Min", "Max", "min", "max", "Piecewise", "piecewise", "Mod",
              "mod", "re", "im", "arg", "conjugate", "step", "clip"}
TIME = "t"

TOP_KEYS = {"name", "description", "coordinates", "dependent", "lagrangian", "constraints",
            "forces", "dissipation", "branch", "principle", "convention", "parameters",
            "initial", "multipliers", "integrals", "simulation"}
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
SAMPLE_POINTS = 24


class _Unknown(Exception):
    """An expression the double-precision evaluation does not know."""


def _float_value(expr, point: dict, memo: dict):
    """``expr`` in double precision at ``point`` (Symbol -> float); None when it (or a
    part of it) is not a finite real number.  Iterative: the tree may be deep."""
    stack = [(expr, False)]
    while stack:
        e, done = stack.pop()
        if id(e) in memo:
            continue
        if not done:
            if e.is_Symbol:
                memo[id(e)] = point[e]
            elif e.is_Number or e is sp.pi or e is sp.E:
                memo[id(e)] = float(e)
            else:
                stack.append((e, True))
                stack.extend((a, False) for a in e.args)
            continue
        vals = [memo[id(a)] for a in e.args]
        if any(v is None for v in vals):
            memo[id(e)] = None
            continue
        try:
            if e.is_Add:
                v = math.fsum(vals)
            elif e.is_Mul:
                v = math.prod(vals)
            elif e.is_Pow:
                v = math.pow(*vals)
            elif type(e).__name__ in _FLOAT:
                v = _FLOAT[type(e).__name__](*vals)
            else:
                raise _Unknown(type(e).__name__)
        except (ValueError, ZeroDivisionError, OverflowError):
            v = None
        memo[id(e)] = v if v is not None and math.isfinite(v) else None
    return memo[id(expr)]


def _real_somewhere(exprs, symbols) -> bool:
    """Whether the expressions are all finite and real at one of ``SAMPLE_POINTS`` random
    points (every symbol in [0.31, 1.37], as jetnh samples to decide ranks)."""
    rng = random.Random(0)
    symbols = sorted(symbols, key=lambda s: s.name)
    for _ in range(SAMPLE_POINTS):
        point = {s: rng.uniform(0.31, 1.37) for s in symbols}
        memo = {}
        try:
            if all(_float_value(e, point, memo) is not None for e in exprs):
                return True
        except _Unknown:
            return True                      # cannot tell: leave it to jetnh
    return False


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
            factors, total, size = [e], v, n
            for o, right in parts:
                e, v, n = self.build(right, depth + 1)
                size = self.size(node, size * n)
                if o is ast.Div and (e == 0 or v == 0.0):
                    self.fail(node, "division by zero:")
                if total is not None and v is not None:
                    total = self.number(node, total * v if o is ast.Mult else total / v)
                else:
                    total = None
                factors.append(e if o is ast.Mult else self.check(node, sp.Pow(e, -1)))
            # one product of all factors: multiplying one factor at a time re-flattens the
            # partial product each time (quadratic: a chain of 1000 factors took seconds)
            return self.check(node, sp.Mul(*factors)), total, size
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
            if n in _NONSMOOTH:
                self.fail(node, f"{n}() is not allowed: it is not smooth, and the equations "
                          "of motion need derivatives; write the model smoothly (e.g. "
                          "tanh(u/eps) for a step, Abs(u) for |u|, whose kink the "
                          "integrators stop at):")
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


class _Budget:
    """What the expressions of one model file may cost together (``MAX_FILE_NODES``
    syntax nodes and ``MAX_CALL_COST`` units of function calls)."""

    def __init__(self, nodes: int | None = None, calls: int | None = None):
        self.nodes = MAX_FILE_NODES if nodes is None else nodes
        self.calls = MAX_CALL_COST if calls is None else calls
        self.used_nodes = 0
        self.used_calls = 0
        self.constraint_nodes = 0


def _is_int_literal(node) -> bool:
    while isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        node = node.operand
    return (isinstance(node, ast.Constant) and isinstance(node.value, int)
            and not isinstance(node.value, bool))


def _call_like(node) -> bool:
    """Function calls and powers with other than integer-literal exponents: the nodes whose
    construction makes sympy query the assumptions of their argument (for nested
    hyperbolic functions those queries expand real and imaginary parts, exponentially
    in the nesting)."""
    if isinstance(node, ast.Call):
        return True
    return (isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow)
            and not _is_int_literal(node.right))


def _measure(tree, where: str):
    """(syntax nodes, deepest nesting of calls, call cost) of a syntax tree, by one
    iterative walk (no recursion: the tree may be deep); stops at ``MAX_NODES`` nodes.

    A call-like node (``_call_like``) with ``k`` calls nested inside it (on its deepest
    path) costs ``CALL_COST_BASE**k`` units.  The hyperbolic functions (``HYPERBOLIC``)
    cost ``HYPERBOLIC_COST`` units each and their argument must hold no call-like node
    and at most ``MAX_HYPERBOLIC_ARG`` syntax nodes (the first offence is returned):
    sympy decides whether sinh, cosh, tanh of an expression are real by expanding the
    real and imaginary parts of the expression, at a cost exponential in the nesting
    and steep in the size (building the derivative of tanh(a sum of 100 terms) does not
    return within minutes).
    """
    count = 0
    level = {}          # id(node) -> deepest nesting of call-like nodes in its subtree
    size = {}           # id(node) -> syntax nodes in its subtree
    cost = 0
    deepest = 0
    bad = None
    stack = [(tree, False)]
    while stack:
        node, done = stack.pop()
        if not done:
            count += 1
            if count > MAX_NODES:
                raise ModelFileError(f"{where}: the expression has more than {MAX_NODES} "
                                     "syntax nodes; split the model into shorter "
                                     "expressions or raise jetnh.modelfile.MAX_NODES")
            stack.append((node, True))
            stack.extend((c, False) for c in ast.iter_child_nodes(node))
            continue
        below, n = 0, 1
        for c in ast.iter_child_nodes(node):
            below = max(below, level.pop(id(c), 0))
            n += size.pop(id(c), 0)
        if _call_like(node):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                    and node.func.id in HYPERBOLIC):
                f = node.func.id
                if below and bad is None:
                    bad = (node, f"{f} of an expression holding function calls (or non-integer "
                         "powers) is refused (sympy's cost of it explodes); write it with "
                         f"exp, e.g. {_EXP_FORM[f]}:")
                if n - 2 > MAX_HYPERBOLIC_ARG and bad is None:
                    bad = (node, f"the argument of {f} has {n - 2} syntax nodes, more than "
                         f"{MAX_HYPERBOLIC_ARG} (sympy's cost of it explodes); write it with "
                         f"exp, e.g. {_EXP_FORM[f]}:")
                cost += HYPERBOLIC_COST
            else:
                cost += CALL_COST_BASE ** min(below, 40)
            below += 1
            deepest = max(deepest, below)
        level[id(node)] = below
        size[id(node)] = n
    return count, deepest, cost, bad


_EXP_FORM = {"sinh": "sinh(u) = (exp(u) - exp(-u))/2", "cosh": "cosh(u) = (exp(u) + exp(-u))/2",
             "tanh": "tanh(u) = (exp(2*u) - 1)/(exp(2*u) + 1)"}


def _refuse_non_ascii(text: str, where: str, at=None):
    """Refuse the first non-ASCII character of ``text``: Python's parser folds letters
    such as U+FF58 (fullwidth x) or U+1D465 (mathematical italic x) into 'x' (NFKC),
    so a name could silently mean another."""
    for i, ch in enumerate(text):
        if ord(ch) > 127:
            name = unicodedata.name(ch, "")
            folded = unicodedata.normalize("NFKC", ch)
            also = (f"; Python would silently read it as {folded!r}"
                    if folded != ch and folded.isascii() else "")
            pos = ""
            if at is not None:
                line, col = at(i)
                pos = f" at line {line}, column {col + 1}"
            raise ModelFileError(
                f"{where}: the character U+{ord(ch):04X}{f' ({name})' if name else ''} "
                f"{ch!r}{pos} is not ASCII{also}; write names, numbers and operators in "
                "ASCII (letters a-z, A-Z, digits and _)")


def parse_expression(text, names: dict, where: str = "expression", hint: dict | None = None,
                     budget: _Budget | None = None):
    """The sympy expression written in ``text``, with ``names`` (str -> Symbol) declared.

    Raises ``ModelFileError`` for anything outside the language of the module docstring.
    ``hint`` maps names to a specific refusal message (e.g. accelerations).  Line breaks
    count as spaces (multi-line TOML strings), positions refer to the text as given.
    ``budget`` is shared by the expressions of one file (``MAX_FILE_NODES``,
    ``MAX_CALL_COST``); without it, the expression has a budget of its own.
    """
    if not isinstance(text, str):
        raise ModelFileError(f"{where}: expected an expression in a string, got "
                             f"{type(text).__name__} ({_shorten(repr(text))})")
    if len(text) > MAX_CHARS:
        raise ModelFileError(f"{where}: the expression has {len(text)} characters; the limit "
                             f"is {MAX_CHARS}; split the model into shorter expressions")
    if "\x00" in text:
        raise ModelFileError(f"{where}: the expression contains a NUL character; remove it")
    # before ast.parse, which normalises identifiers (NFKC)
    _refuse_non_ascii(text, where, lambda i: _line_col(text, i))
    if not text.strip():
        raise ModelFileError(f"{where}: the expression is empty; write an expression such as "
                             "'x_t**2/2'")
    budget = budget if budget is not None else _Budget()
    # one line, same offsets: a line break is white space in an expression
    flat = text.replace("\r", " ").replace("\n", " ").replace("\t", " ").replace("\f", " ")
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
    except (RecursionError, MemoryError, ValueError, OverflowError) as exc:
        raise ModelFileError(f"{where}: the expression is too deeply nested or too large "
                             f"to parse ({type(exc).__name__}); simplify it") from None
    parser = _Parser(body, names, where, hint, lambda col: _line_col(text, lead + col))
    count, deepest, cost, bad = _measure(tree, where)
    if deepest > MAX_CALL_DEPTH:
        raise ModelFileError(
            f"{where}: function calls (or non-integer powers) are nested {deepest} deep, "
            f"e.g. tanh(tanh(...)); the limit is {MAX_CALL_DEPTH} (sympy's cost of building "
            "and differentiating them grows exponentially with the nesting); introduce a "
            "coordinate or rewrite the expression flatter")
    if bad is not None:
        parser.fail(*bad)
    budget.used_nodes += count
    if budget.used_nodes > budget.nodes:
        raise ModelFileError(
            f"{where}: the expressions of this model have more than {budget.nodes} syntax "
            "nodes together; simplify the model or raise jetnh.modelfile.MAX_FILE_NODES")
    budget.used_calls += cost
    if budget.used_calls > budget.calls:
        raise ModelFileError(
            f"{where}: the function calls of this model cost {budget.used_calls} units, "
            f"more than the limit {budget.calls} (a call with k calls nested inside it costs "
            f"{CALL_COST_BASE}**k units, since building nested functions costs sympy about "
            "that much); use fewer or less deeply nested functions, or raise "
            "jetnh.modelfile.MAX_CALL_COST")
    try:
        expr, _, _ = parser.build(tree)
        if expr.has(*_BAD):
            raise ModelFileError(f"{where}: the expression is infinite or undefined")
        if expr.has(sp.I):
            raise ModelFileError(f"{where}: the expression is complex (jetnh works with real "
                                 "expressions); write it with real functions")
    except JetnhError:
        raise
    except RecursionError:
        raise ModelFileError(f"{where}: the expression is too deeply nested; simplify "
                             "it") from None
    except (OverflowError, MemoryError, ValueError, ArithmeticError) as exc:
        raise ModelFileError(f"{where}: sympy cannot build the expression "
                             f"({type(exc).__name__}: {_shorten(str(exc))}); simplify "
                             "it") from None
    except Exception as exc:
        raise ModelFileError(f"{where}: sympy cannot build the expression (internal: "
                             f"{type(exc).__name__}: {_shorten(str(exc))})") from exc
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
    if kind == "number":
        try:
            finite = math.isfinite(float(value))
        except OverflowError:                  # an int beyond double precision
            finite = False
        if not finite:
            raise ModelFileError(f"{where} must be finite (a number within double "
                                 f"precision), got {_shorten(repr(value))}")
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
                             f"({_shorten(repr(name))})")
    _refuse_non_ascii(name, f"{where}: the name {_shorten(name)!r}")
    if not _NAME.fullmatch(name) or keyword.iskeyword(name):
        raise ModelFileError(
            f"{where}: {name!r} is not a usable name (letters, digits and single underscores, "
            "starting with a letter; not a Python keyword)")
    if name in reserved:
        raise ModelFileError(f"{where}: the name {name!r} is reserved ({reserved[name]})")


def _position(data, offset: int) -> tuple[int, int]:
    """(line, column), both from 1, of a character (str) or byte (bytes) offset."""
    before = data[:offset]
    nl = "\n" if isinstance(before, str) else b"\n"
    line = before.count(nl) + 1
    start = before.rfind(nl) + 1
    head = before[start:]
    if isinstance(head, bytes):
        head = head.decode("utf-8", "replace")
    return line, len(head) + 1


def loads(text: str, source: str = "<string>") -> Model:
    """A ``Model`` from the text of a model file."""
    if not isinstance(text, str):
        raise ModelFileError(f"{source}: a model file is text (str), got "
                             f"{type(text).__name__}; decode bytes as UTF-8 first")
    if len(text) > MAX_FILE_BYTES or len(text.encode("utf-8", "replace")) > MAX_FILE_BYTES:
        raise ModelFileError(f"{source}: the file is larger than {MAX_FILE_BYTES} bytes, the "
                             "limit of a model file")
    nul = text.find("\x00")
    if nul >= 0:
        line, col = _position(text, nul)
        raise ModelFileError(f"{source}: the text contains a NUL character at line {line}, "
                             f"column {col}; a model file is plain text (is this a binary "
                             "file?)")
    if text.startswith("\ufeff"):                    # a UTF-8 byte-order mark
        text = text[1:]
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ModelFileError(f"{source}: not valid TOML: {exc}; see the format in "
                             "jetnh.modelfile's documentation") from None
    except RecursionError:
        raise ModelFileError(f"{source}: not valid TOML: nested too deeply") from None
    except Exception as exc:                       # e.g. ValueError of a 5000-digit integer
        raise ModelFileError(f"{source}: not valid TOML ({type(exc).__name__}: "
                             f"{_shorten(str(exc))})") from None
    return from_dict(data, source)


_FILE_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
               (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
               (stat.S_ISSOCK, "a socket"))


def _not_regular(p, mode) -> ModelFileError:
    kind = next((name for test, name in _FILE_KINDS if test(mode)), "not a regular file")
    return ModelFileError(f"{p}: is {kind}, not a regular file; a model file must be a "
                          "regular file (reading pipes, devices or directories may never "
                          "end); give the path of a .toml file")


def _read_bytes(p: Path) -> bytes:
    """At most ``MAX_FILE_BYTES`` bytes of the regular file ``p`` (symlinks followed)."""
    try:
        # stat first, so that devices and FIFOs are not even opened; then check the
        # opened descriptor itself (the path may have changed in between)
        before = os.stat(p)
        if not stat.S_ISREG(before.st_mode):
            raise _not_regular(p, before.st_mode)
        flags = (os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
                 | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_BINARY", 0))
        fd = os.open(p, flags)
    except ModelFileError:
        raise
    except FileNotFoundError:
        raise ModelFileError(f"{p}: no such file; check the path") from None
    except PermissionError:
        raise ModelFileError(f"{p}: permission denied; the file must be readable") from None
    except (OSError, ValueError) as exc:          # ELOOP, ENAMETOOLONG, a NUL in the path
        why = getattr(exc, "strerror", None) or str(exc)
        raise ModelFileError(f"{p}: cannot open the file ({why})") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise _not_regular(p, st.st_mode)
        if st.st_size > MAX_FILE_BYTES:
            raise ModelFileError(f"{p}: the file has {st.st_size} bytes; the limit is "
                                 f"{MAX_FILE_BYTES}")
        chunks, total = [], 0
        while total <= MAX_FILE_BYTES:            # never more than the limit + 1 bytes
            chunk = os.read(fd, min(1 << 16, MAX_FILE_BYTES + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
        if total > MAX_FILE_BYTES:
            raise ModelFileError(f"{p}: the file has more than {MAX_FILE_BYTES} bytes (the "
                                 "limit)")
        return b"".join(chunks)
    except ModelFileError:
        raise
    except OSError as exc:
        raise ModelFileError(f"{p}: cannot read the file ({exc.strerror or exc})") from None
    finally:
        os.close(fd)


def load(path) -> Model:
    """A ``Model`` from a model file on disk (a regular file; symlinks are followed)."""
    if not isinstance(path, (str, os.PathLike)):
        raise ModelFileError(f"the path of a model file is a str or a Path, got "
                             f"{type(path).__name__}")
    try:
        p = Path(path)
    except (TypeError, ValueError) as exc:
        raise ModelFileError(f"{path!r} is not a usable path ({exc})") from None
    raw = _read_bytes(p)
    nul = raw.find(b"\x00")
    if nul >= 0:
        line, col = _position(raw, nul)
        raise ModelFileError(f"{p}: contains a NUL byte at line {line}, column {col} (byte "
                             f"{nul}); a model file is UTF-8 text (is this a binary file?)")
    if raw.startswith(codecs.BOM_UTF8):
        raw = raw[len(codecs.BOM_UTF8):]
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line, col = _position(raw, exc.start)
        raise ModelFileError(f"{p}: not UTF-8 text: the byte 0x{raw[exc.start]:02X} at line "
                             f"{line}, column {col} (byte {exc.start}) cannot be decoded; "
                             "save the file as UTF-8") from None
    return loads(text, str(p))


def _check_keys(data, S):
    """Every key of the TOML data is a str of ASCII characters (names are ASCII)."""
    stack = [("", data)]
    while stack:
        prefix, table = stack.pop()
        for k, v in table.items():
            if not isinstance(k, str):
                raise ModelFileError(f"{S}: the key {_shorten(repr(k))} is a "
                                     f"{type(k).__name__}; keys are names (strings)")
            _refuse_non_ascii(k, f"{S}: the key {prefix}{_shorten(k)!r}")
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
                             f"{_shorten(str(exc))}); simplify it") from None
    except Exception as exc:
        raise ModelFileError(f"{source}: the model cannot be read (internal: "
                             f"{type(exc).__name__}: {_shorten(str(exc))})") from exc


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
    if len(coords) > MAX_COORDINATES:
        raise ModelFileError(f"{S}: {len(coords)} coordinates; the limit is "
                             f"{MAX_COORDINATES} (reading builds the constraint Jacobian); "
                             "raise jetnh.modelfile.MAX_COORDINATES to read larger models")
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
    budget = _Budget()
    L = parse_expression(data["lagrangian"], names, f"{S}: lagrangian", hint, budget)
    cons_in = data.get("constraints", [])
    _expect(f"{S}: 'constraints'", cons_in, "list of strings")
    if len(cons_in) > MAX_CONSTRAINTS:
        raise ModelFileError(f"{S}: {len(cons_in)} constraints; the limit is "
                             f"{MAX_CONSTRAINTS} (reading checks their rank and chooses the "
                             "split); raise jetnh.modelfile.MAX_CONSTRAINTS to read larger "
                             "models")
    if len(coords) * len(cons_in) > MAX_SPLIT_COST:
        raise ModelFileError(f"{S}: {len(coords)} coordinates times {len(cons_in)} "
                             f"constraints is {len(coords) * len(cons_in)}, more than "
                             f"{MAX_SPLIT_COST} (reading tests the rank of the constraints "
                             "for each candidate split); give a smaller model or raise "
                             "jetnh.modelfile.MAX_SPLIT_COST")
    before = budget.used_nodes
    cons = [parse_expression(c, names, f"{S}: constraints[{i}]", hint, budget)
            for i, c in enumerate(cons_in)]
    jac = len(coords) * (budget.used_nodes - before)
    if jac > MAX_JACOBIAN_COST:
        raise ModelFileError(
            f"{S}: constraints: {len(coords)} coordinates times "
            f"{budget.used_nodes - before} syntax nodes of constraints is {jac}, more than "
            f"{MAX_JACOBIAN_COST} (reading differentiates every constraint by every "
            "velocity); write shorter constraints or raise jetnh.modelfile.MAX_JACOBIAN_COST")
    forces_in = _expect(f"{S}: [forces]", data.get("forces", {}), "table")
    forces = {}
    for k, v in forces_in.items():
        _refuse_non_ascii(k, f"{S}: [forces] {_shorten(k)!r}")
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
    unused = sorted(k for k in params if sp.Symbol(k) not in used)
    if unused:
        raise ModelFileError(f"{S}: [parameters]: {', '.join(unused)} "
                             f"{'is' if len(unused) == 1 else 'are'} used neither in the "
                             "Lagrangian, the constraints nor the forces")

    # jetnh decides the rank of the constraints at random points; where they are never
    # real it falls back to symbolic linear algebra, which can take unbounded time
    if cons and not _real_somewhere(cons, set().union(*(c.free_symbols for c in cons))):
        raise ModelFileError(
            f"{S}: constraints: the constraints are not all finite and real at any of "
            f"{SAMPLE_POINTS} random points (every coordinate, velocity, parameter and t in "
            "[0.31, 1.37]); jetnh works with real expressions: check the domains of the "
            "functions (e.g. acos(3 + x**2) is complex everywhere, log(x - 5) there)")

    dependent = data.get("dependent")
    if dependent is not None:
        _expect(f"{S}: 'dependent'", dependent, "list of strings")
        for d in dependent:
            _refuse_non_ascii(d, f"{S}: dependent: {_shorten(d)!r}")
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
                f"alias, jetnh.mechanics.principles); got {_shorten(principle)!r}") from None
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
                        defaults={sp.Symbol(k): v for k, v in params.items()}, name=name,
                        forces=forces, dissipation=dissipation, branch=branch,
                        check_branch=False)
    except JetnhError as exc:
        raise ModelFileError(f"{S}: {exc}") from None
    except RecursionError:
        raise ModelFileError(f"{S}: the model is nested too deeply to build") from None
    except Exception as exc:
        raise ModelFileError(f"{S}: the system cannot be built ({type(exc).__name__}: "
                             f"{_shorten(str(exc))})") from None

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


__all__ = ["Model", "load", "loads", "from_dict", "dump", "dumps", "parse_expression",
           "expression_text", "FUNCTIONS", "MAX_CHARS", "MAX_NODES", "MAX_DEPTH",
           "MAX_EXPONENT", "MAX_INT_DIGITS", "MAX_NUMBER_DIGITS", "MAX_TERMS",
           "MAX_COORDINATES", "MAX_FILE_BYTES", "MAX_FILE_NODES", "MAX_CALL_DEPTH",
           "MAX_CALL_COST", "MAX_HYPERBOLIC_ARG", "MAX_CONSTRAINTS", "MAX_SPLIT_COST",
           "MAX_JACOBIAN_COST"]
