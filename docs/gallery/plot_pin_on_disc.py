"""
A pin on a turning disc under a dead load
=========================================

``pin_on_disc.toml``: a cylindrical pin of Voronoi prisms is pressed by its holder
(a ``[[boundary.rigid]]`` part) with a dead load ramped in over the first tenth of the
run, onto a coated disc turning about the axis x = -1, y = 0. Only contact holds the
pin vertically (load control); the holder carries the load and the friction.

It shows the wear over the pin's face at the last level: the side farther from the
disc's axis slides faster and wears more. Pinned: the largest wear at T. Full size:
``vemwear run src/vemwear/examples/pin_on_disc.toml -o OUTDIR``.
"""

import tomllib

import matplotlib.pyplot as plt
import numpy as np

import vemwear
from vemwear.config import apply_overrides, parse_config
from vemwear.examples import config_path

path = config_path("pin_on_disc")
data = apply_overrides(tomllib.loads(path.read_text(encoding="utf-8")), {"time.steps": 8})
cfg = parse_config(data, source=path.name, base_dir=path.parent)
result = vemwear.simulate(cfg.problem, cfg.solver, store="final")

# %%
x, y = result.contact_points[:, 0], result.contact_points[:, 1]
fig, ax = plt.subplots(figsize=(5.0, 4.2))
art = ax.tricontourf(x, y, result.wear[-1], levels=12)
fig.colorbar(art, ax=ax, label="wear at T")
ax.set(xlabel="x", ylabel="y", aspect="equal", title="the disc's axis is at x = -1")
fig.tight_layout()

max_wear = float(result.wear[-1].max())
holder = result.forces[-1, -1]
print(f"max wear at T {max_wear:.6g}; the holder's force {np.round(holder, 6)}")
