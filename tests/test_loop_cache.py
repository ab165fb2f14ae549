"""The integrator loops' disk cache (``kernels.loop_cache``): numba's cache files, kept in
jetnh's private store and loaded only when their HMAC under the user's key holds.

A probe function stands in for a loop: one code object compiled over two namespaces, so
that an "attacker's" build (``OFFSET = 666``) has exactly the file names and the numba
index key of the user's (``OFFSET = 42``).  Which of the two a load returns shows whose
machine code ran.
"""

from __future__ import annotations

import os
import stat

import numba
import pytest

from jetnh.numeric.kernels import loop_cache, store
from jetnh.numeric.methods import _common

OFFSET = 0.0


def _probe(x):
    return x + OFFSET


def _build(directory, secret, offset, stamp="sources"):
    """A dispatcher of ``_probe`` over ``OFFSET = offset``, its disk cache signed with
    ``secret`` in ``directory``; compiled or loaded."""
    func = _common.rebound(_probe, dict(globals(), OFFSET=offset))
    func.__qualname__ = "probe"
    d = numba.njit(func)
    d._cache = loop_cache.SignedFunctionCache(func, directory, secret, stamp)
    d.compile((numba.types.float64,))
    return d


def _hits(d) -> int:
    return sum(d._cache_hits.values())


@pytest.fixture
def loops(tmp_path, monkeypatch):
    """(directory, the user's key) of a fresh store."""
    monkeypatch.setenv("JETNH_CACHE", str(tmp_path / "cache"))
    root, secret = store.open_root(True)
    directory = root / loop_cache.LOOPS
    loop_cache._private_directory(directory)
    return directory, secret


def test_a_signed_loop_is_loaded(loops):
    directory, secret = loops
    first = _build(directory, secret, 42.0)
    assert _hits(first) == 0 and first(1.0) == 43.0
    again = _build(directory, secret, 42.0)
    assert _hits(again) == 1 and again(1.0) == 43.0       # from disk, not compiled
    for f in directory.iterdir():
        assert stat.S_IMODE(os.lstat(f).st_mode) == 0o600
    assert stat.S_IMODE(os.lstat(directory).st_mode) == 0o700
    # the control: a file signed with the user's key is trusted, whatever it computes
    # (numba's key covers the code, not the globals: the sources hash in the name does)
    planted = _build(directory, secret, 666.0, stamp="other sources")
    assert _hits(planted) == 0 and planted(1.0) == 667.0
    assert _build(directory, secret, 42.0, stamp="other sources")(1.0) == 667.0


def test_a_loop_signed_with_another_key_is_refused(loops):
    directory, secret = loops
    _build(directory, b"\x01" * 32, 666.0)                 # the attacker's files
    names = sorted(p.name for p in directory.iterdir())
    assert any(n.endswith(".nbc") for n in names) and any(n.endswith(".nbi") for n in names)
    mine = _build(directory, secret, 42.0)
    assert _hits(mine) == 0 and mine(1.0) == 43.0           # compiled anew, not loaded
    assert _build(directory, secret, 42.0)(1.0) == 43.0     # and its own files kept


