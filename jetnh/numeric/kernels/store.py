"""The disk store of generated kernels: private, verified before use, self-repairing.

This module knows files, keys and signatures only: it hands out the verified bytes of an
entry (``read``), and the loader (``loader``) compiles them.

Where it lives
--------------
The root is ``$JETNH_CACHE/v<codegen version>`` when ``JETNH_CACHE`` is set, else
``<user cache dir>/v<codegen version>`` (``cache_root()``), the user cache dir being where
the platform keeps caches (``platformdirs.user_cache_dir("jetnh")``: ``~/.cache/jetnh``
or ``$XDG_CACHE_HOME/jetnh`` on Linux, ``~/Library/Caches/jetnh`` on macOS).
``jetnh cache info`` and ``jetnh cache clear`` show and empty it (``info()``,
``clear()``).  ``Scene(..., cache=False)`` uses a private temporary directory removed at
exit.  Each scene's kernels are one *entry*, a
directory named by a hash of the symbolic input (``codegen.KernelSpec.key``)::

    <root>/hmac.key          32 random bytes, this user's secret (mode 0600)
    <root>/loops/            jetnh's own compiled functions (``loop_cache``): the
                             integrator loops, the trampolines of ``calls``; each file
                             signed with the same key
    <root>/k<key>/
        __init__.py          a comment: the entry is a package (never executed)
        kernels.py           rhs_c, aux_c, sing_c (numba cfuncs, cache=True); or the
                             user-event kernel ``events`` (its own key)
        layout.json          the state layout
        __pycache__/         numba's machine code of kernels.py (*.nbi, *.nbc)
        manifest.json        the sha256 of every other file, and an HMAC of that list

A second process that builds the same scene finds the entry, skips the derivation, ``cse``
and code generation, and numba loads the machine code instead of compiling.  The
integrators take ``rhs`` as a callback at its address (``methods._common.function_at``),
so their loops are compiled once for all scenes and kept in ``<root>/loops`` (``loop_cache``,
under the same trust rules; ``jetnh cache warm`` compiles them ahead); per scene only
``kernels.py`` is compiled.

Privacy
-------
Every directory jetnh creates here is made mode 0700 and every file 0600, whatever the
umask.  The root and its parent (``$JETNH_CACHE`` or the user cache dir) must be
directories of the user that group and others cannot write: the root, jetnh's own, is made
0700 again if it is not, and so is the default parent (the user cache dir); a
``$JETNH_CACHE`` that others can write is left alone and not used.  Inside the root, an
entry, file or directory that does not belong to the user, is writable by group or
others, or is a symbolic link, is not trusted.

Trust
-----
Nothing is read from an entry as code or as a pickle unless its bytes are proved to be
what this user's jetnh wrote.  When an entry is complete, jetnh writes ``manifest.json``:
the entry's key and the sha256 of each of its files, including numba's files in
``__pycache__``, signed with HMAC-SHA256 under the user's secret key ``hmac.key`` (made
once, atomically, from ``secrets``).  Before using an entry, jetnh checks the MAC, that
the entry holds exactly the files the manifest lists, and each file's hash.  ``kernels.py``
is then compiled from the very bytes that were hashed (the import system, and so any
``.pyc``, is not used), as the file they came from: numba's default cache locator keeps
the machine code of a module in ``<its directory>/__pycache__``, so the only machine code
numba may read for kernels is the entry's, which has just been checked.  The entry's key
carries what the kernels depend on (the symbolic input, the sources of the derivation and
of the code generator, the versions of sympy and numba).  When ``NUMBA_CACHE_DIR`` or
``NUMBA_CACHE_LOCATOR_CLASSES`` send numba's cache elsewhere, kernels are compiled in
every process instead (a ``KernelCacheWarning`` says so).  If numba adds machine code to
an entry (e.g. for another CPU), jetnh signs the new list after loading.

Repair
------
An entry that fails any check (a bad or missing manifest, a truncated or edited file, an
extra file, a corrupt numba index, wrong owner or permissions) or that fails to load is
removed and generated again, once, from the symbolic input; nothing is executed from it.

Writing
-------
A new entry is written and compiled in a private temporary directory next to its place
(``<root>/.k<key>.*``), sealed with its manifest, and renamed into place as a whole: a
reader never sees half an entry, and of two processes compiling the same new scene, the
first rename wins and the other keeps its own kernels in memory and discards its copy.
If the cache is deleted while a scene compiles, the root is made again and the run goes
on (the kernels are in memory; the entry is written again when possible).

If the root cannot be used (it cannot be created or written, is not a directory, belongs
to another user, or is open to others and cannot be made private), jetnh warns once
(``errors.KernelCacheWarning``, naming the problem and the fix) and uses a private
temporary cache for the rest of the process; it never fails for that.
"""

