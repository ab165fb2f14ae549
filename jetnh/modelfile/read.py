"""Reading a model file safely: a regular file of at most ``MAX_FILE_BYTES`` bytes,
UTF-8 text without NUL, valid TOML (the guarantees: ``jetnh.modelfile``).

Devices, FIFOs, sockets and directories are refused before they are read from (``stat``
before opening, ``fstat`` on the descriptor, opened non-blocking); at most
``MAX_FILE_BYTES`` + 1 bytes are read whatever size the file claims.
"""

from __future__ import annotations

import codecs
import os
import stat
import tomllib
from pathlib import Path

from ..errors import ModelFileError
from . import limits
from .expression import literal
from .model import Model
from .schema import from_dict
from .text import position, shorten


def _toml_float(text: str, source: str) -> float:
    """A TOML float, refused where its nonzero digits fall below double precision's
    normal range (``expression.literal``)."""
    value = float(text.replace("_", ""))

    def fail(what):
        raise ModelFileError(f"{source}: {what} {text!r}")

    literal(text, value, fail, form=False)
    return value


def loads(text: str, source: str = "<string>") -> Model:
    """A ``Model`` from the text of a model file."""
    if not isinstance(text, str):
        raise ModelFileError(f"{source}: a model file is text (str), got "
                             f"{type(text).__name__}; decode bytes as UTF-8 first")
    most = limits.MAX_FILE_BYTES
    if len(text) > most or len(text.encode("utf-8", "replace")) > most:
        raise ModelFileError(f"{source}: the file is larger than {most} bytes, the limit of a "
                             "model file")
    nul = text.find("\x00")
    if nul >= 0:
        line, col = position(text, nul)
        raise ModelFileError(f"{source}: the text contains a NUL character at line {line}, "
                             f"column {col}; a model file is plain text (is this a binary "
                             "file?)")
    if text.startswith("\ufeff"):                    # a UTF-8 byte-order mark
        text = text[1:]
    try:
        data = tomllib.loads(text, parse_float=lambda t: _toml_float(t, source))
    except ModelFileError:
        raise
    except tomllib.TOMLDecodeError as exc:
        raise ModelFileError(f"{source}: not valid TOML: {exc}; see the format in "
                             "jetnh.modelfile's documentation") from None
    except RecursionError:
        raise ModelFileError(f"{source}: not valid TOML: nested too deeply") from None
    except Exception as exc:                       # e.g. ValueError of a 5000-digit integer
        raise ModelFileError(f"{source}: not valid TOML ({type(exc).__name__}: "
                             f"{shorten(str(exc))})") from None
    return from_dict(data, source)


_FILE_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
               (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
               (stat.S_ISSOCK, "a socket"))


def _not_regular(p, mode) -> ModelFileError:
    kind = next((name for test, name in _FILE_KINDS if test(mode)), "not a regular file")
    return ModelFileError(f"{p}: is {kind}, not a regular file; a model file must be a "
                          "regular file (reading pipes, devices or directories may never "
                          "end); give the path of a .toml file")


def _read_bytes(p: Path) -> bytes:
    """At most ``MAX_FILE_BYTES`` bytes of the regular file ``p`` (symlinks followed)."""
    try:
        # stat first, so that devices and FIFOs are not even opened; then check the
        # opened descriptor itself (the path may have changed in between)
        before = os.stat(p)
        if not stat.S_ISREG(before.st_mode):
            raise _not_regular(p, before.st_mode)
        flags = (os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
                 | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_BINARY", 0))
        fd = os.open(p, flags)
    except ModelFileError:
        raise
    except FileNotFoundError:
        raise ModelFileError(f"{p}: no such file; check the path") from None
    except PermissionError:
        raise ModelFileError(f"{p}: permission denied; the file must be readable") from None
    except (OSError, ValueError) as exc:          # ELOOP, ENAMETOOLONG, a NUL in the path
        why = getattr(exc, "strerror", None) or str(exc)
        raise ModelFileError(f"{p}: cannot open the file ({why})") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise _not_regular(p, st.st_mode)
        if st.st_size > limits.MAX_FILE_BYTES:
            raise ModelFileError(f"{p}: the file has {st.st_size} bytes; the limit is "
                                 f"{limits.MAX_FILE_BYTES}")
        chunks, total, most = [], 0, limits.MAX_FILE_BYTES
        while total <= most:                     # never more than the limit + 1 bytes
            chunk = os.read(fd, min(1 << 16, most + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
        if total > most:
            raise ModelFileError(f"{p}: the file has more than {most} bytes (the limit)")
        return b"".join(chunks)
    except ModelFileError:
        raise
    except OSError as exc:
        raise ModelFileError(f"{p}: cannot read the file ({exc.strerror or exc})") from None
    finally:
        os.close(fd)


def load(path) -> Model:
    """A ``Model`` from a model file on disk (a regular file; symlinks are followed)."""
    if not isinstance(path, (str, os.PathLike)):
        raise ModelFileError(f"the path of a model file is a str or a Path, got "
                             f"{type(path).__name__}")
    try:
        p = Path(path)
    except (TypeError, ValueError) as exc:
        raise ModelFileError(f"{path!r} is not a usable path ({exc})") from None
    raw = _read_bytes(p)
    nul = raw.find(b"\x00")
    if nul >= 0:
        line, col = position(raw, nul)
        raise ModelFileError(f"{p}: contains a NUL byte at line {line}, column {col} (byte "
                             f"{nul}); a model file is UTF-8 text (is this a binary file?)")
    if raw.startswith(codecs.BOM_UTF8):
        raw = raw[len(codecs.BOM_UTF8):]
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line, col = position(raw, exc.start)
        raise ModelFileError(f"{p}: not UTF-8 text: the byte 0x{raw[exc.start]:02X} at line "
                             f"{line}, column {col} (byte {exc.start}) cannot be decoded; "
                             "save the file as UTF-8") from None
    return loads(text, str(p))
