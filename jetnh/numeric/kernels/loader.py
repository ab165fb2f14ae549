"""Loading kernels: from this process's memory, from a verified entry of the store
(``store``), or generated, compiled, sealed and stored.

``load(key, make_source)`` is the one way in.  The module of an entry is compiled from the
very bytes the store verified, as the file they came from (numba's default locator then
caches its machine code in the entry, where the next verification covers it); the
import system, and so any ``.pyc``, is not used.
"""

from __future__ import annotations

import hashlib
import shutil
import sys
import tempfile
import threading
import time
import types
import warnings
from pathlib import Path

from ...errors import KernelCacheWarning
from ..layout import Layout
from . import store
from .compiled import CompiledKernels

_LOADED: dict[tuple[str, bool], CompiledKernels] = {}
_LOCK = threading.Lock()            # guards _LOADED and _KEY_LOCKS
_EXEC_LOCK = threading.RLock()      # one kernel module compiled at a time
_KEY_LOCKS: dict[tuple[str, bool], threading.Lock] = {}
_WARNED: set = set()


def clear(root: Path | None = None) -> int:
    """``store.clear``, and the kernels this process loaded from the persistent store are
    forgotten; returns how many entries there were."""
    n = store.clear(root)
    for k in [k for k in _LOADED if k[1]]:
        del _LOADED[k]
    return n


def _numba_caches_in_tree(directory: Path) -> str | None:
    """``None`` if numba caches the functions of ``<directory>/kernels.py`` in
    ``<directory>/__pycache__`` (its default, ``numba.core.caching.InTreeCacheLocator``):
    then the only machine code numba may read for kernels is the entry's, which the
    manifest has just checked.  Else why not: ``NUMBA_CACHE_DIR`` or
    ``NUMBA_CACHE_LOCATOR_CLASSES`` send it elsewhere, or ``__pycache__`` cannot be made
    or written there (a full disk, a read-only file system), and numba would fall back to
    its user-wide cache; jetnh checks nothing in either place."""
    from numba.core import caching, config

    if getattr(config, "CACHE_DIR", "") or getattr(config, "CACHE_LOCATOR_CLASSES", ""):
        return ("NUMBA_CACHE_DIR (or NUMBA_CACHE_LOCATOR_CLASSES) is set, so numba would "
                "keep the machine code of jetnh's kernels where jetnh cannot check it")
    if caching.InTreeCacheLocator.from_function(_forget, str(directory / "kernels.py")) \
            is None:                # numba's own test of the place, as it will make it
        return (f"numba cannot write {directory / '__pycache__'}, so it would keep the "
                "machine code of jetnh's kernels in its user-wide cache, where jetnh "
                "cannot check it")
    return None


def _forget(package: str):
    for name in (f"{package}.kernels", package):
        sys.modules.pop(name, None)


def _exec_kernels(package: str, directory: Path, source: bytes):
    """The module ``<package>.kernels`` compiled from ``source`` (bytes already checked)
    as ``<directory>/kernels.py``, the file those bytes came from (numba's default
    locator caches next to it: in the entry).  If numba would cache elsewhere
    (``_numba_caches_in_tree``), the kernels are compiled without it (``JETNH_NUMBA_CACHE``
    in the module's globals, read by the generated header), with a warning.  The module
    of the same source already in this process is reused."""
    digest = hashlib.sha256(source).digest()
    name = f"{package}.kernels"
    old = sys.modules.get(name)
    if old is not None and getattr(old, "__jetnh_sha256__", None) == digest:
        return old
    elsewhere = _numba_caches_in_tree(directory)
    in_tree = elsewhere is None
    configured = not in_tree and elsewhere.startswith("NUMBA")
    if not in_tree and ("numba", configured) not in _WARNED:
        _WARNED.add(("numba", configured))
        warnings.warn(
            f"jetnh: {elsewhere}; the kernels are compiled anew in each process (their "
            "derivation and code are still cached). "
            + ("Unset it to load compiled kernels from jetnh's cache." if configured else
               "Free space there, or set JETNH_CACHE to a writable directory of yours."),
            KernelCacheWarning, stacklevel=4)
    pkg = types.ModuleType(package, "jetnh generated kernel package")
    pkg.__path__ = [str(directory)]
    pkg.__file__ = str(directory / "__init__.py")
    pkg.__package__ = package
    mod = types.ModuleType(name)
    mod.__file__ = str(directory / "kernels.py")
    mod.__package__ = package
    mod.__jetnh_sha256__ = digest
    mod.JETNH_NUMBA_CACHE = in_tree
    code = compile(source, mod.__file__, "exec", dont_inherit=True)
    with _EXEC_LOCK:
        sys.modules[package] = pkg
        sys.modules[name] = mod
        try:
            exec(code, mod.__dict__)  # noqa: S102 - bytes checked against the manifest
        except BaseException:
            _forget(package)
            raise
    for value in list(vars(mod).values()):
        if hasattr(value, "disable_compile"):
            # compiled when the module ran (explicit signatures), and cached then, in the
            # directory that is then sealed: nothing compiles (nor writes) later
            value.disable_compile()
    pkg.kernels = mod
    return mod


