"""The wire between the grader and the sandboxed child: length-prefixed JSON, never pickles.

A frame is a 4-byte big-endian length and that many bytes of UTF-8 JSON. The child's standard
input and output pipes carry the frames, and the child moves them off descriptors 0 and 1
before anything else runs (a submission's ``print`` goes to the log, ``input()`` reads
nothing), so whatever a submission prints is never mistaken for a result. Reading blocks;
the grader waits for a frame with a deadline on a thread of its own
(:class:`autograder.sandbox.Replies`), which works on every platform. Values cross as plain
data:

* grader to child, arguments: numbers, strings, and arrays as ``{"nd": [...], "shape": [...]}``;
* child to grader, a returned value described by :func:`encode_value` (arrays, strings such
  as joint names, and sequences of them), which the grader
  turns back into a :class:`Value` with :func:`decode_value` and validates (the child is
  untrusted: anything malformed is a :class:`ProtocolError`).

This module is also loaded by the child (by path, standard library and numpy only).
"""

from __future__ import annotations

import json
import math
import os
import struct
from dataclasses import dataclass
from typing import Any

import numpy as np

MAX_FRAME = 8 << 20  # a single rotation's answer is tiny; this only bounds garbage
MAX_ITEMS = 1 << 20  # numbers in one returned array
MAX_STR = 200  # characters kept of a returned string (a joint name, say)
MAX_INT_DIGITS = 19  # an int64's; the child sends numbers as floats, so a longer int is forged
_asarray = np.asarray  # bound now: a submission may monkeypatch numpy later


class ProtocolError(Exception):
    """The other side sent something that is not a well-formed frame or value."""


# --- framing -------------------------------------------------------------------------------


def write_frame(fd: int, obj: Any) -> None:
    data = json.dumps(obj, separators=(",", ":")).encode()
    view = memoryview(struct.pack(">I", len(data)) + data)
    while view:
        view = view[os.write(fd, view):]


def read_frame(fd: int, parse_at_most: int = MAX_FRAME) -> Any | None:
    """Read one frame (blocking); None at end of file. A frame longer than ``parse_at_most``
    bytes (but within :data:`MAX_FRAME`) is read and dropped unparsed, as
    ``{"oversized": its length}``."""
    head = _read_exactly(fd, 4)
    if head is None:
        return None
    (n,) = struct.unpack(">I", head)
    if n > MAX_FRAME:
        raise ProtocolError(f"frame of {n} bytes is too large")
    if n > parse_at_most:
        for start in range(0, n, 1 << 16):
            if _read_exactly(fd, min(1 << 16, n - start)) is None:
                raise ProtocolError("stream ended inside a frame")
        return {"oversized": n}
    body = _read_exactly(fd, n)
    if body is None:
        raise ProtocolError("stream ended inside a frame")
    try:
        return json.loads(body, parse_int=_bounded_int)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ProtocolError(f"not JSON ({exc})") from None
    except RecursionError:  # '[[[[...' nested deeper than the parser goes: forged
        raise ProtocolError("JSON nested too deeply") from None


def _bounded_int(digits: str) -> int:
    """An integer of the frame, refused past an int64's digits: ``int()`` of a long digit
    string costs quadratic time, and Python refuses more than 4300 digits with a ValueError
    that is not the child's to raise in the grader."""
    if len(digits.lstrip("-")) > MAX_INT_DIGITS:
        raise ProtocolError(f"an integer of {len(digits)} digits")
    return int(digits)


def _read_exactly(fd: int, n: int) -> bytes | None:
    buf = bytearray()
    while len(buf) < n:
        chunk = os.read(fd, n - len(buf))
        if not chunk:
            if buf:
                raise ProtocolError("stream ended inside a frame")
            return None
        buf += chunk
    return bytes(buf)


# --- arguments (grader -> child) ------------------------------------------------------------


def encode_args(args: tuple[Any, ...]) -> list[Any]:
    """Arrays as nested data; integer arrays (a skeleton's ``parents``) stay integers."""
    return [
        {"nd": a.ravel().tolist(), "shape": list(a.shape),
         "int": a.dtype.kind in "iu"} if isinstance(a, np.ndarray) else a
        for a in args
    ]


def decode_args(args: list[Any]) -> list[Any]:
    return [
        _asarray(a["nd"], dtype=np.int64 if a.get("int") else np.float64).reshape(a["shape"])
        if isinstance(a, dict) else a
        for a in args
    ]


# --- returned values (child -> grader) ------------------------------------------------------


