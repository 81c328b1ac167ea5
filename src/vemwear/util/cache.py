"""The user's cache of vemwear: reference solutions kept between runs.

It lives in the user's cache directory (``platformdirs``: ``~/.cache/vemwear`` on
Linux, ``$XDG_CACHE_HOME/vemwear`` when that is set), or where ``VEMWEAR_CACHE_DIR``
points; never beside an output directory, whose parent may be read-only (a container
volume) or someone else's. ``vemwear clean --cache`` shows its size and empties it.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

__all__ = ["cache_size", "clear_cache", "user_cache_dir"]


def user_cache_dir() -> Path:
    """The cache directory of vemwear (created by whoever writes into it)."""
    env = os.environ.get("VEMWEAR_CACHE_DIR")
    if env:
        return Path(env).expanduser().absolute()
    import platformdirs

    return Path(platformdirs.user_cache_dir("vemwear", appauthor=False))


def cache_size(path: Path | None = None) -> tuple[int, int]:
    """Bytes and files in the cache (or in ``path``); (0, 0) if it does not exist."""
    root = user_cache_dir() if path is None else path
    sizes = [f.lstat().st_size for f in root.rglob("*") if f.is_file()] if root.is_dir() else []
    return sum(sizes), len(sizes)


def clear_cache(path: Path | None = None) -> tuple[int, int]:
    """Empty the cache (or ``path``); returns the bytes and files it held."""
    root = user_cache_dir() if path is None else path
    held = cache_size(root)
    if root.is_dir():
        shutil.rmtree(root)
    return held
