"""Text files the user gives (configurations, studies, data): UTF-8, or one clear line.

A file saved as UTF-16 (a Windows editor's "Unicode"), Latin-1 or binary data made
``open(...).read()`` fail with a ``UnicodeDecodeError`` far from the file's name; here
the error names the byte, its offset and its line.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["NotUtf8Error", "read_utf8"]

_BOMS = {b"\xff\xfe": "UTF-16 (little-endian)", b"\xfe\xff": "UTF-16 (big-endian)"}


class NotUtf8Error(ValueError):
    """A text file that is not UTF-8; the message says where."""


def read_utf8(path: str | os.PathLike[str]) -> str:
    """The text of ``path``, which must be UTF-8 (a UTF-8 byte-order mark is dropped).

    Raises
    ------
    NotUtf8Error
        Naming the first byte that is not UTF-8, its offset and line.
    OSError
        If the file cannot be read.
    """
    data = Path(path).read_bytes()
    for bom, name in _BOMS.items():
        if data.startswith(bom) and not data.startswith(b"\xff\xfe\x00\x00"):
            raise NotUtf8Error(
                f"not UTF-8 text: a {name} byte-order mark at byte offset 0; save the file as UTF-8"
            )
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise NotUtf8Error(
            f"not UTF-8 text: byte 0x{data[exc.start]:02x} at byte offset {exc.start} "
            f"(line {line}); save the file as UTF-8"
        ) from None