from __future__ import annotations

import atexit
import errno
import hashlib
import hmac
import json
import os
import secrets
import shutil
import stat
import tempfile
import time
import warnings
from pathlib import Path

from ...errors import KernelCacheWarning
from ..layout import CODEGEN_VERSION

_TEMP_ROOT: Path | None = None
_WARNED: set[str] = set()

MANIFEST = "manifest.json"
KEY_FILE = "hmac.key"
#: the file jetnh writes into every cache root it creates: ``clear`` removes a root only
#: when it holds it (a user's own ``~/v1`` under ``JETNH_CACHE=$HOME`` is never touched)
MARKER = ".jetnh-kernel-cache"
PYCACHE = "__pycache__"
SOURCES = ("__init__.py", "kernels.py", "layout.json")
INIT_TEXT = b"# jetnh generated kernel package\n"
MANIFEST_FORMAT = 1
STALE_SECONDS = 3600.0          # a staging directory older than this is left over: removed

_O_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_O_CLOEXEC = getattr(os, "O_CLOEXEC", 0)


class Untrusted(Exception):
    """An entry (or file) that must not be used; the message says why."""


class _Unusable(Exception):
    """The cache root cannot be used: ``(problem, fix)``."""


def _user_cache_dir() -> Path:
    """jetnh's directory among the platform's caches (``platformdirs``)."""
    import platformdirs

    return Path(platformdirs.user_cache_dir("jetnh", appauthor=False))


def _env_base() -> Path | None:
    """``$JETNH_CACHE`` when set (and not empty), else None."""
    env = os.environ.get("JETNH_CACHE")
    return Path(env).expanduser() if env else None


def cache_root() -> Path:
    """Where persistent kernels go: ``$JETNH_CACHE/v<N>`` or ``<user cache dir>/v<N>``."""
    base = _env_base() or _user_cache_dir()
    return base / f"v{CODEGEN_VERSION}"


def _entries(root: Path) -> list[Path]:
    """The entries under ``root`` (``k<key>`` directories, not links)."""
    try:
        names = os.listdir(root)
    except OSError:
        return []
    return [root / n for n in names
            if n.startswith("k") and os.path.isdir(root / n) and not os.path.islink(root / n)]


def _size(path: Path) -> int:
    """Bytes of the files under ``path`` (links are not followed)."""
    total = 0
    for dirpath, _dirs, files in os.walk(path):
        for f in files:
            try:
                total += os.lstat(os.path.join(dirpath, f)).st_size
            except OSError:
                pass
    return total


def _old_versions(root: Path) -> list[Path]:
    """Roots of other codegen versions next to ``root`` (left by older jetnh)."""
    try:
        names = os.listdir(root.parent)
    except OSError:
        return []
    return [root.parent / n for n in names
            if n != root.name and n[:1] == "v" and n[1:].isdigit()
            and os.path.isdir(root.parent / n) and not os.path.islink(root.parent / n)
            and owned(root.parent / n)]


def owned(root: Path) -> bool:
    """Whether jetnh provably made ``root``: it holds jetnh's marker file (a regular file,
    not a link)."""
    try:
        return stat.S_ISREG(os.lstat(Path(root) / MARKER).st_mode)
    except OSError:
        return False


