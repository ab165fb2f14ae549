"""Quick compilation of huge kernels (``jetnh.numeric.codegen.quick``): chosen by size and
kind, part of the kernel cache key, and the same arithmetic as numba's -O3 route (bit-for-bit
equal outputs, two compilations of one program compared)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jetnh import models
from jetnh.errors import JetnhError
from jetnh.numeric import Scene
from jetnh.numeric.codegen import KernelSpec, quick
from jetnh.numeric.codegen.llvm import program_of, program_text, straight_line
from jetnh.numeric.methods._common import FunctionAddress

SIG = "void(float64, float64[::1], float64[::1], float64[::1])"


def _callbacks(ops):
    """The program ``ops`` as a numba -O3 callback and as a quick one (no cache)."""
    import numba

    body = straight_line(ops)

    def kernel(t, y, p, out):
        body(t, y, p, out)

    return (numba.cfunc(SIG, error_model="numpy")(kernel),
            quick.quick_cfunc(SIG, error_model="numpy")(kernel))


def _call(cfunc, y, n_out):
    from jetnh.numeric.kernels.calls import Kernel

    out = np.zeros(n_out)
    Kernel(FunctionAddress(cfunc), (len(y), 0, n_out))(0.3, y, np.zeros(0), out)
    return out


def test_the_threshold_picks_the_decorator(monkeypatch):
    monkeypatch.delenv("JETNH_QUICK_OPS", raising=False)
    assert quick.decorator(quick.QUICK_OPS) == "@numba.cfunc(_SIG, **_CB)"
    assert quick.decorator(quick.QUICK_OPS + 1, "_JAC_SIG") == "@quick_cfunc(_JAC_SIG, **_CB)"
    monkeypatch.setenv("JETNH_QUICK_OPS", "10")
    assert quick.decorator(11) == "@quick_cfunc(_SIG, **_CB)"
    assert quick.decorator(10) == "@numba.cfunc(_SIG, **_CB)"


def test_kernels_called_less_often_are_compiled_quickly_from_smaller_sizes(monkeypatch):
    """rhs (every stage) at QUICK_OPS, jac at a quarter of it, the kernels called once a
    step or less (aux, sing, hol, events, verdicts) at an eighth; JETNH_QUICK_OPS moves
    them together."""
    monkeypatch.delenv("JETNH_QUICK_OPS", raising=False)
    for kind, threshold in (("rhs", 8000), ("jac", 2000), ("aux", 1000), ("sing", 1000),
                            ("hol", 1000), ("events", 1000), ("verdicts", 1000)):
        assert quick.quick_ops(kind) == threshold
        assert quick.decorator(threshold, kind=kind) == "@numba.cfunc(_SIG, **_CB)"
        assert quick.decorator(threshold + 1, kind=kind) == "@quick_cfunc(_SIG, **_CB)"
    assert quick.decorator(2000, "_JAC_SIG") == "@numba.cfunc(_JAC_SIG, **_CB)"
    assert quick.decorator(2001, "_JAC_SIG") == "@quick_cfunc(_JAC_SIG, **_CB)"
    monkeypatch.setenv("JETNH_QUICK_OPS", "800")
    assert [quick.quick_ops(k) for k in ("rhs", "jac", "sing")] == [800, 200, 100]


def test_the_catalogue_keeps_o3_where_the_n_trailer_keeps_it(monkeypatch, tmp_path):
    """The N-trailer at N = 8 (Suslov: the largest aux) keeps numba's -O3 for rhs, aux and
    sing; at N = 16 aux and sing (once a step) are compiled quickly, the rhs is not."""
    from jetnh.numeric.codegen import generate, multiplier_names

    monkeypatch.delenv("JETNH_QUICK_OPS", raising=False)
    for N, principle, quick_ones in ((8, "suslov", set()), (16, "chetaev", {"aux", "sing"})):
        system = models.get("n_trailer", N=N)
        initial = {**models.initial("n_trailer", N=N),
                   **{m: 0.0 for m in multiplier_names(system, principle)}}
        src = generate(Scene(system, principle, initial=initial).spec).source
        routes = {k: src.count(f"@quick_cfunc(_SIG, **_CB)\ndef {k}_c(") == 1
                  for k in ("rhs", "aux", "sing")}
        assert {k for k, q in routes.items() if q} == quick_ones, (N, routes)


def test_a_quick_callback_is_built_from_assembly_text_below_the_rhs_threshold(monkeypatch):
    """The intrinsic follows the route of the callback compiling it: LLVM assembly text
    (``ir_text``) under ``quick_cfunc`` whatever the size, instructions built one by one
    under numba's -O3 below the rhs threshold; the same bits."""
    from jetnh.numeric.codegen import llvm

    monkeypatch.delenv("JETNH_QUICK_OPS", raising=False)
    texts = []
    real = llvm.ir_text
    monkeypatch.setattr(llvm, "ir_text", lambda ops: texts.append(len(ops)) or real(ops))
    ops = (("y", 0), ("y", 1), ("mul", 0, 1), ("fn", "cos", 2), ("out", 0, 3),
           ("t",), ("add", 5, 0), ("out", 1, 6))
    full, fast = _callbacks(ops)
    assert texts == [len(ops)]                # once: the quick callback's
    y = np.array([0.7, -1.3, 0.2])
    np.testing.assert_array_equal(_call(full, y, 2), _call(fast, y, 2))


