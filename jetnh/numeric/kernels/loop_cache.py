"""jetnh's own compiled functions on disk: numba's cache format, kept in the private
store of the kernels (``store``) and read only after its signature is checked.

The integrator loops (``methods._common.compiled``), the trampolines that call a kernel
from Python (``calls``) and the no-op event callback of the discrete methods
(``discrete``) do not depend on the scene, so each is compiled once and kept in
``<root>/loops/`` (``store.cache_root()``, the root of the kernel entries, or the private
temporary root when that cannot be used; ``signed_njit`` and ``signed_cfunc`` compile a
function so)::

    <root>/loops/<module>.<loop>-<line>.py<XY>.nbi       numba's index of the loop
    <root>/loops/<module>.<loop>-<line>.py<XY>.<k>.nbc   its compiled code (one a CPU)

Each file is numba's bytes preceded by an HMAC-SHA256 of its name and those bytes under
this user's secret key (``store.secret_key``, the key that signs the kernel entries).

Threat model
------------
numba's cache files are pickles, and a pickle runs code when it is loaded; the ``.nbc``
files hold machine code that is then run.  numba itself reads them from
``NUMBA_CACHE_DIR`` (when set), from ``__pycache__`` beside the source or from the user's
numba cache, without checking who wrote them: anyone who can write one of those places
(a ``NUMBA_CACHE_DIR`` shared between users, a copied cache) could run code as the
user.  So the loops never use numba's locators: whatever ``NUMBA_CACHE_DIR`` or
``NUMBA_CACHE_LOCATOR_CLASSES`` say, they are read from and written to ``<root>/loops``
only, a directory of the user's that group and others cannot write, through the store's
file checks (a regular file of the user that others cannot write, no link followed);
the bytes are read once, their MAC checked, and only then unpickled (nothing is read
again between the check and the use).  A file that fails a check is removed and the loop
compiled anew; nothing of it is executed.  The MAC covers the file's name, so signed
files cannot be swapped for one another; the name carries the hash of the integrator
sources (``methods._common.sources_hash``) and numba checks its version and the CPU in
the index, so a file of other sources, another numba or another CPU is not used.

Not covered: whoever can write the user's files (the key, jetnh's sources, the Python
environment) runs code as the user anyway; the key is only as secret as the user's
account.
"""

from __future__ import annotations

import hashlib
import hmac
import inspect
import io
import os
import pickle
import sys
from pathlib import Path

import numba
from numba.core.caching import (
    CompileResultCacheImpl, FunctionCache, IndexDataCacheFile, NullCache, _CacheLocator)

from . import store

LOOPS = "loops"
#: what the MAC of a file says it is (a MAC of a kernel manifest is never a loop's)
_DOMAIN = b"jetnh loop cache 1\0"
_MAC_SIZE = hashlib.sha256().digest_size


def _mac(secret: bytes, name: str, payload: bytes) -> bytes:
    return hmac.new(secret, _DOMAIN + name.encode() + b"\0" + payload, hashlib.sha256).digest()


class _Locator(_CacheLocator):
    """The loops' directory in the store (never numba's locators)."""

    def __init__(self, directory: Path, stamp: str, lineno: int, py_file: str):
        self._directory = directory
        self._stamp = stamp
        self._lineno = lineno
        self._py_file = py_file          # numba names the function's file in its warnings

    def ensure_cache_path(self):
        # numba calls this unguarded before saving: a store removed meanwhile (``jetnh
        # cache clear`` in another process) must not fail the run; the save is skipped
        try:
            _private_directory(self._directory)
        except (OSError, store.Untrusted):
            pass

    def get_cache_path(self):
        return str(self._directory)

    def get_source_stamp(self):
        return self._stamp

    def get_disambiguator(self):
        return str(self._lineno)


class _Impl(CompileResultCacheImpl):
    """numba's serialisation of a compiled function, located by ``_Locator``."""

    def __init__(self, py_func, locator: _Locator, name: str):   # no numba locator searched
        self._lineno = py_func.__code__.co_firstlineno
        self._locator = locator
        modname = os.path.splitext(os.path.basename(inspect.getfile(py_func)))[0]
        self._filename_base = self.get_filename_base(f"{modname}.{name}",
                                                     getattr(sys, "abiflags", ""))


