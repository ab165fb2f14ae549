"""Fuzzing the model-file reader: whatever the input, only a JetnhError escapes, and every
call returns within a time bound.

Inputs: random bytes (through ``load``), random text (``loads``), random TOML-like data
(``from_dict``), and mutations of valid files (the examples and the catalogue's written
files) with hostile expressions spliced in.  The number of examples comes from the
hypothesis profile of tests/conftest.py ("ci": derandomized and bounded; "dev": more).
"""

import math
import pathlib
import tempfile

import pytest
import sympy as sp
from hypothesis import given
from hypothesis import strategies as st

from jetnh import models
from jetnh import modelfile as mf
from jetnh.errors import JetnhError
from deadline import deadline

BOUND = 5.0          # seconds per call (the documented limits are measured at about 2 s)
HARD = 30.0          # a call still running then is interrupted, and the test fails

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXAMPLES = [p.read_text(encoding="utf-8") for p in sorted((ROOT / "examples").glob("*.toml"))]


def _catalogue_files():
    out = []
    for name in models.CATALOGUE:
        opts = {"n_trailer": {"N": 1}}.get(name, {})
        try:
            out.append(mf.dumps(models.get(name, **opts), models.initial(name, **opts),
                                simulation={"t_end": 1.0}))
        except JetnhError:                     # pragma: no cover - the catalogue writes
            pass
    return out


VALID = EXAMPLES + _catalogue_files()

HOSTILE = [
    "tanh(" * 12 + "x" + ")" * 12, "exp(exp(exp(exp(10))))", "10**10**10", "9**9**9**9",
    "((x_t + 1)**64 + 1)**64", "(x + 1)**64*(x + 1)", "10.0**10.0**10.0", "1e308*10",
    "__import__('os').system('true')", "open('/etc/passwd')", "x.__class__", "lambda: 0",
    "\uff58_t", "\U0001d465", "x\u2002+ 1", "\x00", "sin(" * 60 + "x" + ")" * 60,
    "(" * 150 + "x" + ")" * 150, "-" * 500 + "x", "Abs(x)", "sign(x)", "floor(x)",
    "Max(x, 1)", "1/0", "log(0)", "sqrt(-1)", "acos(3 + x**2)", "atan2(0, 0)",
    "(-8)**(1/3)", "x**0.5**0.5", "tanh(sin(x))", "cosh(" + "+".join(["x"] * 40) + ")",
    "1" * 60, "0x10", "1_000", "x_tt", "lambda_x", "t**t**t", "pi**pi**pi**pi",
    "*".join(["x", "y"] * 200), "+".join(f"sin({k}*x)" for k in range(400)),
    "exp(710)", "cosh(1000)", "tan(pi/2)", "sec(pi/2)", "0**-1", "x**-65",
]
HOSTILE_LINES = [
    'branch = 99', 'branch = -1', 'branch = 1e3', 'dependent = ["nope"]', 'dependent = []',
    'coordinates = []', 'coordinates = ["t"]', 'coordinates = ["x", "x"]',
    'principle = "lagrange"', 'convention = 3', '[simulation]\npoints = 1',
    '[simulation]\nt_end = inf', '[parameters]\nk = nan', '[parameters]\n"\uff4b" = 1.0',
    '[initial]\nlambda_x = 1.0', '[integrals]\nE = "x_t**2"', 'name = "\\u001b[2J"',
    'a = [[[[[[[[[[[[[[[[[[[[[[[[1]]]]]]]]]]]]]]]]]]]]]]]', 'big = 1' + "0" * 5000,
    '[[coordinates]]', 'lagrangian = """x_t**2\n+ 1"""', "\ufeff", "\x00",
]


def _guarded(fn, *args):
    """fn(*args), which may return or raise a JetnhError only, within BOUND seconds."""
    with deadline(BOUND, "the reader", hard=HARD):
        try:
            fn(*args)
        except JetnhError as exc:
            assert "(internal" not in str(exc), f"an unexpected error was wrapped: {exc}"