def test_a_tampered_loop_is_refused_and_removed(loops):
    directory, secret = loops
    _build(directory, secret, 42.0)
    (data,) = directory.glob("*.nbc")
    raw = bytearray(data.read_bytes())
    raw[len(raw) // 2] ^= 0xFF
    data.write_bytes(bytes(raw))
    d = _build(directory, secret, 42.0)
    assert _hits(d) == 0 and d(2.0) == 44.0
    assert _hits(_build(directory, secret, 42.0)) == 1       # the rewritten file is good


def test_numba_own_cache_files_are_not_read(loops, tmp_path):
    """numba's unsigned files (what ``NUMBA_CACHE_DIR`` or ``__pycache__`` would hold)
    under the loop's names are refused; numba's cache directory is never used."""
    directory, secret = loops
    _build(directory, b"\x02" * 32, 666.0)
    for f in directory.iterdir():                           # strip the MAC: numba's format
        f.write_bytes(f.read_bytes()[32:])
    elsewhere = tmp_path / "numba"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(numba.core.config, "CACHE_DIR", str(elsewhere))
        d = _build(directory, secret, 42.0)
    assert _hits(d) == 0 and d(0.0) == 42.0
    assert not elsewhere.exists()


def test_untrusted_files_and_directories_are_not_read(loops):
    directory, secret = loops
    _build(directory, secret, 42.0)
    (index,) = directory.glob("*.nbi")
    os.chmod(index, 0o666)                                  # writable by others
    d = _build(directory, secret, 42.0)
    assert _hits(d) == 0 and d(1.0) == 43.0
    assert stat.S_IMODE(os.lstat(index).st_mode) == 0o600   # written again, private
    os.chmod(directory, 0o777)
    loop_cache._private_directory(directory)                # not private: made again
    assert stat.S_IMODE(os.lstat(directory).st_mode) == 0o700
    assert not list(directory.iterdir())


def test_the_integrator_loops_use_the_signed_store(tmp_path, monkeypatch):
    """``compiled`` gives every loop the signed cache in the store's root, whatever
    numba's configuration says."""
    monkeypatch.setattr(numba.core.config, "CACHE_DIR", str(tmp_path / "numba"))
    monkeypatch.setenv("JETNH_CACHE", str(tmp_path / "cache"))
    cache = loop_cache.cache_for(_probe, _common.sources_hash())
    assert isinstance(cache, loop_cache.SignedFunctionCache)
    assert cache.cache_path == str(store.cache_root() / loop_cache.LOOPS)
    assert not (tmp_path / "numba").exists()


def test_warm_compiles_loops_that_the_next_process_loads(tmp_path):
    """``jetnh cache warm``'s work (``precompile.warm``) in one process; a later process
    loads the loop instead of compiling it."""
    import json
    import subprocess
    import sys

    env = dict(os.environ, JETNH_CACHE=str(tmp_path / "cache"))
    code = ("import json, sys; from jetnh.numeric import precompile as p; "
            "print(json.dumps(p.{}))")

    def child(call):
        out = subprocess.run([sys.executable, "-c", code.format(call)], env=env,
                             capture_output=True, text=True, timeout=600)
        assert out.returncode == 0, out.stderr[-3000:]
        return json.loads(out.stdout.strip().splitlines()[-1])

    first = child('warm(["rk4:plain"], jobs=1)')
    assert list(first) == ["rk4:plain"] and first["rk4:plain"][1] is False   # compiled
    name, _seconds, loaded = child('compile_loop("rk4:plain")')
    assert name == "rk4:plain" and loaded is True
    assert list((tmp_path / "cache").glob("v*/loops/loop._solve_rk4_s_*.nbc"))


def test_warm_refuses_unknown_loops():
    from jetnh.errors import JetnhError
    from jetnh.numeric import precompile

    with pytest.raises(JetnhError, match="unknown loops.*dop853:plain"):
        precompile.warm(["dop853:fast"])
    assert set(precompile.DEFAULT) <= set(precompile.LOOPS)


def test_a_data_file_answers_only_for_its_own_key(tmp_path):
    """Two keys whose index entries got crossed (two processes that picked the same new
    data file name): each load refuses the other's code instead of returning it."""
    f = loop_cache._SignedFile(tmp_path, "probe", "sources", b"k" * 32)
    f.save(("sig", "cpu-a"), "code for a")
    f.save(("sig", "cpu-b"), "code for b")
    assert f.load(("sig", "cpu-a")) == "code for a"
    index = f._load_index()
    index[("sig", "cpu-a")], index[("sig", "cpu-b")] = (index[("sig", "cpu-b")],
                                                        index[("sig", "cpu-a")])
    f._save_index(index)
    assert f.load(("sig", "cpu-a")) is None
    assert f.load(("sig", "cpu-b")) is None
    f.save(("sig", "cpu-a"), "code for a")           # compiled anew, stored for its key
    assert f.load(("sig", "cpu-a")) == "code for a"
