"""Characters and positions in the text of a model file: what the refusals quote."""

from __future__ import annotations

import unicodedata

from ..errors import ModelFileError


def shorten(s: str, limit: int = 60) -> str:
    """``s`` on one line, cut to ``limit`` characters (for quoting it in a message)."""
    s = " ".join(s.split())
    return s if len(s) <= limit else s[:limit - 3] + "..."


def char_column(text: str, line: int, byte_col: int | None) -> int:
    """ast gives UTF-8 byte offsets; report characters."""
    if byte_col is None:
        return 0
    lines = text.splitlines() or [""]
    if 1 <= line <= len(lines):
        return len(lines[line - 1].encode("utf-8")[:byte_col].decode("utf-8", "replace"))
    return byte_col


def line_col(text: str, offset: int) -> tuple[int, int]:
    """(line from 1, column from 0) of a character offset in ``text``."""
    before = text[:offset]
    line = before.count("\n") + 1
    return line, offset - (before.rfind("\n") + 1)


def position(data, offset: int) -> tuple[int, int]:
    """(line, column), both from 1, of a character (str) or byte (bytes) offset."""
    before = data[:offset]
    nl = "\n" if isinstance(before, str) else b"\n"
    line = before.count(nl) + 1
    start = before.rfind(nl) + 1
    head = before[start:]
    if isinstance(head, bytes):
        head = head.decode("utf-8", "replace")
    return line, len(head) + 1


def refuse_non_ascii(text: str, where: str, at=None):
    """Refuse the first non-ASCII character of ``text``: Python's parser folds letters
    such as U+FF58 (fullwidth x) or U+1D465 (mathematical italic x) into 'x' (NFKC),
    so a name could silently mean another.  ``at(i)``: the (line, column from 0) of
    character ``i``, to report."""
    for i, ch in enumerate(text):
        if ord(ch) > 127:
            name = unicodedata.name(ch, "")
            folded = unicodedata.normalize("NFKC", ch)
            also = (f"; Python would silently read it as {folded!r}"
                    if folded != ch and folded.isascii() else "")
            pos = ""
            if at is not None:
                line, col = at(i)
                pos = f" at line {line}, column {col + 1}"
            raise ModelFileError(
                f"{where}: the character U+{ord(ch):04X}{f' ({name})' if name else ''} "
                f"{ch!r}{pos} is not ASCII{also}; write names, numbers and operators in "
                "ASCII (letters a-z, A-Z, digits and _)")