def test_a_bad_threshold_names_the_variable(monkeypatch):
    monkeypatch.setenv("JETNH_QUICK_OPS", "lots")
    with pytest.raises(JetnhError, match="JETNH_QUICK_OPS"):
        quick.quick_ops()


def test_the_threshold_is_part_of_the_cache_key(monkeypatch):
    system = models.get("knife_edge")
    monkeypatch.delenv("JETNH_QUICK_OPS", raising=False)
    default = KernelSpec(system, "chetaev", {}).key
    monkeypatch.setenv("JETNH_QUICK_OPS", "0")
    assert KernelSpec(system, "chetaev", {}).key != default
    monkeypatch.setenv("JETNH_QUICK_OPS", str(quick.QUICK_OPS))
    assert KernelSpec(system, "chetaev", {}).key == default


def test_a_scene_above_the_threshold_compiles_quickly_and_runs_alike(monkeypatch, tmp_path):
    """Every kernel of the 2-trailer quick (threshold 0) against every kernel at -O3
    (threshold above their size): the source says which, the trajectories agree bit for
    bit."""
    runs = {}
    for name, threshold in (("quick", "0"), ("full", "1000000")):
        monkeypatch.setenv("JETNH_QUICK_OPS", threshold)
        monkeypatch.setenv("JETNH_CACHE", str(tmp_path / name))
        system = models.get("n_trailer", N=2)
        sc = Scene(system, "vakonomic",
                   initial={**models.initial("n_trailer", N=2), "lambda_y": 0.01,
                            "lambda_theta1": -0.01, "lambda_theta2": 0.01},
                   t_span=(0.0, 0.5))
        src = sc.kernels.source
        marks = src.count("@quick_cfunc("), src.count("@numba.cfunc(")
        assert marks == ((3, 0) if name == "quick" else (0, 3)), marks
        tr = sc.run(method="dop853", rtol=1e-10, atol=1e-12)
        runs[name] = np.column_stack([tr.t, tr.y])
    np.testing.assert_array_equal(runs["quick"], runs["full"])


_leaf = st.sampled_from([("y", 0), ("y", 1), ("y", 2), ("t",), ("c", 0.75), ("c", -1.5)])


