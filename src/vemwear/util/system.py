"""What the machine offers: available memory, free disk space, this process's memory."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

__all__ = ["available_memory", "free_disk", "peak_memory", "resident_memory"]


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


def _status(key: str) -> int | None:
    """A size from ``/proc/self/status`` in bytes (Linux), or None."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def _maxrss() -> int:
    try:
        import resource

        return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) * 1024
    except (ImportError, OSError):
        return 0


def resident_memory() -> int:
    """Bytes of memory this process holds now (Linux ``VmRSS``; elsewhere its peak
    resident size, or 0 if unknown)."""
    now = _status("VmRSS")
    return _maxrss() if now is None else now


def peak_memory() -> int:
    """Peak bytes of memory this process has held (Linux ``VmHWM``).

    Not ``ru_maxrss``: Linux carries that across ``execve``, so a child started by a
    large parent (a test runner) reports the parent's size as its own peak.
    """
    peak = _status("VmHWM")
    return _maxrss() if peak is None else peak
