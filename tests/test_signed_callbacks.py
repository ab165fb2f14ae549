"""The trampolines of ``kernels.calls`` and the compiled callbacks of ``discrete`` in
jetnh's signed store (``loop_cache.signed_njit``, ``signed_cfunc``), never in numba's own
cache: a file signed with another key, stripped of its MAC (numba's own format) or
tampered with is refused, and the function compiled anew.

An "attacker's" build has the file names and numba index key of the user's (the same
code object, other globals): which value a call returns shows whose machine code ran.
"""

from __future__ import annotations

import numba
import numpy as np
import pytest

from jetnh.numeric import discrete
from jetnh.numeric.kernels import calls, loop_cache, store
from jetnh.numeric.methods._common import FunctionAddress, RHS_SIGNATURE, rebound

STAMP = "test-stamp"
OTHER_KEY = b"\x01" * 32


@pytest.fixture
def loops(tmp_path, monkeypatch):
    """(loops directory, the user's key) of a fresh store; numba's own cache directory
    set to a place that must stay untouched."""
    monkeypatch.setenv("JETNH_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(numba.core.config, "CACHE_DIR", str(tmp_path / "numba"))
    root, secret = store.open_root(True)
    directory = root / loop_cache.LOOPS
    loop_cache._private_directory(directory)
    yield directory, secret
    assert not (tmp_path / "numba").exists()


def _hits(f) -> int:
    hits = f._cache_hits
    return hits if isinstance(hits, int) else sum(hits.values())


# ---------------------------------------------------------------------- the trampolines
@numba.cfunc(RHS_SIGNATURE)
def _double(t, y, p, out):
    for i in range(y.shape[0]):
        out[i] = 2.0 * y[i] + t


@numba.njit
def _evil_call(address, t, y, p, out):
    out[0] = 666.0


def _trampoline(directory, secret):
    """``calls._call`` built as an attacker would: it writes 666 whatever the kernel."""
    func = rebound(calls._call, dict(vars(calls), _call_at=_evil_call))
    d = numba.njit(**calls._JIT)(func)
    d._cache = loop_cache.SignedFunctionCache(func, directory, secret, STAMP,
                                              f"_call_{STAMP}")
    d.compile(calls._TRAMPOLINES[calls._call][0])
    return d


def _mine():
    return loop_cache.signed_njit(calls._call, calls._TRAMPOLINES[calls._call][0], STAMP,
                                  **calls._JIT)


def _value(d) -> float:
    out = np.zeros(2)
    d(FunctionAddress(_double).address, calls._pack((2, 0, 2)), 1.0, np.array([3.0, 4.0]),
      np.zeros(0), out)
    return tuple(out)


def test_a_trampoline_is_signed_and_loaded(loops):
    directory, secret = loops
    first = _mine()
    assert _hits(first) == 0 and _value(first) == (7.0, 9.0)
    again = _mine()
    assert _hits(again) == 1 and _value(again) == (7.0, 9.0)
    assert sorted(p.suffix for p in directory.glob(f"calls._call_{STAMP}-*")) == [".nbc",
                                                                                  ".nbi"]
    # the control: a file signed with the user's key is trusted, whatever it computes
    directory_files = list(directory.iterdir())
    for f in directory_files:
        f.unlink()
    _trampoline(directory, secret)
    planted = _mine()
    assert _hits(planted) == 1 and _value(planted)[0] == 666.0


def test_a_trampoline_signed_with_another_key_is_refused(loops):
    directory, _ = loops
    _trampoline(directory, OTHER_KEY)
    mine = _mine()
    assert _hits(mine) == 0 and _value(mine) == (7.0, 9.0)


def test_an_unsigned_trampoline_is_refused(loops):
    """numba's own format (what ``NUMBA_CACHE_DIR`` or ``__pycache__`` would hold)."""
    directory, _ = loops
    _trampoline(directory, OTHER_KEY)
    for f in directory.iterdir():
        f.write_bytes(f.read_bytes()[32:])
    mine = _mine()
    assert _hits(mine) == 0 and _value(mine) == (7.0, 9.0)


def test_a_tampered_trampoline_is_refused_and_removed(loops):
    directory, _ = loops
    _mine()
    (data,) = directory.glob("*.nbc")
    raw = bytearray(data.read_bytes())
    raw[len(raw) // 2] ^= 0xFF
    data.write_bytes(bytes(raw))
    d = _mine()
    assert _hits(d) == 0 and _value(d) == (7.0, 9.0)
    assert _hits(_mine()) == 1                             # the rewritten file is good


def test_kernels_called_from_python_use_the_signed_trampolines():
    for py_func in (calls._call, calls._call_jac, calls._rows):
        d = calls.trampoline(py_func)
        assert isinstance(d._cache, loop_cache.SignedFunctionCache)
        assert len(d.signatures) == 1
    k = calls.Kernel(_double, (2, 0, 2))
    out = np.zeros(2)
    k(0.5, np.array([1.0, -1.0]), np.zeros(0), out)
    assert tuple(out) == (2.5, -1.5)
    with pytest.raises(TypeError, match="C-contiguous float64"):
        k(0.5, np.array([1, 2]), np.zeros(0), out)


# ---------------------------------------------------------------------- compiled callbacks
OFFSET = 0.0


def _probe(x):
    return x + OFFSET


def _callback(directory, secret, offset):
    """``_probe`` over ``OFFSET = offset`` as a cfunc, its cache signed with ``secret``."""
    from numba.core.ccallback import CFunc

    func = rebound(_probe, dict(globals(), OFFSET=offset))
    cf = CFunc(func, ((numba.float64,), numba.float64), locals={}, options={})
    cf._cache = loop_cache.SignedFunctionCache(func, directory, secret, STAMP,
                                               f"_probe_{STAMP}")
    cf.compile()
    return cf


def _my_callback():
    return loop_cache.signed_cfunc(_probe, numba.float64(numba.float64), STAMP)


def test_a_signed_cfunc_is_loaded(loops):
    directory, secret = loops
    first = _my_callback()
    assert _hits(first) == 0 and first.ctypes(1.0) == 1.0
    again = _my_callback()
    assert _hits(again) == 1 and again.ctypes(1.0) == 1.0
    for f in directory.iterdir():                           # the control (own key)
        f.unlink()
    _callback(directory, secret, 666.0)
    assert _my_callback().ctypes(1.0) == 667.0


@pytest.mark.parametrize("damage", ["other key", "unsigned", "tampered"])
def test_an_untrusted_cfunc_is_refused(loops, damage):
    directory, secret = loops
    _callback(directory, OTHER_KEY if damage == "other key" else secret, 666.0)
    for f in directory.iterdir():
        raw = bytearray(f.read_bytes())
        if damage == "unsigned":
            raw = raw[32:]
        elif damage == "tampered" and f.suffix == ".nbc":
            raw[-1] ^= 0x01
        f.write_bytes(bytes(raw))
    if damage == "tampered":                                # the index alone still holds
        assert any(f.suffix == ".nbi" for f in directory.iterdir())
    mine = _my_callback()
    assert _hits(mine) == 0 and mine.ctypes(1.0) == 1.0


def test_the_no_event_callback_is_in_the_signed_store(loops):
    directory, _ = loops
    first = discrete._no_events.__wrapped__()
    assert isinstance(first._cache, loop_cache.SignedFunctionCache) and _hits(first) == 0
    assert list(directory.glob("discrete._nothing_*.nbc"))
    again = discrete._no_events.__wrapped__()
    assert _hits(again) == 1
    out = np.full(1, 5.0)
    calls.Kernel(again, (1, 0, 1))(0.0, np.zeros(1), np.zeros(0), out)
    assert out[0] == 5.0                                    # a no-op: out untouched


# ---------------------------------------------------------------------- generated kernels
def test_kernels_compile_uncached_where_numba_would_cache_unchecked(tmp_path, monkeypatch):
    """A kernel module uses numba's cache only where numba keeps it in the entry's own
    ``__pycache__`` (which the manifest covers): not when ``NUMBA_CACHE_DIR`` is set, nor
    when ``__pycache__`` cannot be made there (numba would fall back to its user-wide
    cache)."""
    from jetnh.errors import KernelCacheWarning
    from jetnh.numeric.kernels import loader

    monkeypatch.setattr(loader, "_WARNED", set())
    monkeypatch.setattr(numba.core.config, "CACHE_DIR", "")
    source = b"CACHED = JETNH_NUMBA_CACHE\n"
    good, blocked = tmp_path / "good", tmp_path / "blocked"
    for d in (good, blocked):
        d.mkdir()
        (d / "kernels.py").write_bytes(source)
    (blocked / "__pycache__").write_bytes(b"not a directory")
    assert loader._exec_kernels("jetnh_probe_good", good, source).CACHED is True
    with pytest.warns(KernelCacheWarning, match="numba cannot write .*__pycache__"):
        mod = loader._exec_kernels("jetnh_probe_blocked", blocked, source + b"#\n")
    assert mod.CACHED is False
    monkeypatch.setattr(numba.core.config, "CACHE_DIR", str(tmp_path / "numba"))
    with pytest.warns(KernelCacheWarning, match="NUMBA_CACHE_DIR"):
        mod = loader._exec_kernels("jetnh_probe_env", good, source + b"##\n")
    assert mod.CACHED is False
    for package in ("jetnh_probe_good", "jetnh_probe_blocked", "jetnh_probe_env"):
        loader._forget(package)


def test_the_chart_change_is_stamped_with_the_calling_convention_it_compiles_in(monkeypatch):
    """``chart_change.compiled`` inlines ``kernels.calls._call_at``: its signed-store
    stamp changes with ``calls.py`` as with its own file (stale machine code calling the
    kernels the old way is never loaded)."""
    from jetnh.numeric import chart_change

    stamps = {chart_change.__file__: "own", calls.__file__: "abi"}
    seen = []
    monkeypatch.setattr(loop_cache, "file_stamp", lambda path: stamps.get(path, "other"))
    monkeypatch.setattr(loop_cache, "signed_njit",
                        lambda fn, signature, stamp, **options: seen.append(stamp))
    chart_change.compiled.__wrapped__()
    stamps[calls.__file__] = "abi2"
    chart_change.compiled.__wrapped__()
    assert seen == ["ownabi", "ownabi2"]
