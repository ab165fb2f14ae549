"""Output files of the command line: checked before any work, written atomically.

``check(path, kinds, what)`` refuses, before a derivation or a run starts, a path that is
a directory, whose directory does not exist or cannot be written, whose suffix is not a
format of ``kinds`` (``TABLE``, ``CSV``, ``TEXT`` or ``FIGURE``: matplotlib's formats)
or whose format needs a library that is not installed (pyarrow for parquet, matplotlib
for figures).  ``write(path, fill)`` calls ``fill(tmp)`` on a temporary file in the same
directory, then renames it over ``path`` (``os.replace``) with the permissions of the
file it replaces (else those of a new file): a failed write (a full disk) leaves the
previous file as it was, removes the temporary one and names the path.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path

from ..errors import JetnhError

CSV = (".csv",)
TABLE = (".csv", ".parquet")
TEXT = None                     # any suffix
FIGURE = "figure"


def _figure_formats() -> tuple[str, ...]:
    try:
        from matplotlib.backend_bases import FigureCanvasBase
    except ImportError:
        raise JetnhError("plots need matplotlib: pip install matplotlib") from None
    return tuple("." + k for k in FigureCanvasBase.get_supported_filetypes())


def check(path, kinds, what: str) -> Path:
    """``path`` as a Path after the checks above (a ``JetnhError`` naming it)."""
    p = Path(path)
    if p.is_dir():
        raise JetnhError(f"cannot write {what} {p}: it is a directory; give a file name")
    parent = p.resolve().parent
    if not parent.is_dir():
        raise JetnhError(f"cannot write {what} {p}: the directory {parent} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK) or not _takes_files(parent, p.name):
        raise JetnhError(f"cannot write {what} {p}: the directory {parent} is not writable")
    suffix = p.suffix.lower()
    allowed = _figure_formats() if kinds == FIGURE else kinds
    if allowed is not None and suffix not in allowed:
        raise JetnhError(f"cannot write {what} {p}: {suffix or 'no suffix'} is not one of "
                         f"the formats; give a {' or '.join(allowed)} path")
    if suffix == ".parquet":
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise JetnhError(f"cannot write {what} {p}: parquet needs pyarrow (pip install "
                             "'jetnh[parquet]'), or write a .csv") from None
    return p


def _takes_files(parent: Path, name: str) -> bool:
    """Whether a file can be made in ``parent`` (a temporary one, removed at once): what
    ``os.access`` does not tell for root, or in a file system such as /proc."""
    try:
        fd, tmp = tempfile.mkstemp(dir=parent, prefix=f".{name}.", suffix=".check")
    except OSError:
        return False
    os.close(fd)
    os.unlink(tmp)
    return True


def _mode(path: Path) -> int:
    """The permissions of the file written to ``path``: those of the file it replaces,
    else what ``open`` would give a new file (0o666 less the umask; the temporary file
    is made 0o600)."""
    try:
        return path.stat().st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def write(path, fill) -> None:
    """``fill(tmp)`` writes the content to the path ``tmp``; then it replaces ``path``.
    An error names ``path``, never the temporary file."""
    p = Path(path)
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(dir=p.resolve().parent, prefix=f".{p.name}.",
                                   suffix=f".partial{p.suffix}")
        os.close(fd)
        fill(tmp)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.chmod(tmp, _mode(p))
        os.replace(tmp, p)
    except BaseException as exc:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass
        if isinstance(exc, OSError):
            raise JetnhError(f"cannot write {p}: {exc.strerror or type(exc).__name__}; the "
                             "previous file, if any, is unchanged") from None
        raise


def as_json(data, **kw) -> str:
    """``data`` as strict JSON (RFC 8259, which has no NaN or infinity): a float that is
    not finite becomes null (a NaN energy that could not be evaluated, an undecided
    margin); numpy numbers become Python ones."""
    def clean(v):
        if isinstance(v, dict):
            return {k: clean(x) for k, x in v.items()}
        if isinstance(v, (list, tuple)):
            return [clean(x) for x in v]
        if isinstance(v, float) and not math.isfinite(v):
            return None
        return v

    def number(o):
        return clean(float(o))
    return json.dumps(clean(data), allow_nan=False, default=number, **kw)
