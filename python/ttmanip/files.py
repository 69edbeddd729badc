"""Reading user files within limits (issue 29): every text or JSON file the package reads (hit
files, flight recordings, ball lists, telemetry) goes through here, so that a device such as
``/dev/zero``, a zip bomb, a non-UTF-8 byte, JSON nested 100,000 deep or a 401-digit integer is a
one-line :class:`ttmanip.TtmanipError` naming the file, never a hang, a ``MemoryError`` or a
traceback. The limits are ``ttkin::budget``'s (``docs/boundary.md``)."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import IO, Any

from . import TtmanipError

__all__ = [
    "MAX_FILE_BYTES",
    "MAX_JSON_DEPTH",
    "MAX_TOTAL_BYTES",
    "json_depth",
    "load_json",
    "read_limited",
    "read_text",
]

#: Largest file read, bytes (16 MiB, ``ttkin::budget::MAX_FILE_BYTES``).
MAX_FILE_BYTES = 16 << 20
#: Largest sum of the files of one collection (a folder or zip of flights), bytes (512 MiB,
#: ``ttkin::budget::MAX_BYTES``).
MAX_TOTAL_BYTES = 512 << 20
#: Deepest nesting of JSON arrays and objects read.
MAX_JSON_DEPTH = 64


def read_limited(f: IO[bytes], what: str, limit: int = MAX_FILE_BYTES) -> bytes:
    """At most ``limit`` bytes of the open binary file ``f`` (reads one byte more to tell); a
    longer file is refused naming ``what``. ``limit``: an integer in 0..=:data:`MAX_TOTAL_BYTES`."""
    if not callable(getattr(f, "read", None)):
        raise TypeError(f"f: expected a binary file open for reading, got {type(f).__name__}")
    if isinstance(limit, bool) or not isinstance(limit, int) or not 0 <= limit <= MAX_TOTAL_BYTES:
        # f.read(10**400) raised a bare OverflowError; a limit over 512 MiB is no limit
        shown = (
            f"an integer of {len(str(limit))} digits"
            if isinstance(limit, int) and abs(limit) > 10**30
            else repr(limit)
        )
        raise TtmanipError(
            f"limit: expected an integer number of bytes in 0..={MAX_TOTAL_BYTES}, got {shown}"
        )
    raw = f.read(limit + 1)
    if not isinstance(raw, bytes):
        raise TypeError(f"f: expected a binary file (read() gave {type(raw).__name__}, not bytes)")
    if len(raw) > limit:
        raise TtmanipError(f"{what}: larger than {limit} bytes ({limit >> 20} MiB), the most a file may be")
    return raw


def decode(raw: bytes, what: str) -> str:
    """``raw`` as UTF-8 text; an invalid byte is refused with its offset."""
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise TtmanipError(f"{what}: not UTF-8 text: invalid byte at offset {e.start}") from None


def read_text(path: str | Path, what: str | None = None) -> str:
    """The UTF-8 text of the file at ``path``, read no further than :data:`MAX_FILE_BYTES`
    (``/dev/zero`` ends the read). ``OSError`` (missing, unreadable, a folder) passes through."""
    what = str(path) if what is None else what
    with open(path, "rb") as f:
        return decode(read_limited(f, what), what)


def json_depth(text: str) -> int:
    """Deepest nesting of ``[`` and ``{`` in JSON ``text`` (strings skipped), without recursing."""
    depth = deepest = 0
    for m in re.finditer(r'"(?:[^"\\]|\\.)*"|[\[\]{}]', text):
        c = m.group()
        if c in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif c in "]}":
            depth -= 1
    return deepest


def load_json(text: str | bytes, what: str) -> Any:
    """Parses JSON ``text`` (bytes must be UTF-8) nested at most :data:`MAX_JSON_DEPTH` deep;
    integers are read as floats (a 401-digit integer is ``inf``, for the caller's finiteness
    check, not an ``OverflowError``). Malformed JSON is a :class:`TtmanipError` with line and
    column."""
    if isinstance(text, bytes):
        text = decode(text, what)
    depth = json_depth(text)
    if depth > MAX_JSON_DEPTH:
        raise TtmanipError(f"{what}: JSON nested {depth} deep, at most {MAX_JSON_DEPTH}")
    try:
        return json.loads(text, parse_int=float)
    except json.JSONDecodeError as e:
        raise TtmanipError(f"{what}: not valid JSON (line {e.lineno}, column {e.colno}: {e.msg})") from None
    except (ValueError, RecursionError) as e:
        raise TtmanipError(f"{what}: not readable JSON ({e})") from None