def info() -> dict:
    """The persistent cache: ``root``, ``entries``, ``bytes``, ``old_versions`` (their
    bytes), ``env`` (``JETNH_CACHE`` set) and ``fallback`` (None, or why a run would use a
    private temporary cache instead, and the fix)."""
    root = cache_root()
    try:
        _prepare_root(root)
        fallback = None
    except _Unusable as exc:
        fallback = "{}; to keep kernels between runs, {}".format(*exc.args)
    old = _old_versions(root)
    return {"root": root, "entries": len(_entries(root)),
            "bytes": _size(root) if root.is_dir() else 0,
            "old_versions": sum(_size(p) for p in old), "env": _env_base() is not None,
            "fallback": fallback}


def clear(root: Path | None = None) -> int:
    """Remove every cached kernel under ``root`` (default: the persistent cache, and the
    roots older jetnh versions left next to it); returns how many entries there were.
    Only directories holding jetnh's ``MARKER`` (written when jetnh made them) are
    removed; anything else, a link included, is left alone."""
    targets = [root] if root else [cache_root(), *_old_versions(cache_root())]
    n = 0
    for r in targets:
        if os.path.islink(r) or not owned(r):
            continue                    # not provably jetnh's: never deleted
        n += len(_entries(r))
        shutil.rmtree(r)
    return n


# ---------------------------------------------------------------------- private files
def _uid() -> int:
    return os.geteuid()


def _check_stat(st, path, want_dir: bool, secret: bool = False):
    """Raise ``Untrusted`` unless ``st`` is a regular file (a directory if ``want_dir``)
    of this user that group and others cannot write (nor read, for a ``secret``)."""
    kind = stat.S_ISDIR(st.st_mode) if want_dir else stat.S_ISREG(st.st_mode)
    if not kind:
        raise Untrusted(f"{path} is not a {'directory' if want_dir else 'regular file'}")
    if st.st_uid != _uid():
        raise Untrusted(f"{path} belongs to user {st.st_uid}, not {_uid()}")
    if st.st_mode & (0o077 if secret else 0o022):
        raise Untrusted(f"{path} has mode {stat.S_IMODE(st.st_mode):o}")


def _mkdir_private(path):
    """``mkdir`` with mode 0700 whatever the umask (``FileExistsError`` if there)."""
    os.mkdir(path, 0o700)
    os.chmod(path, 0o700)


def _makedirs_private(path):
    """``path`` and its missing parents, each made with mode 0700."""
    path = os.path.abspath(path)
    missing = []
    while not os.path.lexists(path):
        missing.append(path)
        parent = os.path.dirname(path)
        if parent == path:
            break
        path = parent
    for p in reversed(missing):
        try:
            _mkdir_private(p)
        except FileExistsError:
            pass


def write_private(path, data: bytes):
    """A new file of mode 0600 (fails if ``path`` exists; never follows a link)."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _O_NOFOLLOW | _O_CLOEXEC,
                 0o600)
    try:
        os.fchmod(fd, 0o600)
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view):]
    finally:
        os.close(fd)


def _replace_private(path: Path, data: bytes):
    """Atomic write of a 0600 file: readers see the old or the new file, never half."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
    write_private(tmp, data)
    try:
        os.replace(tmp, path)
    except OSError:
        _unlink(tmp)
        raise


