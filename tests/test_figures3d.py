"""The figures of a 3D run on their fixed layout: the content (panels, labels, colour
scales) and, drawn to PNG, no text outside the figure or over another text or panel."""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from matplotlib.figure import Figure
from matplotlib.text import Text

from conftest import CONFIG_3D
from vemwear.config import parse_config
from vemwear.post.forces import plot_forces
from vemwear.post.layout import place_grid, renderer
from vemwear.post.maps3d import MAP_QUANTITIES, plot_contact_line, plot_contact_maps
from vemwear.post.plots import plot_time_history
from vemwear.simulate import simulate

TIMES = [0.25, 0.5, 0.75, 1.0]


@pytest.fixture(scope="module")
def run3d() -> Any:
    import tomllib

    data = tomllib.loads(CONFIG_3D)
    return simulate(parse_config(data, source="c.toml", base_dir=Path(".")).problem, "newton")


def _tick_labels(ax: Any) -> tuple[list[Text], list[Text]]:
    """The tick labels an axes draws, and all its tick labels (ticks made for an earlier
    size stay in the axis, undrawn)."""
    drawn, every = [], []
    for axis in (ax.xaxis, ax.yaxis):
        lo, hi = sorted(axis.get_view_interval())
        eps = 1e-9 * max(hi - lo, 1e-300)
        locs = axis.get_majorticklocs()
        for tick in [*axis.majorTicks, *axis.minorTicks]:
            every += [tick.label1, tick.label2]
        for loc, tick in zip(locs, axis.get_major_ticks(len(locs)), strict=True):
            if lo - eps <= loc <= hi + eps:
                drawn += [x for x in (tick.label1, tick.label2) if x.get_visible()]
    return drawn, every


def _texts(fig: Figure) -> list[tuple[Text, Any]]:
    """The drawn, non-empty texts of a figure saved to PNG, with their extents (pixels)."""
    fig.savefig(io.BytesIO(), format="png", dpi=fig.dpi)
    r = renderer(fig)
    ticks, skip = [], set()
    for ax in fig.axes:
        drawn, every = _tick_labels(ax)
        ticks += drawn
        skip.update(map(id, every))
    others = [t for t in fig.findobj(Text) if id(t) not in skip and t.get_visible()]
    return [(t, t.get_window_extent(r)) for t in [*others, *ticks] if t.get_text().strip()]


def assert_laid_out(fig: Figure) -> None:
    """Every text inside the figure, on no other text, and on no panel but its own."""
    texts = _texts(fig)
    W, H = fig.bbox.width, fig.bbox.height
    for t, b in texts:
        assert b.x0 >= -0.5 and b.y0 >= -0.5 and b.x1 <= W + 0.5 and b.y1 <= H + 0.5, (
            f"{t.get_text()!r} clipped: {b} outside {W} x {H}"
        )
    r = renderer(fig)
    boxes = {ax: ax.get_window_extent(r) for ax in fig.axes}
    for t, b in texts:
        own = t.axes
        for ax, a in boxes.items():
            if ax is own or (own is not None and np.allclose(a.extents, boxes[own].extents)):
                continue  # its own panel, or a twin sharing it
            ov = b.intersection(b, a)
            assert ov is None or ov.width < 1 or ov.height < 1, f"{t.get_text()!r} on a panel"
    for i, (t, b) in enumerate(texts):
        for u, c in texts[i + 1 :]:
            ov = b.intersection(b, c)
            assert ov is None or ov.width < 1 or ov.height < 1, (
                f"{t.get_text()!r} overlaps {u.get_text()!r}"
            )


def test_contact_maps_content_and_layout(run3d: Any, tmp_path: Path) -> None:
    fig = plot_contact_maps(run3d, TIMES, tmp_path / "maps.png")
    assert (tmp_path / "maps.png").stat().st_size > 0
    assert fig.get_layout_engine() is None  # placed once, drawn once
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    bars = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"]
    assert len(panels) == 8 and len(bars) == 2
    for i, name in enumerate(("wear", "penetration")):
        V = np.asarray(getattr(run3d, name))[[run3d.level(t) for t in TIMES]]
        lo, hi = bars[i].get_ylim()
        assert lo == pytest.approx(V.min()) and hi == pytest.approx(V.max())  # one scale a row
        assert bars[i].get_ylabel() == MAP_QUANTITIES[name]
    row0, row1 = panels[:4], panels[4:]
    assert [ax.get_title() for ax in row0] == [f"$t$ = {t:.3g}" for t in TIMES]
    assert [ax.get_title() for ax in row1] == [ax.get_title() for ax in row0]
    assert [ax.get_xlabel() for ax in row1] == ["$x$"] * 4 and row0[0].get_ylabel() == "$y$"
    assert "Contact face" in fig.get_suptitle() and r"$\mu$ = 0.2" in fig.get_suptitle()
    assert_laid_out(fig)


@pytest.mark.parametrize("rows", [("wear",), tuple(MAP_QUANTITIES)])
def test_contact_maps_of_other_rows_and_one_time(run3d: Any, rows: tuple[str, ...]) -> None:
    fig = plot_contact_maps(run3d, [1.0], quantities=rows)
    assert len(fig.axes) == 2 * len(rows)
    assert_laid_out(fig)


def test_line_history_and_forces_layout(run3d: Any, tmp_path: Path) -> None:
    line = plot_contact_line(run3d, TIMES, tmp_path / "line.png")
    labels = [MAP_QUANTITIES[q] for q in ("wear", "penetration")]
    assert [ax.get_ylabel() for ax in line.axes] == labels
    assert all(len(ax.get_lines()) == 4 for ax in line.axes)
    hist = plot_time_history(run3d, tmp_path / "hist.png")
    assert len(hist.legends) == 1 and len(hist.legends[0].get_texts()) == 4
    forces = plot_forces(run3d, tmp_path / "forces.png")
    assert [ax.get_title() for ax in forces.axes] == [
        "contact parts: force of the layer on the body",
        "clamped and prescribed parts: reactions",
    ]
    for fig in (line, hist, forces):
        assert fig.get_layout_engine() is None
        assert_laid_out(fig)


def test_place_grid_keeps_long_labels_and_titles_apart() -> None:
    """Decorations of any size: a title of three lines, long tick labels, wide titles."""
    fig = Figure(dpi=100)
    axes = fig.subplots(2, 3)
    for k, ax in enumerate(axes.flat):
        ax.plot([0, 1], [0, 1e5 * (k + 1)])
        ax.set_title("a title wider than its panel, on purpose", y=1.0)
        ax.set_xlabel("x label")
        ax.set_ylabel("a y label\nof two lines")
    cax = [fig.add_axes((0, 0, 0.1, 0.1)) for _ in range(2)]
    for c in cax:
        c.set_ylabel("colour bar label")
        c.set_ylim(-1234.5, 98765.4)
    title = fig.suptitle("first line\nsecond line\nthird line")
    place_grid(fig, axes.tolist(), (1.5, 1.0), colorbars=cax, suptitle=title)
    assert_laid_out(fig)
    w, h = fig.get_size_inches()
    assert w > 3 * 1.5 and h > 2 * 1.0
