"""Text that is safe to show: much of what a report says comes from the submission (file
names, messages of its errors, notes on its notebook), so a file name is made printable
(:func:`printable`) and every other string bounded (:func:`bounded`, :func:`one_line`) and
writable as UTF-8 (:func:`utf8`) before any view or log shows it.

Plain functions of strings, below every module that shows one: the submission's reader and
the sandbox name files with them, the record of a result (:mod:`autograder.findings`) and
its views bound what they say."""

from __future__ import annotations

import os

MAX_LINE = 2000  # characters of one problem, note or reason: far more than ours ever say
MAX_FIELD = 20_000  # characters of one field of results.json (a test's output, the header)


def bounded(text: str, limit: int = MAX_LINE) -> str:
    """``text`` cut to ``limit`` characters, saying how many were cut; characters that
    cannot be written as UTF-8 (lone surrogates) escaped."""
    if len(text) > limit:
        text = f"{text[:limit]} [... {len(text) - limit} characters cut]"
    return utf8(text)


def one_line(text: str, limit: int = MAX_LINE) -> str:
    """``text`` as one line (every run of white space a single space), :func:`bounded`."""
    return bounded(" ".join(text.split()), limit)


def utf8(text: str) -> str:
    """``text`` with lone surrogates (which a forged JSON message can hold) escaped: print()
    and UTF-8 files would fail on them."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return text.encode("utf-8", "backslashreplace").decode("utf-8")
    return text


def printable(text: str | os.PathLike[str]) -> str:
    """A file name or path as it can be shown and written anywhere: bytes that are not UTF-8
    as ``\\xe9``, control and invisible characters escaped (``\\n``, ``\\x1b``,
    ``\\u202e``)."""
    s = os.fsdecode(text)
    out = []
    for ch in s:
        code = ord(ch)
        if 0xDC80 <= code <= 0xDCFF:  # a byte that was not UTF-8 (os.fsdecode's surrogateescape)
            out.append(f"\\x{code - 0xDC00:02x}")
        else:
            out.append(ch if ch.isprintable() else repr(ch)[1:-1])
    return "".join(out)