# ---------------------------------------------------------------------- mutations
@st.composite
def mutated(draw):
    text = draw(st.sampled_from(VALID))
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.integers(0, 6))
        n = len(text)
        i = draw(st.integers(0, n))
        j = draw(st.integers(i, min(n, i + 40)))
        if kind == 0:                                  # replace a character
            text = text[:i] + draw(st.characters()) + text[i + 1:]
        elif kind == 1:                                # delete a slice
            text = text[:i] + text[j:]
        elif kind == 2:                                # insert a hostile expression
            text = text[:i] + draw(st.sampled_from(HOSTILE)) + text[i:]
        elif kind == 3:                                # replace an expression's text
            quotes = [k for k, c in enumerate(text) if c == '"']
            if len(quotes) >= 2:
                a = draw(st.integers(0, len(quotes) - 2))
                s, e = quotes[a], quotes[a + 1]
                frag = draw(st.sampled_from(HOSTILE)).replace("\\", "\\\\").replace('"', "'")
                text = text[:s + 1] + frag + text[e:]
        elif kind == 4:                                # add a hostile line
            lines = text.split("\n")
            k = draw(st.integers(0, len(lines)))
            lines.insert(k, draw(st.sampled_from(HOSTILE_LINES)))
            text = "\n".join(lines)
        elif kind == 5:                                # duplicate or drop a line
            lines = text.split("\n")
            k = draw(st.integers(0, len(lines) - 1))
            if draw(st.booleans()):
                lines.insert(k, lines[k])
            else:
                del lines[k]
            text = "\n".join(lines)
        else:                                          # swap two lines
            lines = text.split("\n")
            a, b = draw(st.integers(0, len(lines) - 1)), draw(st.integers(0, len(lines) - 1))
            lines[a], lines[b] = lines[b], lines[a]
            text = "\n".join(lines)
    return text


def test_the_valid_files_read():
    assert len(VALID) >= len(EXAMPLES) + 10
    for text in VALID:
        _guarded(mf.loads, text)
        mf.loads(text)                                 # and they are valid


@given(mutated())
def test_mutated_files(text):
    _guarded(mf.loads, text)


@given(st.binary(max_size=2000))
def test_random_bytes_from_disk(raw):
    with tempfile.TemporaryDirectory() as d:
        p = pathlib.Path(d) / "m.toml"
        p.write_bytes(raw)
        _guarded(mf.load, p)


@given(st.text(max_size=400))
def test_random_text(text):
    _guarded(mf.loads, text)


@given(st.lists(st.sampled_from(HOSTILE_LINES + [f'lagrangian = "{h}"' for h in HOSTILE
                                                 if '"' not in h and "\\" not in h]),
                max_size=6))
def test_hostile_lines_around_a_valid_core(lines):
    core = 'coordinates = ["x", "y"]\nconstraints = ["y_t - x*x_t"]\n'
    has_l = any(ln.startswith("lagrangian") for ln in lines)
    text = core + ("" if has_l else 'lagrangian = "(x_t**2 + y_t**2)/2"\n') + "\n".join(lines)
    _guarded(mf.loads, text)


_scalars = (st.none() | st.booleans() | st.integers() | st.floats()
            | st.text(max_size=30) | st.sampled_from(HOSTILE)
            | st.just(math.inf) | st.just(10 ** 400))
_data = st.recursive(_scalars, lambda c: st.lists(c, max_size=4)
                     | st.dictionaries(st.text(max_size=8) | st.integers(), c, max_size=4),
                     max_leaves=20)
_keys = st.sampled_from(sorted(mf.TOP_KEYS) + ["other"])


@given(st.dictionaries(_keys, _data, max_size=8))
def test_random_data(data):
    """from_dict with any Python data (not only what TOML can express)."""
    data.setdefault("coordinates", ["x", "y"])
    data.setdefault("lagrangian", "(x_t**2 + y_t**2)/2")
    _guarded(mf.from_dict, data)


@pytest.mark.parametrize("text", HOSTILE)
def test_each_hostile_expression(text):
    names = {n: sp.Symbol(n) for n in ("x", "x_t", "y", "y_t", "t")}
    _guarded(mf.parse_expression, text, names)
