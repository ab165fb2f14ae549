"""The kernel cache: private, verified before use (planted code never runs), self-repairing,
safe under concurrent writers and deletion, and falling back when the root is unusable."""

import hashlib
import json
import math
import os
import pickle
import shutil
import stat
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numba
import pytest
import sympy as sp

import jetnh as jn
from jetnh.errors import KernelCacheWarning
from jetnh.numeric import Scene, codegen
from jetnh.numeric.kernels import loader, store as cache
from jetnh.numeric.layout import Layout

ROOT_USER = os.geteuid() == 0
OTHER_UID = 65534                     # "nobody"
REPO = Path(__file__).resolve().parents[1]


def oscillator():
    J = jn.JetSpace("x")
    (x,), (xd,) = J.q, J.qd
    k = sp.Symbol("k")
    return jn.System(J, xd**2 / 2 - k * x**2 / 2, []), k


def scene(kval):
    """x'' = -k x, x(0) = 1, x'(0) = 0: x(1) = cos(sqrt(k)).  Each k is its own key."""
    s, k = oscillator()
    return Scene(s, "chetaev", params={k: kval}, initial=dict(x=1.0, x_t=0.0),
                 t_span=(0.0, 1.0))


def assert_runs(sc, kval):
    tr = sc.run(save="final")
    assert abs(tr["x"][-1] - math.cos(math.sqrt(kval))) < 1e-6


def trusted(directory: Path, key: str) -> bool:
    try:
        return cache.verify(directory, key, cache.secret_key(directory.parent)) is not None
    except cache.Untrusted:
        return False


def reload(sc, forget=False):
    """The scene's kernels loaded again from disk (not from this process's memo; with
    ``forget``, not even its module: numba loads or compiles as in a new process)."""
    loader._LOADED.clear()
    if forget:
        loader._forget(f"jetnh_kernels_{sc.key}")
    return sc.kernels


@pytest.fixture
def fresh(tmp_path, monkeypatch):
    """An empty cache of this test, and no kernels remembered by the process."""
    root = tmp_path / "cache"
    monkeypatch.setenv("JETNH_CACHE", str(root))
    monkeypatch.setattr(loader, "_LOADED", {})
    monkeypatch.setattr(loader, "_KEY_LOCKS", {})
    monkeypatch.setattr(loader, "_WARNED", set())
    monkeypatch.setattr(cache, "_WARNED", set())
    return root


def modes(root: Path):
    return {p: stat.S_IMODE(os.lstat(p).st_mode) for p in [root, *root.rglob("*")]}


# ---------------------------------------------------------------------- privacy
def test_private_under_umask_000_and_numba_files_in_manifest(fresh):
    old = os.umask(0)
    try:
        sc = scene(1.25)
        ck = sc.kernels
        assert_runs(sc, 1.25)
    finally:
        os.umask(old)
    for path, mode in modes(fresh).items():
        want = 0o700 if path.is_dir() else 0o600
        assert mode == want, f"{path}: {mode:o}"
    manifest = json.loads((ck.directory / "manifest.json").read_text())["body"]["files"]
    numba_files = {f"__pycache__/{p.name}" for p in (ck.directory / "__pycache__").iterdir()}
    assert any(n.endswith(".nbi") for n in numba_files)
    assert any(n.endswith(".nbc") for n in numba_files)
    assert set(manifest) == {"__init__.py", "kernels.py", "layout.json"} | numba_files
    assert (cache.cache_root() / "hmac.key").stat().st_size == 32
    assert trusted(ck.directory, sc.key)


def test_entry_open_to_others_or_not_ours_is_refused_and_rebuilt(fresh):
    sc = scene(1.5)
    d = sc.kernels.directory
    bad = [lambda: os.chmod(d, 0o777),                           # the entry directory
           lambda: os.chmod(d / "kernels.py", 0o666),            # a source
           lambda: os.chmod(d / "__pycache__", 0o770)]           # numba's directory
    if ROOT_USER:
        bad.append(lambda: os.chown(d / "layout.json", OTHER_UID, OTHER_UID))
    for damage in bad:
        damage()
        assert not trusted(d, sc.key)
        ck = reload(sc)
        assert not ck.hit                                        # refused, generated again
        assert trusted(d, sc.key)
        assert all(m in (0o700, 0o600) for m in modes(d).values())
    assert reload(sc).hit
    assert_runs(sc, 1.5)


# ---------------------------------------------------------------------- trust
class _Plant:
    """A pickle that creates a file when it is unpickled."""

    def __init__(self, path):
        self.path = path

    def __reduce__(self):
        return (open, (self.path, "w"))


