"""Figures and the report of a study: ``summary.png``, ``wear_profiles.png``, ``report.md``.

``summary.png`` shows each scalar summary (rows) against each axis (columns): for a grid,
one line per combination of the other axes; for the other designs, one point per run.
``wear_profiles.png`` overlays the wear at the final time along Gamma_C of every run,
coloured by the first axis. Figures are built with :class:`matplotlib.figure.Figure`
(no ``pyplot``, no display needed) and written atomically.
"""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..util.atomic import atomic_file, write_atomic

__all__ = ["PLOTTED", "plot_fit", "plot_profiles", "plot_summary", "write_report"]

#: The scalars of ``summary.png``.
PLOTTED = ("max_wear", "worn_volume", "max_p_soft", "iterations", "wall_time")
_MAX_LINES = 64
DPI = 120


def _axis_values(ds: Any, key: str) -> tuple[np.ndarray, list[str] | None]:
    """Numeric positions of an axis and tick labels if its values are not numbers."""
    v = np.asarray(ds[key].values)
    if v.dtype.kind in "biuf":
        return v.astype(float), None
    labels = [str(x) for x in v]
    uniq = list(dict.fromkeys(labels))
    return np.asarray([uniq.index(x) for x in labels], dtype=float), uniq


def _save(fig: Any, path: Path) -> Path:
    with atomic_file(path) as tmp:
        fig.savefig(tmp, dpi=DPI)
    return path


def plot_summary(ds: Any, path: str | Path) -> Path:
    """Each scalar of :data:`PLOTTED` against each axis, in one figure."""
    from matplotlib.figure import Figure

    keys: list[str] = json.loads(ds.attrs.get("axis_variables", ds.attrs["axes"]))
    grid = ds.attrs["design"] == "grid"
    rows, cols = len(PLOTTED), len(keys)
    fig = Figure(figsize=(3.6 * cols + 0.8, 2.2 * rows + 0.6), layout="constrained")
    axs = fig.subplots(rows, cols, squeeze=False)
    for j, key in enumerate(keys):
        x, labels = _axis_values(ds, key)
        for i, name in enumerate(PLOTTED):
            ax = axs[i][j]
            var = ds[name]
            if grid:
                others = [k for k in keys if k != key]
                combos = list(itertools.product(*(range(ds.sizes[k]) for k in others)))
                for c in combos[:_MAX_LINES]:
                    y = var.isel(dict(zip(others, c, strict=True))).values
                    lab = ", ".join(
                        f"{k}={ds[k].values[n]}" for k, n in zip(others, c, strict=True)
                    )
                    ax.plot(x, y, "o-", ms=3, label=lab or None)
                if others and len(combos) <= 8 and i == 0:
                    ax.legend(fontsize=6)
            else:
                ax.plot(x, var.values, "o", ms=3)
            if labels is not None:
                ax.set_xticks(range(len(labels)), labels, fontsize=7)
            if i == rows - 1:
                ax.set_xlabel(key)
            if j == 0:
                ax.set_ylabel(name)
            ax.grid(True, alpha=0.3)
    fig.suptitle(f"{ds.attrs['title']}: {ds.attrs['design']} design, {ds.attrs['runs']} runs")
    return _save(fig, Path(path))


def plot_profiles(ds: Any, path: str | Path) -> Path | None:
    """The wear at the final time along Gamma_C of every run (at most 64), overlaid."""
    if "wear" not in ds:
        return None
    from matplotlib import colormaps
    from matplotlib.figure import Figure

    keys: list[str] = json.loads(ds.attrs.get("axis_variables", ds.attrs["axes"]))
    dims = [d for d in ds["wear"].dims if d not in ("time", "s", "node")]
    w = ds["wear"].isel(time=-1).stack(_run=dims).transpose("_run", ...)
    first = np.asarray(ds[keys[0]].broadcast_like(ds["max_wear"]).stack(_run=dims).values)
    s = np.asarray(ds["s"].values)
    fig = Figure(figsize=(7.0, 4.2), layout="constrained")
    ax = fig.subplots()
    cmap = colormaps["viridis"]
    num = first.dtype.kind in "biuf"
    lo, hi = (float(np.nanmin(first)), float(np.nanmax(first))) if num else (0.0, 1.0)
    for n in range(min(w.shape[0], _MAX_LINES)):
        y = np.asarray(w.values[n])
        if not np.any(np.isfinite(y)):
            continue
        f = (float(first[n]) - lo) / (hi - lo) if num and hi > lo else n / max(w.shape[0], 1)
        ax.plot(s, y, color=cmap(f), lw=1.0, label=f"{keys[0]}={first[n]}" if n < 8 else None)
    ax.set_xlabel("arc length s along $\\Gamma_C$")
    ax.set_ylabel("wear $w$ at $T$")
    ax.set_title(f"{ds.attrs['title']}: wear at T (colour: {keys[0]})")
    ax.grid(True, alpha=0.3)
    if w.shape[0] <= 8:
        ax.legend(fontsize=7)
    return _save(fig, Path(path))