def _read_private(path, secret: bool = False) -> tuple[bytes, os.stat_result]:
    """The bytes of a regular file of this user that others cannot write (``Untrusted``
    otherwise; ``FileNotFoundError`` if absent); links are not followed."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | _O_NOFOLLOW | _O_CLOEXEC)
    except FileNotFoundError:
        raise
    except OSError as exc:          # ELOOP: a symbolic link; EACCES; ...
        raise Untrusted(f"{path} cannot be opened ({exc.strerror})") from None
    try:
        st = os.fstat(fd)
        _check_stat(st, path, want_dir=False, secret=secret)
        chunks = []
        while True:
            chunk = os.read(fd, 1 << 20)
            if not chunk:
                break
            chunks.append(chunk)
        return b"".join(chunks), st
    finally:
        os.close(fd)


def _unlink(path):
    try:
        os.unlink(path)
    except OSError:
        pass


def discard(path: Path):
    """Remove an untrusted or damaged entry (or whatever is at its place): moved aside
    first, so a concurrent reader never sees it half removed, then deleted."""
    try:
        st = os.lstat(path)
    except OSError:
        return
    if not stat.S_ISDIR(st.st_mode):
        _unlink(path)
        return
    trash = path.with_name(f".trash-{path.name}.{os.getpid()}.{secrets.token_hex(4)}")
    try:
        os.rename(path, trash)
    except OSError:
        trash = path
    shutil.rmtree(trash, ignore_errors=True)


# ---------------------------------------------------------------------- the root
def _prepare_root(root: Path, own_base: bool = True) -> Path:
    """Make ``root`` (and its missing parents) private and check it and, if ``own_base``,
    its parent (``$JETNH_CACHE`` or the user cache dir); ``_Unusable`` if it cannot be
    used.  The version directory is jetnh's: made 0700 if it is not.  ``$JETNH_CACHE``
    is the user's: never changed, only refused if others can write it."""
    base = root.parent
    fix = (f"make {base} a directory of yours that only you can write ('chmod 700 "
           f"{base}'), or set JETNH_CACHE to one")
    made = not os.path.lexists(root)
    try:
        _makedirs_private(root)
    except OSError as exc:
        raise _Unusable(f"{exc.filename or root} cannot be created ({exc.strerror})",
                        fix) from None
    for path in ((base, root) if own_base else (root,)):
        try:
            st = os.stat(path) if path == base else os.lstat(path)
        except OSError as exc:
            raise _Unusable(f"{path} cannot be read ({exc.strerror})", fix) from None
        if not stat.S_ISDIR(st.st_mode):
            raise _Unusable(f"{path} is not a directory", fix)
        if st.st_uid != _uid():
            raise _Unusable(f"{path} belongs to user {st.st_uid}, not to you ({_uid()})", fix)
        if path == base and st.st_mode & 0o022 and _env_base() is not None:
            raise _Unusable(f"{path} is writable by group or others (mode "
                            f"{stat.S_IMODE(st.st_mode):o})", fix)
        if st.st_mode & (0o077 if path == root else 0o022):
            try:
                os.chmod(path, 0o700)
            except OSError as exc:
                raise _Unusable(f"{path} has mode {stat.S_IMODE(st.st_mode):o} and cannot "
                                f"be made private ({exc.strerror})", fix) from None
    if not os.access(root, os.W_OK | os.X_OK):
        raise _Unusable(f"{root} is not writable", fix)
    # the marker: in a root jetnh made now, or one whose key file shows jetnh made it
    if (made or os.path.isfile(root / KEY_FILE)) and not owned(root):
        try:
            write_private(root / MARKER, b"jetnh kernel cache: jetnh made this directory\n")
        except FileExistsError:
            pass
        except OSError as exc:
            raise _Unusable(f"{root / MARKER} cannot be written ({exc.strerror})",
                            fix) from None
    return root


def temp_root() -> Path:
    """A private temporary cache (0700), removed at exit."""
    global _TEMP_ROOT
    if _TEMP_ROOT is None or not _TEMP_ROOT.is_dir():
        _TEMP_ROOT = Path(tempfile.mkdtemp(prefix="jetnh-kernels-"))
        atexit.register(shutil.rmtree, _TEMP_ROOT, True)
    return _TEMP_ROOT


def secret_key(root: Path) -> bytes:
    """This user's HMAC key, ``<root>/hmac.key``: 32 random bytes, mode 0600, made once
    and atomically (written aside, then linked into place: the first one stays)."""
    path = root / KEY_FILE
    for _ in range(3):
        try:
            data, _st = _read_private(path, secret=True)
            if len(data) == 32:
                return data
            _unlink(path)           # truncated: entries signed with it cannot be checked
        except FileNotFoundError:
            pass
        except Untrusted:
            _unlink(path)           # readable or writable by others: no longer a secret
        tmp = root / f".{KEY_FILE}.{os.getpid()}.{secrets.token_hex(4)}"
        try:
            write_private(tmp, secrets.token_bytes(32))
            try:
                os.link(tmp, path)
            except FileExistsError:
                pass
            except OSError:          # no hard links here: a rename, unless one appeared
                if not os.path.lexists(path):
                    os.rename(tmp, path)
        except OSError as exc:
            raise _Unusable(f"the key {path} cannot be written ({exc.strerror})",
                            "set JETNH_CACHE to a writable directory of your own") from None
        finally:
            _unlink(tmp)
    raise _Unusable(f"the key {path} cannot be made private",
                    f"remove {path} (it is made again)")


