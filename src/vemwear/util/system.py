"""What the machine offers: available memory and free disk space."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

__all__ = ["available_memory", "free_disk"]


def available_memory() -> int:
    """Bytes of memory available to a new process (Linux ``MemAvailable``; elsewhere the
    free physical pages, or 0 if unknown)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return 0


def free_disk(path: str | os.PathLike[str]) -> int:
    """Free bytes on the file system of ``path`` (or of its nearest existing ancestor)."""
    p = Path(path).expanduser().absolute()
    while not p.exists():
        p = p.parent
    return shutil.disk_usage(p).free