PLANTED = r"""
import json, math, sys
import sympy as sp, jetnh as jn
from jetnh.numeric import Scene
J = jn.JetSpace("x")
(x,), (xd,) = J.q, J.qd
k = sp.Symbol("k")
s = jn.System(J, xd**2 / 2 - k * x**2 / 2, [])
out = []
for kval in json.loads(sys.argv[1]):
    sc = Scene(s, "chetaev", params={k: kval}, initial=dict(x=1.0, x_t=0.0), t_span=(0, 1))
    tr = sc.run(save="final")
    out.append(dict(k=kval, hit=sc.kernels.hit, err=abs(tr["x"][-1] - math.cos(math.sqrt(kval)))))
print(json.dumps(out))
"""


def run_script(script, args, env, timeout=300):
    out = subprocess.run([sys.executable, "-c", script, *args], env=env, cwd=REPO,
                         capture_output=True, text=True, timeout=timeout)
    assert out.returncode == 0, out.stderr[-3000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_planted_code_and_pickles_are_never_run(fresh, tmp_path):
    """Code appended to kernels.py or __init__.py, and a pickle put in numba's index, in
    real entries: a fresh process refuses them, runs nothing, and rebuilds the entries."""
    ks = [2.25, 2.5, 2.75]
    entries = {kval: (scene(kval).kernels.directory, scene(kval).key) for kval in ks}
    canary = {kval: tmp_path / f"canary{i}" for i, kval in enumerate(ks)}
    code = "\nopen({!r}, 'w').close()\n"
    d, _ = entries[ks[0]]
    with open(d / "kernels.py", "a") as f:
        f.write(code.format(str(canary[ks[0]])))
    d, _ = entries[ks[1]]
    with open(d / "__init__.py", "a") as f:
        f.write(code.format(str(canary[ks[1]])))
    d, _ = entries[ks[2]]
    indexes = list((d / "__pycache__").glob("*.nbi"))
    assert indexes
    for path in indexes:
        path.write_bytes(pickle.dumps(_Plant(str(canary[ks[2]]))))
    # the pickle does what it should if anyone loads it
    probe = tmp_path / "probe"
    pickle.loads(pickle.dumps(_Plant(str(probe))))
    assert probe.exists()

    results = run_script(PLANTED, [json.dumps(ks)], dict(os.environ, JETNH_CACHE=str(fresh)))
    assert [p.name for p in canary.values() if p.exists()] == []
    for r in results:
        assert not r["hit"] and r["err"] < 1e-6, r
    for kval in ks:
        assert trusted(*entries[kval])


def test_forged_manifest_is_refused(fresh, tmp_path):
    """A manifest edited to match planted code (without the user's key) is refused."""
    sc = scene(3.25)
    d = sc.kernels.directory
    canary = tmp_path / "canary"
    src = (d / "kernels.py").read_bytes() + f"\nopen({str(canary)!r}, 'w').close()\n".encode()
    (d / "kernels.py").write_bytes(src)
    doc = json.loads((d / "manifest.json").read_text())
    doc["body"]["files"]["kernels.py"] = hashlib.sha256(src).hexdigest()
    (d / "manifest.json").write_text(json.dumps(doc))
    assert not reload(sc).hit
    assert not canary.exists()
    # a manifest signed with another key
    (d / "kernels.py").write_bytes(src)
    (cache.cache_root() / "hmac.key").write_bytes(os.urandom(32))
    assert not reload(sc).hit
    assert not canary.exists()
    assert_runs(sc, 3.25)


# ---------------------------------------------------------------------- repair
def test_damaged_entries_repair_themselves(fresh):
    sc = scene(3.5)
    d = sc.kernels.directory
    source = (d / "kernels.py").read_text()

    def corrupt_index():
        for p in (d / "__pycache__").glob("*.nbi"):
            p.write_bytes(b"\x80\x04garbage")

    def truncate():
        with open(d / "kernels.py", "r+") as f:
            f.truncate(100)

    damages = [corrupt_index, lambda: next((d / "__pycache__").glob("*.nbc")).unlink(),
               truncate,
               lambda: (d / "layout.json").write_text("{not json"),
               lambda: (d / "manifest.json").unlink(),
               lambda: (d / "manifest.json").write_text("[]"),
               lambda: (d / "__pycache__" / "stray.nbc").write_bytes(b"x"),
               lambda: (d / "__pycache__" / "kernels.cpython-311.pyc").write_bytes(b"x"),
               lambda: shutil.rmtree(d / "__pycache__")]
    for i, damage in enumerate(damages):
        damage()
        ck = reload(sc, forget=True)
        assert not ck.hit, i
        assert trusted(d, sc.key)
        assert (d / "kernels.py").read_text() == source
        assert ck.layout == Layout.from_json((d / "layout.json").read_text())
        assert list((d / "__pycache__").glob("*.nbi"))
        assert reload(sc, forget=True).hit
    assert_runs(sc, 3.5)


# ---------------------------------------------------------------------- concurrency
CONCURRENT = r"""
import json, math, os, sys, time
import sympy as sp, jetnh as jn
from jetnh.numeric import Scene, codegen
barrier, me = sys.argv[1], sys.argv[2]
generate = codegen.generate

def slow_generate(*a, **k):
    # both processes have derived the scene before either writes: a real race
    ks = generate(*a, **k)
    open(os.path.join(barrier, me), "w").close()
    t0 = time.time()
    while len(os.listdir(barrier)) < 2 and time.time() - t0 < 60:
        time.sleep(0.01)
    return ks

codegen.generate = slow_generate
J = jn.JetSpace("x")
(x,), (xd,) = J.q, J.qd
k = sp.Symbol("k")
s = jn.System(J, xd**2 / 2 - k * x**2 / 2, [])
sc = Scene(s, "chetaev", params={k: 3.75}, initial=dict(x=1.0, x_t=0.0), t_span=(0, 1))
tr = sc.run(save="final")
print(json.dumps(dict(hit=sc.kernels.hit, err=abs(tr["x"][-1] - math.cos(math.sqrt(3.75))))))
"""


def test_two_processes_compile_one_new_scene(fresh, tmp_path):
    barrier = tmp_path / "barrier"
    barrier.mkdir()
    env = dict(os.environ, JETNH_CACHE=str(fresh))
    procs = [subprocess.Popen([sys.executable, "-c", CONCURRENT, str(barrier), str(i)],
                              env=env, cwd=REPO, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for i in range(2)]
    for p in procs:
        out, err = p.communicate(timeout=300)
        assert p.returncode == 0, err[-3000:]
        r = json.loads(out.strip().splitlines()[-1])
        assert not r["hit"] and r["err"] < 1e-6
    root = cache.cache_root()
    entries = [p for p in root.iterdir() if p.is_dir() and p.name != "loops"]
    assert len(entries) == 1 and entries[0].name.startswith("k")   # no staging left over
    assert (root / "loops").is_dir()                # the integrator loop, signed beside
    sc = scene(3.75)
    assert trusted(entries[0], sc.key)
    assert reload(sc).hit


# ---------------------------------------------------------------------- deletion
def test_cache_deleted_while_compiling(fresh, monkeypatch):
    """The cache removed while numba compiles the kernels (the source file gone), and
    removed again before the generated source is returned: the run goes on, and the
    entry is written again."""
    sc = scene(4.25)
    real_cfunc = numba.cfunc
    state = {"deleted": 0}

    def cfunc(*args, **kw):
        if not state["deleted"]:
            state["deleted"] = 1
            shutil.rmtree(fresh)
        return real_cfunc(*args, **kw)

    monkeypatch.setattr(numba, "cfunc", cfunc)
    ck = sc.kernels
    monkeypatch.setattr(numba, "cfunc", real_cfunc)
    assert state["deleted"] and not ck.hit
    assert_runs(sc, 4.25)
    assert trusted(ck.directory, sc.key)

    generate = codegen.generate

    def deleting_generate(*args, **kw):
        ks = generate(*args, **kw)
        shutil.rmtree(fresh)
        return ks

    shutil.rmtree(fresh)
    monkeypatch.setattr(codegen, "generate", deleting_generate)
    ck = reload(sc)
    monkeypatch.setattr(codegen, "generate", generate)
    assert not ck.hit and trusted(ck.directory, sc.key)
    assert reload(sc).hit
    assert_runs(sc, 4.25)


# ---------------------------------------------------------------------- unusable root
def _unusable_roots(tmp_path):
    """(name, JETNH_CACHE, words of the warning) of roots that cannot be used."""
    out = []
    f = tmp_path / "a_file"
    f.write_text("not a directory")
    out.append(("file", f, "cannot be created"))
    other = tmp_path / "other"
    other.mkdir()
    if ROOT_USER:
        os.chown(other, OTHER_UID, OTHER_UID)
        out.append(("owner", other, "belongs to user"))
    else:
        os.chmod(other, 0o500)
        out.append(("read-only", other, "cannot be created"))
    shared = tmp_path / "shared"
    shared.mkdir()
    os.chmod(shared, 0o777)
    out.append(("world-writable", shared, "writable by group or others"))
    return out


def test_unusable_root_warns_once_and_uses_a_temporary_cache(fresh, tmp_path, monkeypatch):
    sc = scene(4.5)
    for name, path, words in _unusable_roots(tmp_path):
        monkeypatch.setenv("JETNH_CACHE", str(path))
        cache._WARNED.clear()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            ck = reload(sc)
            assert_runs(sc, 4.5)
            reload(sc)
            scene(4.5).kernels
        ours = [w for w in caught if issubclass(w.category, KernelCacheWarning)]
        assert len(ours) == 1, (name, [str(w.message) for w in caught])
        assert words in str(ours[0].message) and "JETNH_CACHE" in str(ours[0].message), name
        assert ck.directory.parent == cache.temp_root(), name
        assert stat.S_IMODE(os.stat(cache.temp_root()).st_mode) == 0o700
    for name in ("shared", "other"):
        os.chmod(tmp_path / name, 0o700)


def test_loose_version_directory_is_made_private(fresh):
    """The version directory is jetnh's own: open to others, it is made 0700 again."""
    root = cache.cache_root()
    root.mkdir(parents=True)
    os.chmod(root, 0o777)
    sc = scene(4.5)
    reload(sc)
    assert stat.S_IMODE(os.stat(root).st_mode) == 0o700
    assert sc.kernels.directory.parent == root


def test_hit_overhead_is_small(fresh):
    """Verifying an entry (hashing every file, the MAC) costs little next to loading it."""
    sc = scene(4.5)
    d = sc.kernels.directory
    key = sc.key
    secret = cache.secret_key(d.parent)
    t0 = time.perf_counter()
    for _ in range(20):
        assert cache.verify(d, key, secret) is not None
    per = (time.perf_counter() - t0) / 20
    assert per < 0.05


# ---------------------------------------------------------------------- location
def test_default_root_is_the_platform_cache_dir(tmp_path, monkeypatch):
    """Without JETNH_CACHE (unset or empty) the root is under the user cache dir, which
    honours XDG_CACHE_HOME on Linux; that parent is jetnh's and is made private."""
    xdg = tmp_path / "xdg"
    monkeypatch.setenv("XDG_CACHE_HOME", str(xdg))
    monkeypatch.setattr(cache, "_WARNED", set())
    for unset in (lambda: monkeypatch.delenv("JETNH_CACHE", raising=False),
                  lambda: monkeypatch.setenv("JETNH_CACHE", "")):
        unset()
        root = cache.cache_root()
        if sys.platform.startswith("linux"):
            assert root.parent == xdg / "jetnh"
        assert cache._env_base() is None
    if sys.platform.startswith("linux"):
        (xdg / "jetnh").mkdir(parents=True)
        os.chmod(xdg / "jetnh", 0o777)
        cache._prepare_root(root)        # our own default dir: made private, not refused
        assert stat.S_IMODE(os.stat(xdg / "jetnh").st_mode) == 0o700
    monkeypatch.setenv("JETNH_CACHE", str(tmp_path / "mine"))
    assert cache.cache_root().parent == tmp_path / "mine"


def test_info_and_clear(fresh):
    """info() counts the entries and their bytes; clear() removes them and older roots."""
    i = cache.info()
    assert i["entries"] == 0 and i["fallback"] is None and i["env"]
    reload(scene(4.5))
    old = fresh / "v0"                  # an older jetnh's root: it holds the marker
    old.mkdir()
    (old / "x").write_bytes(b"12345")
    (old / cache.MARKER).write_bytes(b"")
    mine = fresh / "v1"                 # the user's own directory of that name: no marker
    (mine / "k1").mkdir(parents=True)
    (mine / "thesis.tex").write_bytes(b"irreplaceable")
    i = cache.info()
    assert i["root"] == cache.cache_root() and i["entries"] == 1 and i["bytes"] > 0
    assert i["old_versions"] == 5
    assert cache.owned(cache.cache_root())
    assert loader.clear() == 1
    assert not cache.cache_root().exists() and not old.exists()
    assert (mine / "thesis.tex").read_bytes() == b"irreplaceable" and (mine / "k1").is_dir()
    assert cache.info()["entries"] == 0


def test_clear_never_deletes_what_jetnh_did_not_make(fresh):
    """JETNH_CACHE=$HOME with the user's own v1, v2024 and a current-version directory
    jetnh did not make (no marker), a link to elsewhere: clear deletes none of them."""
    root = cache.cache_root()
    dirs = [fresh / "v1", fresh / "v2024", root]
    for d in dirs:
        (d / "k0").mkdir(parents=True)
        (d / "k0" / "data").write_bytes(b"user data")
    elsewhere = fresh.parent / "elsewhere"
    (elsewhere / "k0").mkdir(parents=True)
    os.symlink(elsewhere, fresh / "v3")
    (elsewhere / cache.MARKER).write_bytes(b"")
    assert loader.clear() == 0
    for d in dirs:
        assert (d / "k0" / "data").read_bytes() == b"user data"
    assert (elsewhere / "k0").is_dir() and os.path.islink(fresh / "v3")


def test_info_names_why_the_fallback_is_used(fresh, tmp_path, monkeypatch):
    shared = tmp_path / "shared"
    shared.mkdir()
    os.chmod(shared, 0o777)
    monkeypatch.setenv("JETNH_CACHE", str(shared))
    assert "writable by group or others" in cache.info()["fallback"]


# ---------------------------------------------------------------------- numba's own cache
NUMBA_DIR = r"""
import json, sys, warnings
sys.path.insert(0, sys.argv[1])
import sympy as sp, jetnh as jn
from jetnh.numeric import Scene
J = jn.JetSpace("x")
(x,), (xd,) = J.q, J.qd
k = sp.Symbol("k")
s = jn.System(J, xd**2 / 2 - k * x**2 / 2, [])
with warnings.catch_warnings(record=True) as w:
    warnings.simplefilter("always")
    sc = Scene(s, "chetaev", params={k: 2.5}, initial=dict(x=1.0, x_t=0.0), t_span=(0, 1))
    ck = sc.kernels
    x1 = float(sc.run(save="final")["x"][-1])
print(json.dumps(dict(hit=ck.hit, code_hits=ck.rhs_c.cache_hits, x1=x1,
                      warned=[str(m.message) for m in w
                              if m.category.__name__ == "KernelCacheWarning"])))
"""


@pytest.mark.parametrize("redirect", [False, True])
def test_numba_reads_kernel_machine_code_only_from_the_checked_entry(tmp_path, redirect):
    """By default numba caches a kernel module beside it, in its entry (which the manifest
    covers): a second process loads that machine code.  With NUMBA_CACHE_DIR set, numba
    would read it from where jetnh checks nothing: the kernels are compiled in each
    process instead, nothing of theirs is written there, and a warning says so."""
    elsewhere = tmp_path / "numba"
    env = dict(os.environ, JETNH_CACHE=str(tmp_path / "cache"))
    env.pop("NUMBA_CACHE_DIR", None)
    env.pop("NUMBA_CACHE_LOCATOR_CLASSES", None)
    if redirect:
        env["NUMBA_CACHE_DIR"] = str(elsewhere)

    def run():
        out = subprocess.run([sys.executable, "-c", NUMBA_DIR, str(REPO)], env=env,
                             capture_output=True, text=True, timeout=600)
        assert out.returncode == 0, out.stderr[-3000:]
        return json.loads(out.stdout.strip().splitlines()[-1])

    cold, warm = run(), run()
    assert not cold["hit"] and warm["hit"]               # derivation and code: cached
    assert abs(warm["x1"] - math.cos(math.sqrt(2.5))) < 1e-6 and warm["x1"] == cold["x1"]
    entry = next((tmp_path / "cache").glob("v*/k*"))
    pycache = sorted(p.name for p in (entry / "__pycache__").iterdir())
    listed = json.loads((entry / "manifest.json").read_text())["body"]["files"]
    assert all(f"__pycache__/{name}" in listed for name in pycache)
    # the integrator loop is in the signed store either way (kernels.loop_cache), never
    # where NUMBA_CACHE_DIR points
    assert list((tmp_path / "cache").glob("v*/loops/loop._solve_dop853_*.nbc"))
    assert not any("_solve" in p.name for p in elsewhere.rglob("*"))
    if redirect:
        assert warm["code_hits"] == 0 and warm["warned"] and cold["warned"]
        assert "NUMBA_CACHE_DIR" in warm["warned"][0]
        assert not pycache                                # nothing cached at all
        # no machine code of a generated module (kernels.py) went there
        assert not any(p.name.startswith("kernels.") for p in elsewhere.rglob("*"))
    else:
        assert warm["code_hits"] >= 1 and not warm["warned"]
        assert any(name.endswith(".nbc") for name in pycache)