def open_root(persistent: bool) -> tuple[Path, bytes]:
    """The root to use and its key: the configured one, or the temporary fallback."""
    if persistent:
        root = cache_root()
        try:
            return root, secret_key(_prepare_root(root))
        except _Unusable as exc:
            problem, fix = exc.args
            if str(root) + problem not in _WARNED:
                _WARNED.add(str(root) + problem)
                warnings.warn(
                    f"jetnh: the kernel cache {root} cannot be used: {problem}. Compiled "
                    f"kernels go to a private temporary directory removed at exit; to keep "
                    f"them between runs, {fix}.", KernelCacheWarning, stacklevel=3)
    global _TEMP_ROOT
    for _ in range(2):
        root = temp_root()
        try:
            return root, secret_key(_prepare_root(root, own_base=False))
        except _Unusable:           # the temporary root was damaged: a new one
            _TEMP_ROOT = None
    root = temp_root()
    return root, secret_key(_prepare_root(root, own_base=False))


# ---------------------------------------------------------------------- manifests
def _mac(secret: bytes, body: dict) -> str:
    text = json.dumps(body, sort_keys=True, separators=(",", ":")).encode()
    return hmac.new(secret, text, hashlib.sha256).hexdigest()


def _listing(directory: Path) -> dict[str, Path]:
    """Every file of an entry but the manifest, by relative name (``__pycache__/<name>``
    for numba's); ``Untrusted`` if a directory is not private or is unexpected."""
    _check_stat(os.lstat(directory), directory, want_dir=True)
    out = {}
    for name in os.listdir(directory):
        if name == MANIFEST:
            continue
        path = directory / name
        if name == PYCACHE:
            _check_stat(os.lstat(path), path, want_dir=True)
            for sub in os.listdir(path):
                out[f"{PYCACHE}/{sub}"] = path / sub
        else:
            out[name] = path
    return out


def seal(directory: Path, key: str, secret: bytes, sources: dict[str, str] | None = None):
    """Write the signed manifest of ``directory``: every file, numba's included (made
    0600 first: numba creates them with the umask).  With ``sources`` (name -> sha256),
    only if the sources are still those."""
    pycache = directory / PYCACHE       # numba makes it with the umask if it was gone
    st = os.lstat(pycache) if os.path.isdir(pycache) else None
    if st is not None and st.st_uid == _uid() and st.st_mode & 0o077:
        os.chmod(pycache, 0o700)
    files = {}
    for rel, path in sorted(_listing(directory).items()):
        st = os.lstat(path)
        if stat.S_ISREG(st.st_mode) and st.st_uid == _uid() and st.st_mode & 0o077:
            os.chmod(path, 0o600)
        data, _st = _read_private(path)
        files[rel] = hashlib.sha256(data).hexdigest()
    if sources is not None and any(files.get(n) != h for n, h in sources.items()):
        raise Untrusted(f"{directory} changed while it was loaded")
    if any(n not in files for n in SOURCES):
        raise Untrusted(f"{directory} is incomplete")
    body = {"format": MANIFEST_FORMAT, "key": key, "files": files}
    _replace_private(directory / MANIFEST,
                     json.dumps({"body": body, "mac": _mac(secret, body)}).encode())


