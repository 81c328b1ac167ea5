"""The README's Python example runs as written (in a temporary directory)."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_python_example_runs(tmp_path, monkeypatch):
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)
    assert blocks, "the README has no Python example"
    monkeypatch.chdir(tmp_path)
    ns: dict = {}
    exec(compile(blocks[0], "README.md", "exec"), ns)  # the documented example itself
    result = ns["result"]
    assert result.residuals.max() <= 1e-10
    assert (tmp_path / "out" / "result.npz").exists()
    assert (tmp_path / "out" / "profiles.png").stat().st_size > 0


def test_readme_config_example_is_valid(tmp_path):
    from vemwear.cli.main import main

    blocks = re.findall(r"```toml\n(.*?)```", README.read_text(), re.S)
    assert blocks, "the README has no config example"
    cfg = tmp_path / "readme.toml"
    cfg.write_text(blocks[0])
    assert main(["check", str(cfg)]) == 0
