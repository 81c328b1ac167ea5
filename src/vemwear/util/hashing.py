"""Canonical hashes of inputs: the one fingerprint scheme of runs and cached results.

A fingerprint is JSON-friendly data; :func:`sha256_json` hashes its canonical JSON
form (sorted keys, numbers as floats, so that ``4`` and ``4.0`` are the same input).
Arrays enter through :func:`sha256_arrays`, which hashes their dtype, shape and bytes.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Mapping
from typing import Any

import numpy as np


def normalize(x: Any) -> Any:
    """JSON-friendly canonical form: numbers as floats, tuples as lists, keys as strings."""
    if isinstance(x, Mapping):
        return {str(k): normalize(v) for k, v in x.items()}
    if isinstance(x, np.ndarray):
        return normalize(x.tolist())
    if isinstance(x, list | tuple):
        return [normalize(v) for v in x]
    if isinstance(x, bool) or x is None or isinstance(x, str):
        return x
    if isinstance(x, int | float | np.integer | np.floating):
        v = float(x)
        return v if math.isfinite(v) else str(v)
    return str(x)


def sha256_json(data: Any) -> str:
    """Hex SHA-256 of the canonical JSON of ``normalize(data)``."""
    text = json.dumps(normalize(data), sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def sha256_arrays(*arrays: Any) -> str:
    """Hex SHA-256 of arrays: dtype, shape and contents of each, in order."""
    h = hashlib.sha256()
    for a in arrays:
        arr = np.ascontiguousarray(a)
        h.update(f"{arr.dtype.str}{arr.shape}".encode())
        h.update(arr.tobytes())
    return h.hexdigest()


def sha256_file(path: str | os.PathLike[str]) -> str:
    """Hex SHA-256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()