def verify(directory: Path, key: str, secret: bytes):
    """``(contents, stamps, hashes)`` of a trusted entry -- the bytes of its sources, the
    (size, mtime) of each file, the manifest's hashes -- or ``None`` if there is no
    entry; ``Untrusted`` (saying why) if it is not what this user's jetnh wrote."""
    try:
        os.lstat(directory)
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise Untrusted(f"{directory}: {exc.strerror}") from None
    try:
        listing = _listing(directory)
        raw, _st = _read_private(directory / MANIFEST)
        doc = json.loads(raw)
        body, mac = doc["body"], doc["mac"]
        if not (isinstance(mac, str) and hmac.compare_digest(mac, _mac(secret, body))):
            raise Untrusted(f"{directory / MANIFEST} is not signed with your key")
        files = body["files"]
        if body["format"] != MANIFEST_FORMAT or body["key"] != key:
            raise Untrusted(f"{directory / MANIFEST} is for another entry")
        if set(listing) != set(files) or any(n not in files for n in SOURCES):
            extra = sorted(set(listing) - set(files))
            missing = sorted(set(files) - set(listing))
            raise Untrusted(f"{directory}: files not in the manifest {extra}, "
                             f"missing {missing}")
        contents, stamps = {}, {}
        for rel, path in sorted(listing.items()):
            data, st = _read_private(path)
            if not hmac.compare_digest(hashlib.sha256(data).hexdigest(), str(files[rel])):
                raise Untrusted(f"{path} does not match the manifest")
            stamps[rel] = (st.st_size, st.st_mtime_ns)
            if rel in SOURCES:
                contents[rel] = data
    except Untrusted:
        raise
    except FileNotFoundError as exc:
        raise Untrusted(f"{exc.filename} is missing") from None
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise Untrusted(f"{directory}: {type(exc).__name__}: {exc}") from None
    return contents, stamps, files


def read(entry: Path, key: str, secret: bytes):
    """The verified bytes of ``entry``: ``(contents, stamps, hashes)`` as ``verify``, or
    ``None`` when there is no entry or it is untrusted or damaged (then removed)."""
    try:
        return verify(entry, key, secret)
    except Untrusted:
        discard(entry)
        return None


def changed(directory: Path, stamps: dict) -> bool:
    """Whether the files of ``directory`` are no longer those ``stamps`` recorded (numba
    added or rewrote machine code while loading)."""
    try:
        now = {rel: os.lstat(p) for rel, p in _listing(directory).items()}
    except (OSError, Untrusted):
        return False
    return (set(now) != set(stamps)
            or any((st.st_size, st.st_mtime_ns) != stamps[rel] for rel, st in now.items()))




def stage(root: Path, key: str, source: bytes, layout: bytes) -> Path:
    """A private staging directory ``<root>/.k<key>.*`` holding the sources."""
    tmp = Path(tempfile.mkdtemp(prefix=f".k{key}.", dir=root))
    write_private(tmp / "__init__.py", INIT_TEXT)
    write_private(tmp / "kernels.py", source)
    write_private(tmp / "layout.json", layout)
    _mkdir_private(tmp / PYCACHE)
    return tmp


def publish(tmp: Path, entry: Path, key: str, secret: bytes) -> bool:
    """Rename the sealed ``tmp`` to ``entry``.  If another process put a trusted entry
    there first, that one stays and ``tmp`` is discarded; an untrusted one is replaced."""
    for _ in range(3):
        try:
            os.rename(tmp, entry)
            return True
        except OSError as exc:
            if exc.errno not in (errno.EEXIST, errno.ENOTEMPTY, errno.ENOTDIR, errno.EISDIR):
                raise
        try:
            if verify(entry, key, secret) is not None:
                shutil.rmtree(tmp, ignore_errors=True)
                return True
        except Untrusted:
            discard(entry)
    shutil.rmtree(tmp, ignore_errors=True)
    return False


def remove_stale(root: Path):
    """Staging and trash directories, key files and other files being made
    (``_replace_private``'s ``.tmp``), left by processes that died."""
    now = time.time()
    try:
        names = os.listdir(root)
    except OSError:
        return
    for name in names:
        if name.startswith((".k", ".trash-", f".{KEY_FILE}.")) or (
                name.startswith(".") and name.endswith(".tmp")):
            path = root / name
            try:
                st = os.lstat(path)
            except OSError:
                continue
            if now - st.st_mtime > STALE_SECONDS:
                if stat.S_ISDIR(st.st_mode):
                    shutil.rmtree(path, ignore_errors=True)
                else:
                    _unlink(path)

