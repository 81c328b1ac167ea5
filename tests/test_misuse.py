"""A new user's misuse: each ends in one line naming the real cause, before any work.

Run in-process through :func:`vemwear.cli.main.main`, as ``vemwear ...`` would.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from conftest import small_config
from vemwear.cli.main import main

OFF = {"figures": False, "vtk": False}


def _err(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return err


# ---------------------------------------------------------------------------- encodings
@pytest.mark.parametrize(
    ("data", "where"),
    [
        (
            'title = "x"\n'.encode("utf-16"),
            "a UTF-16 (little-endian) byte-order mark at byte offset 0",
        ),
        (b'title = "caf\xe9"\n[mesh]\n', "byte 0xe9 at byte offset 12 (line 1)"),
        (b'title = "x"\n\n\x80\x81\x82', "byte 0x80 at byte offset 13 (line 3)"),
    ],
    ids=["utf-16", "latin-1", "binary"],
)
def test_a_config_that_is_not_utf8_is_exit_2_with_the_byte_offset(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], data: bytes, where: str
) -> None:
    cfg = tmp_path / "case.toml"
    cfg.write_bytes(data)
    for cmd in (["run", str(cfg), "-o", str(tmp_path / "out")], ["check", str(cfg)]):
        assert main(cmd) == 2
        assert (
            _err(capsys)
            == f"vemwear: error: {cfg}: not UTF-8 text: {where}; save the file as UTF-8\n"
        )
    assert not (tmp_path / "out").exists()
    study = tmp_path / "study.toml"
    study.write_bytes(data)
    assert main(["sweep", str(study), "-o", str(tmp_path / "sw")]) == 2
    assert f"{study}: not UTF-8 text: {where}" in _err(capsys)
    good = tmp_path / "good.toml"
    good.write_text(small_config("good", output=OFF))
    csv = tmp_path / "data.csv"
    csv.write_bytes(data)
    assert main(["fit", str(good), "--data", str(csv)]) == 2
    assert f"{csv}: not UTF-8 text: {where}" in _err(capsys)
    # a UTF-8 byte-order mark is fine
    good.write_bytes(b"\xef\xbb\xbf" + good.read_bytes())
    assert main(["check", str(good)]) == 0
