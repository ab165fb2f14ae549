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
multipliers), ``[simulation]`` (``t_start``, ``t_end``, ``method``, ``rtol``,
``atol``, ``points``) and ``[assumptions]`` (parameter = a table of booleans, e.g.
``m = { positive = true }``: what sympy may take as known about the parameter, as
``sp.Symbol("m", positive=True)``; the facts are ``real``, ``nonzero``, ``nonnegative``,
``nonpositive``, ``integer``, ``positive`` and ``negative``, and the parameter's value
must satisfy them; without it a parameter is a plain symbol, and ``jetnh.compare``'s
singular sets keep branches such as ``m = 0``).  Any other key is an error (so jetnh
before ``[assumptions]`` refuses a file that has it, rather than drop the assumptions).  The ``[simulation]`` values are
checked when the file is read, as a run checks them (before any derivation): a known
method, ``rtol`` below 1, a span of nonzero length that floating point resolves;
``t_end`` below ``t_start`` integrates backwards in time.

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
time).  The limits are module attributes (``jetnh.modelfile.limits``): a trusted caller
may raise them, e.g. ``jetnh.modelfile.MAX_CONSTRAINTS = 32``.

The modules: ``read`` (files and text), ``schema`` (keys, names, building the ``System``),
``expression`` (the expression language, both ways), ``assumptions`` (of parameters),
``write``, ``model`` (the ``Model`` record, shared with the catalogue) and ``limits``.
"""

import sys
import types

from . import limits
from .expression import CONSTANTS, FUNCTIONS, HYPERBOLIC, expression_text, parse_expression
from .model import Model
from .read import load, loads
from .schema import REQUIRED_KEYS, SIMULATION_KEYS, TIME, TOP_KEYS, from_dict
from .write import dump, dumps

__all__ = ["Model", "load", "loads", "from_dict", "dump", "dumps", "parse_expression",
           "expression_text", "FUNCTIONS", "CONSTANTS", "HYPERBOLIC", "TIME", "TOP_KEYS",
           "REQUIRED_KEYS", "SIMULATION_KEYS", *limits.__all__]


class _Package(types.ModuleType):
    """``jetnh.modelfile``: each limit is a property that reads and sets it in
    ``jetnh.modelfile.limits``, where the reader looks it up."""


def _limit(name):
    return property(lambda module: getattr(limits, name),
                    lambda module, value: setattr(limits, name, value),
                    doc=f"jetnh.modelfile.limits.{name}")


for _name in limits.__all__:
    setattr(_Package, _name, _limit(_name))
del _name
sys.modules[__name__].__class__ = _Package