def _load_entry(entry: Path, key: str, secret: bytes, package: str, persistent: bool):
    """The kernels of a trusted entry, or ``None`` (absent; or untrusted or damaged, and
    then removed)."""
    t0 = time.perf_counter()
    found = store.read(entry, key, secret)
    if found is None:
        return None
    contents, stamps, files = found
    t1 = time.perf_counter()
    try:
        layout = Layout.from_json(contents["layout.json"].decode("utf-8"))
        source = contents["kernels.py"]
        module = _exec_kernels(package, entry, source)
        ck = CompiledKernels(key, entry, layout, True, {"verify": t1 - t0}, persistent,
                             module=module, source=source.decode("utf-8"))
    except Exception:               # a damaged entry (it verified, yet does not load)
        _forget(package)
        store.discard(entry)
        return None
    if store.changed(entry, stamps):     # numba wrote machine code (e.g. another CPU): sign it
        try:
            store.seal(entry, key, secret, {n: files[n] for n in store.SOURCES})
        except (OSError, store.Untrusted):
            pass                    # left as is: the next load finds it untrusted
    return ck


def _build(ks, key: str, package: str, persistent: bool, root: Path, secret: bytes):
    """Write, compile, seal and publish a new entry; the kernels, in memory whatever
    happens to the cache meanwhile."""
    timings = dict(ks.timings)
    t0 = time.perf_counter()
    source = ks.source.encode("utf-8")
    layout = ks.layout.to_json().encode("utf-8")
    store.remove_stale(root)
    module, entry = None, root / f"k{key}"
    for attempt in range(2):
        tmp = None
        try:
            if attempt:             # the cache went away (or was damaged): again
                root, secret = store.open_root(persistent)
                entry = root / f"k{key}"
            tmp = store.stage(root, key, source, layout)
            if module is None:
                module = _exec_kernels(package, tmp, source)   # numba writes its cache
            store.seal(tmp, key, secret)
            if store.publish(tmp, entry, key, secret):
                break
        except (OSError, store.Untrusted):
            if tmp is not None:
                shutil.rmtree(tmp, ignore_errors=True)
        except Exception:
            if tmp is not None and not (tmp / "kernels.py").exists():
                continue            # removed while numba compiled (it caches beside it)
            if tmp is not None:     # the source does not compile: not the cache's doing
                shutil.rmtree(tmp, ignore_errors=True)
            raise
        except BaseException:
            if tmp is not None:
                shutil.rmtree(tmp, ignore_errors=True)
            raise
    if module is None:              # never compiled: in a private temporary directory
        tmp = Path(tempfile.mkdtemp(prefix=f".k{key}.", dir=store.temp_root()))
        store.write_private(tmp / "kernels.py", source)
        module = _exec_kernels(package, tmp, source)
    module.__file__ = str(entry / "kernels.py")
    timings["write"] = time.perf_counter() - t0
    return CompiledKernels(key, entry, ks.layout, False, timings, persistent, module=module,
                           source=ks.source)


def load(key: str, make_source, persistent: bool = True) -> CompiledKernels:
    """The kernels of ``key``: from memory, from a trusted entry on disk, or generated by
    ``make_source()`` (a callable returning a ``codegen.KernelSource``) and stored."""
    memo = (key, persistent)
    ck = _LOADED.get(memo)
    if ck is not None:
        return ck
    with _LOCK:
        lock = _KEY_LOCKS.setdefault(memo, threading.Lock())
    with lock:                      # one thread builds a key; others wait for it
        if memo in _LOADED:
            return _LOADED[memo]
        package = f"jetnh_kernels_{key}" + ("" if persistent else "_tmp")
        root, secret = store.open_root(persistent)
        ck = _load_entry(root / f"k{key}", key, secret, package, persistent)
        if ck is None:
            ks = make_source()
            root, secret = store.open_root(persistent)      # again: it may have gone meanwhile
            ck = _build(ks, key, package, persistent, root, secret)
        with _LOCK:
            _LOADED[memo] = ck
        return ck
