"""The limits of reading a model file (each documented in ``jetnh.modelfile``).

They were measured so that the largest allowed models read in about 2 s.  A trusted
caller may raise them as ``jetnh.modelfile.MAX_...``, which sets them here, where the
reader looks them up on every call.
"""

#: characters of one expression
MAX_CHARS = 20_000
#: syntax nodes of one expression
MAX_NODES = 5_000
#: syntax nodes of all the expressions of one file
MAX_FILE_NODES = 20_000
#: nesting depth of one expression (chains of + or * count once)
MAX_DEPTH = 100
#: nesting of function calls (and powers whose exponent is not an integer literal)
MAX_CALL_DEPTH = 5
#: units of function calls per file; a call with k calls nested inside it costs
#: CALL_COST_BASE**k units
MAX_CALL_COST = 2_000
CALL_COST_BASE = 3
#: units each sinh, cosh or tanh costs; their argument has at most MAX_HYPERBOLIC_ARG nodes
HYPERBOLIC_COST = 20
MAX_HYPERBOLIC_ARG = 30
#: absolute value of an integer exponent (after sympy combines equal bases)
MAX_EXPONENT = 64
#: digits of an integer literal, and of an exact number built from literals
MAX_INT_DIGITS = 40
MAX_NUMBER_DIGITS = 200
#: bytes of a model file
MAX_FILE_BYTES = 1_000_000
#: terms of an expression when expanded (estimated from the syntax)
MAX_TERMS = 10_000
#: coordinates and constraints of a model
MAX_COORDINATES = 100
MAX_CONSTRAINTS = 16
#: coordinates times the syntax nodes of all constraints (the constraint Jacobian)
MAX_JACOBIAN_COST = 20_000
#: coordinates times constraints (the automatic split tests ranks for each candidate)
MAX_SPLIT_COST = 500
#: random points at which the constraints must all be finite and real at least once
SAMPLE_POINTS = 24

__all__ = ["MAX_CHARS", "MAX_NODES", "MAX_FILE_NODES", "MAX_DEPTH", "MAX_CALL_DEPTH",
           "MAX_CALL_COST", "CALL_COST_BASE", "HYPERBOLIC_COST", "MAX_HYPERBOLIC_ARG",
           "MAX_EXPONENT", "MAX_INT_DIGITS", "MAX_NUMBER_DIGITS", "MAX_FILE_BYTES",
           "MAX_TERMS", "MAX_COORDINATES", "MAX_CONSTRAINTS", "MAX_JACOBIAN_COST",
           "MAX_SPLIT_COST", "SAMPLE_POINTS"]