def encode_value(x: Any, depth: int = 0, most: int | None = None) -> dict[str, Any]:
    """Describe what a student's function returned as plain JSON (runs in the child). An
    array of more than ``most`` numbers is only counted, ``{"kind": "oversized", "numbers":
    n}``: encoding a million numbers the grader would not read costs the case's time."""
    if x is None:
        return {"kind": "none"}
    if isinstance(x, (str, np.str_)):
        return {"kind": "str", "value": str(x)[:MAX_STR]}
    if isinstance(x, np.ndarray) and x.dtype.kind == "U" and x.ndim == 1 and len(x) <= 64:
        return {"kind": "seq", "type": "ndarray", "items": [encode_value(i) for i in x]}
    if isinstance(x, (np.ndarray, np.generic, int, float)):
        return _encode_array(_asarray(x), type(x).__name__, most)
    if isinstance(x, (list, tuple)):
        try:
            a = _asarray(x)
        except (ValueError, TypeError):
            a = None
        if a is not None and a.dtype.kind in "biuf":
            return _encode_array(a, type(x).__name__, most)
        if depth < 3 and len(x) <= 64:
            return {"kind": "seq", "type": type(x).__name__,
                    "items": [encode_value(i, depth + 1, most) for i in x]}
    return {"kind": "other", "type": type(x).__name__}


def _encode_array(a: np.ndarray, type_name: str, most: int | None = None) -> dict[str, Any]:
    if a.dtype.kind not in "biuf":
        return {"kind": "other", "type": f"{type_name} of dtype {a.dtype}"}
    if most is not None and a.size > most:
        return {"kind": "oversized", "numbers": int(a.size)}
    if a.size > MAX_ITEMS:
        return {"kind": "other", "type": f"array of {a.size} numbers (too large)"}
    return {"kind": "array", "type": type_name, "dtype": "bool" if a.dtype.kind == "b" else
            str(a.dtype), "shape": list(a.shape), "data": a.astype(np.float64).ravel().tolist()}


@dataclass(frozen=True)
class Value:
    """A returned value as the grader sees it.

    ``kind`` is ``"array"`` (numbers; ``array`` holds them as float64 and ``dtype`` the
    student's dtype), ``"str"`` (``text``), ``"seq"`` (a list/tuple of ``items`` that is not
    one array), ``"none"``, or ``"other"`` (anything else; ``type_name`` says what).
    """

    kind: str
    type_name: str = ""
    array: np.ndarray | None = None
    dtype: str = ""
    items: tuple[Value, ...] = ()
    text: str = ""


def numbers_in(obj: Any, depth: int = 0) -> int:
    """How many numbers the child's JSON value declares, counted without decoding it (the
    grader refuses an answer far larger than expected before building it)."""
    if not isinstance(obj, dict) or depth > 3:
        return 0
    if obj.get("kind") == "array":
        data = obj.get("data")
        return len(data) if isinstance(data, list) else 0
    items = obj.get("items") if obj.get("kind") == "seq" else None
    if isinstance(items, list):
        return sum(numbers_in(i, depth + 1) for i in items[:64])
    return 0


def decode_value(obj: Any, depth: int = 0) -> Value:
    """Rebuild a :class:`Value` from the child's JSON, rejecting anything malformed (nested
    deeper than :func:`encode_value` writes, say)."""
    if depth > 3:
        raise ProtocolError("value nested too deeply")
    try:
        kind = obj["kind"]
        type_name = str(obj.get("type", ""))[:60]
        if kind == "none":
            return Value("none", "NoneType")
        if kind == "other":
            return Value("other", type_name or "object")
        if kind == "oversized":  # counted, not sent (encode_value's ``most``)
            return Value("other", f"array of {int(obj['numbers'])} numbers (too large)")
        if kind == "str":
            if not isinstance(obj["value"], str):
                raise ProtocolError("bad string")
            return Value("str", "str", text=obj["value"][:MAX_STR])
        if kind == "seq":
            items = obj["items"]
            if not isinstance(items, list) or len(items) > 64:
                raise ProtocolError("bad sequence")
            return Value("seq", type_name, items=tuple(decode_value(i, depth + 1)
                                                       for i in items))
        if kind == "array":
            shape = tuple(obj["shape"])
            data = obj["data"]
            if (len(shape) > 8 or not all(type(s) is int and s >= 0 for s in shape)
                    or not isinstance(data, list) or len(data) != math.prod(shape)
                    or not all(type(v) in (int, float) for v in data)):
                raise ProtocolError("bad array")
            arr = np.array(data, dtype=np.float64).reshape(shape)
            return Value("array", type_name, arr, str(obj["dtype"])[:20])
    except (KeyError, TypeError, AttributeError, ValueError, OverflowError) as exc:
        raise ProtocolError(f"malformed value ({exc})") from None
    raise ProtocolError(f"unknown value kind {kind!r}")
