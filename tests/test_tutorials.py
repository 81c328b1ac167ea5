"""The tutorials of the documentation site (docs/tutorials/*.md) run as written: the
``python`` blocks of each page, in order, in one namespace, in a fresh directory (blocks
marked ``py`` are shown but not run: they need a batch system)."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

TUTORIALS = Path(__file__).resolve().parents[1] / "docs" / "tutorials"
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)


def _pages() -> list[str]:
    return sorted(p.name for p in TUTORIALS.glob("*.md") if BLOCK.search(p.read_text("utf-8")))


def test_the_tutorials_are_in_their_index() -> None:
    index = (TUTORIALS / "index.md").read_text(encoding="utf-8")
    pages = {p.stem for p in TUTORIALS.glob("*.md")} - {"index"}
    assert pages and all(f"\n{p}\n" in index for p in pages)
    assert set(_pages()) >= {"first-run.md", "own-problem.md", "results.md", "three-d.md"}


@pytest.mark.parametrize("page", _pages())
def test_tutorial_runs(page: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    monkeypatch.chdir(tmp_path)
    # the command-line runs of a page (python -m vemwear) import this checkout too
    src = str(Path(__file__).resolve().parents[1] / "src")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([src, os.environ.get("PYTHONPATH", "")]))
    namespace: dict[str, object] = {"__name__": "__main__"}
    try:
        for n, block in enumerate(BLOCK.findall((TUTORIALS / page).read_text("utf-8"))):
            exec(compile(block, f"{page} block {n + 1}", "exec"), namespace)
    finally:
        plt.close("all")
