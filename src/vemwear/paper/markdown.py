"""Small Markdown helpers shared by the examples' reports."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

__all__ = ["cell", "links", "num", "subdir", "table", "yes"]


def subdir(name: str) -> str:
    """The subdirectory of example ``name`` in ``vemwear paper``'s output: ``example_5_N``."""
    return "example_" + name.replace(".", "_")


def num(v: Any, fmt: str = ".4e") -> str:
    """``v`` formatted, or ``-`` if it is missing or not finite."""
    try:
        x = float(v)
    except (TypeError, ValueError):
        return "-"
    return "-" if not math.isfinite(x) else format(x, fmt)


def yes(b: bool) -> str:
    """``yes``, or a bold ``no``."""
    return "yes" if b else "**no**"


def cell(text: str) -> str:
    """Escape the pipes of a Markdown table cell."""
    return text.replace("|", "\\|")


def table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    """A Markdown table as lines."""
    return [
        "| " + " | ".join(header) + " |",
        "|" + "---|" * len(header),
        *("| " + " | ".join(r) + " |" for r in rows),
    ]


def links(out: Path, sub: str, top_only: bool = False) -> list[str]:
    """Links to the figures under ``out/sub``: the example's own, then the runs' on one line."""
    d = out / sub
    figs = sorted(str(p.relative_to(out)) for p in d.rglob("*.png")) if d.is_dir() else []
    top = [f for f in figs if f.count("/") == 1]
    rest = [f for f in figs if f.count("/") > 1]
    lines = [f"- [{Path(f).name}]({f})" for f in top]
    if rest and not top_only:
        lines.append("- per run: " + ", ".join(f"[{f.split('/', 1)[1]}]({f})" for f in rest))
    return lines