class _SignedFile(IndexDataCacheFile):
    """numba's index and data files, each stored as ``MAC + bytes`` and read through the
    store's checks; a file that fails them is removed and counts as absent, one that
    cannot be read or written is left to the next process."""

    def __init__(self, directory: Path, filename_base: str, stamp: str, secret: bytes):
        super().__init__(str(directory), filename_base, stamp)
        self._secret = secret

    def _read(self, path: str) -> bytes | None:
        name = os.path.basename(path)
        try:
            data, _st = store._read_private(path)
        except store.Untrusted:
            store.discard(Path(path))
            return None
        except OSError:                     # absent, or unreadable: compiled anew
            return None
        mac, payload = data[:_MAC_SIZE], data[_MAC_SIZE:]
        if not hmac.compare_digest(mac, _mac(self._secret, name, payload)):
            store.discard(Path(path))
            return None
        return payload

    def _write(self, path: str, payload: bytes):
        """Signed and written atomically; if it cannot be written (the cache removed
        meanwhile, a full disk), the loop stays in this process's memory only."""
        name = os.path.basename(path)
        try:
            store._replace_private(Path(path), _mac(self._secret, name, payload) + payload)
        except OSError:
            pass

    def save(self, key, data):
        # the data file carries its key (under the MAC): an index that points a key at a
        # file holding another key's code (two processes that picked the same new name,
        # e.g. two hosts sharing one store) is not believed
        super().save(key, (key, data))

    def load(self, key):
        found = super().load(key)
        if not (isinstance(found, tuple) and len(found) == 2 and found[0] == key):
            return None
        return found[1]

    def _load_index(self):
        payload = self._read(self._index_path)
        if payload is None:
            return {}
        stream = io.BytesIO(payload)
        version = pickle.load(stream)       # signed by this user's jetnh: safe to unpickle
        if version != self._version:
            return {}
        stamp, overloads = pickle.loads(stream.read())
        return overloads if stamp == self._source_stamp else {}

    def _save_index(self, overloads):
        self._write(self._index_path, pickle.dumps(self._version, protocol=-1)
                    + self._dump((self._source_stamp, overloads)))

    def _load_data(self, name):
        payload = self._read(self._data_path(name))
        if payload is None:
            raise FileNotFoundError(name)   # numba's ``load``: no entry
        return pickle.loads(payload)

    def _save_data(self, name, data):
        self._write(self._data_path(name), self._dump(data))


class SignedFunctionCache(FunctionCache):
    """numba's ``FunctionCache`` of ``py_func`` in ``directory``, its files signed with
    ``secret`` (``_SignedFile``); ``stamp`` says which sources it was compiled from;
    ``name`` names its files (default: the function's qualified name)."""

    def __init__(self, py_func, directory: Path, secret: bytes, stamp: str,
                 name: str | None = None):
        self._name = repr(py_func)
        self._py_func = py_func
        locator = _Locator(directory, stamp, py_func.__code__.co_firstlineno,
                           inspect.getfile(py_func))
        self._impl = _Impl(py_func, locator, name or py_func.__qualname__)
        self._cache_path = locator.get_cache_path()
        self._cache_file = _SignedFile(directory, self._impl.filename_base, stamp, secret)
        self.enable()


def _private_directory(path: Path):
    """``path`` made (0700) if missing; one that is not a directory of the user that
    group and others cannot write (a link is not one) is removed and made again
    (``store.Untrusted`` if that fails)."""
    for attempt in range(2):
        try:
            store._mkdir_private(path)
        except FileExistsError:
            pass
        try:
            store._check_stat(os.lstat(path), path, want_dir=True)
            return
        except store.Untrusted:
            if attempt:
                raise
            store.discard(path)


def cache_for(py_func, stamp: str, name: str | None = None):
    """The disk cache of a loop: a ``SignedFunctionCache`` in ``<root>/loops`` of the
    store (``store.open_root``: the persistent root, else the private temporary one), or
    numba's ``NullCache`` (compiled in this process only) if no directory can be used."""
    for persistent in (True, False):
        try:
            root, secret = store.open_root(persistent)
            directory = root / LOOPS
            _private_directory(directory)
        except (OSError, store.Untrusted):
            continue
        store.remove_stale(directory)
        return SignedFunctionCache(py_func, directory, secret, stamp, name)
    return NullCache()


def file_stamp(path) -> str:
    """A hash of the file ``path``: the stamp of what a function compiled from it and the
    helpers of the same file is made of."""
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()[:16]


def signed_njit(py_func, signature, stamp: str, **options):
    """``numba.njit(signature, **options)(py_func)`` with its machine code in the signed
    store (``cache_for``; its files named with ``stamp``, so that other sources never
    share them) instead of numba's cache; compiled for ``signature`` only."""
    dispatcher = numba.njit(**options)(py_func)
    dispatcher._cache = cache_for(py_func, stamp, f"{py_func.__qualname__}_{stamp}")
    dispatcher.compile(signature)
    dispatcher.disable_compile()
    return dispatcher


def signed_cfunc(py_func, signature, stamp: str, **options):
    """``numba.cfunc(signature, **options)(py_func)`` with its machine code in the signed
    store (as ``signed_njit``): numba's ``CFunc`` loads and saves through its ``_cache``
    like a dispatcher."""
    from numba.core import sigutils
    from numba.core.ccallback import CFunc

    callback = CFunc(py_func, sigutils.normalize_signature(signature), locals={},
                     options=options)
    callback._cache = cache_for(py_func, stamp, f"{py_func.__qualname__}_{stamp}")
    callback.compile()
    return callback