@st.composite
def programs(draw):
    """Random straight-line programs over every instruction kind, outputs at the end."""
    ops = [("y", 0), ("y", 1), ("y", 2), ("t",)]
    for _ in range(draw(st.integers(1, 25))):
        n = len(ops)
        idx = st.integers(0, n - 1)
        kind = draw(st.sampled_from(["add", "mul", "div", "powi", "fn", "pow", "leaf"]))
        if kind in ("add", "mul"):
            ops.append((kind, *draw(st.lists(idx, min_size=2, max_size=4))))
        elif kind == "div":
            ops.append(("div", draw(idx), draw(idx)))
        elif kind == "powi":
            ops.append(("powi", draw(idx), draw(st.integers(1, 7))))
        elif kind == "pow":                  # a positive base: 1 + x*x
            x = draw(idx)
            ops += [("c", 1.0), ("mul", x, x)]
            ops.append(("add", len(ops) - 2, len(ops) - 1))
            ops.append(("pow", len(ops) - 1, draw(idx)))
        elif kind == "fn":
            ops.append(("fn", draw(st.sampled_from(["sin", "cos", "exp", "abs"])), draw(idx)))
        else:
            ops.append(draw(_leaf))
    n = len(ops)
    outs = draw(st.lists(st.integers(0, n - 1), min_size=1, max_size=5))
    return tuple(ops) + tuple(("out", k, i) for k, i in enumerate(outs)), len(outs)


@settings(max_examples=8, deadline=None)
@given(programs(), st.lists(st.floats(-2, 2), min_size=3, max_size=3))
def test_quick_and_full_callbacks_agree_bit_for_bit(prog, y):
    ops, n_out = prog
    full, fast = _callbacks(ops)
    y = np.array(y)
    a, b = _call(full, y, n_out), _call(fast, y, n_out)
    np.testing.assert_array_equal(a, b)


@settings(max_examples=8, deadline=None)
@given(programs(), st.lists(st.floats(-2, 2), min_size=3, max_size=3))
def test_assembly_text_and_instruction_builder_agree_bit_for_bit(prog, y):
    """A program above the threshold is written as LLVM assembly (``llvm.ir_text``); the
    same program built instruction by instruction computes the same bits (both at -O3
    and quick)."""
    import os

    import numba

    ops, n_out = prog
    ops = ops + (("fn", "atan2", 0, 1), ("out", n_out, len(ops)))
    old = os.environ.get("JETNH_QUICK_OPS")
    try:
        os.environ["JETNH_QUICK_OPS"] = "0"
        text = straight_line(ops)
    finally:
        if old is None:
            del os.environ["JETNH_QUICK_OPS"]
        else:
            os.environ["JETNH_QUICK_OPS"] = old
    builder = straight_line(ops) if len(ops) <= quick.quick_ops() else None
    assert builder is not None

    def make(body, compiler):
        def kernel(t, y, p, out):
            body(t, y, p, out)
        return compiler(SIG, error_model="numpy")(kernel)

    y = np.array(y)
    ref = _call(make(builder, numba.cfunc), y, n_out + 1)
    for compiler in (numba.cfunc, quick.quick_cfunc):
        np.testing.assert_array_equal(_call(make(text, compiler), y, n_out + 1), ref)


@settings(max_examples=25, deadline=None)
@given(programs(), st.lists(st.sampled_from(
    [-0.0, 0.0, 5e-324, -1.7976931348623157e308, 0.1, 1 / 3, float("inf")]), max_size=4))
def test_programs_round_trip_through_their_text(prog, constants):
    """A generated module holds its programs as text (``program_text``); ``program_of``
    gives back the same instructions, every float bit for bit."""
    import struct

    ops = prog[0] + tuple(("c", x) for x in constants)
    back = program_of(program_text(ops))
    assert back == ops and all(type(a) is type(b) for p, q in zip(back, ops)
                               for a, b in zip(p, q))
    bits = [struct.pack("<d", op[1]) for op in back if op[0] == "c"]
    assert bits == [struct.pack("<d", op[1]) for op in ops if op[0] == "c"]