def _num(x: Any) -> str:
    try:
        v = float(x)
    except (TypeError, ValueError):
        return str(x)
    return "-" if math.isnan(v) else f"{v:.6g}"


def write_report(ds: Any, path: str | Path, figures: list[Path]) -> Path:
    """``report.md``: the design, the counts, a table of the runs, failures, figures."""
    keys: list[str] = json.loads(ds.attrs.get("axis_variables", ds.attrs["axes"]))
    dims = list(ds["max_wear"].dims)
    flat = ds.stack(_run=dims) if dims else ds
    cols = ["run", *keys, "status", "max_wear", "worn_volume", "max_p_soft", "iterations"]
    lines = [
        f"# Study: {ds.attrs['title']}",
        "",
        f"- design: {ds.attrs['design']}, {ds.attrs['runs']} runs over "
        + ", ".join(f"`{k}`" for k in keys),
        f"- this execution: {ds.attrs['runs_computed']} computed, {ds.attrs['runs_skipped']} "
        f"finished earlier, {ds.attrs['runs_failed']} failed",
        f"- base configuration: `{ds.attrs['base_config_file']}`",
        f"- vemwear {ds.attrs['vemwear_version']}, written {ds.attrs['created']}",
        "- the whole result: `study.nc` (xarray: `xarray.open_dataset('study.nc')`); each run's "
        "output in `runs/<run>/`, its configuration in `configs/<run>.toml`",
        "",
        "| " + " | ".join(cols) + " |",
        "|" + "---|" * len(cols),
    ]
    n = flat.sizes.get("_run", 1)
    failed = []
    for i in range(n):
        row = flat.isel(_run=i) if dims else flat
        vals = [str(row["run_id"].values), *(str(row[k].values) for k in keys)]
        vals.append(str(row["status"].values))
        vals += [_num(row[c].values) for c in cols[len(keys) + 2 :]]
        lines.append("| " + " | ".join(vals) + " |")
        if str(row["status"].values) != "done":
            failed.append(f"- `{row['run_id'].values}`: {row['error'].values}")
    if failed:
        lines += ["", "## Failed runs", "", *failed]
    if ds.attrs.get("profiles"):
        lines += ["", f"Profiles along Gamma_C: {ds.attrs['profiles']}."]
    lines += ["", "## Figures", ""]
    lines += [f"![{p.stem}]({p.name})" for p in figures]
    return write_atomic(path, "\n".join(lines) + "\n")


def plot_fit(res: Any, path: str | Path) -> Path:
    """Measured wear (markers) against the fitted model (lines) at each measured time,
    and the residuals."""
    from matplotlib import colormaps
    from matplotlib.figure import Figure

    m, prof = res.data, res.profiles
    a = prof["contact_points"][:, 0] if m.abscissa == "x" else prof["contact_s"]
    order = np.argsort(a, kind="stable")
    fig = Figure(figsize=(9.0, 3.8), layout="constrained")
    ax, axr = fig.subplots(1, 2)
    times = np.unique(m.t)
    cmap = colormaps["viridis"]
    for n, tu in enumerate(times):
        col = cmap(n / max(len(times) - 1, 1))
        sel = m.t == tu
        ax.plot(m.a[sel], m.w[sel], "o", ms=4, color=col, label=f"measured, t = {tu:g}")
        k = int(np.argmin(np.abs(prof["t"] - tu)))
        ax.plot(a[order], prof["wear"][k][order], "-", color=col, label=f"fitted, t = {tu:g}")
        axr.plot(m.a[sel], res.residuals[sel], "o", ms=4, color=col)
    est = ", ".join(
        f"{p} = {res.estimate[p]:.4g} [{res.interval[p][0]:.4g}, {res.interval[p][1]:.4g}]"
        for p in res.params
    )
    ax.set_title(f"fit: {est}", fontsize=9)
    ax.set_xlabel(m.abscissa)
    ax.set_ylabel("wear w")
    ax.legend(fontsize=7)
    ax.grid(True, alpha=0.3)
    axr.axhline(0.0, color="k", lw=0.8)
    axr.set_xlabel(m.abscissa)
    axr.set_ylabel("residual  w_model - w_measured")
    axr.grid(True, alpha=0.3)
    return _save(fig, Path(path))
