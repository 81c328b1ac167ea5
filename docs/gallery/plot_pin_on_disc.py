"""
A pin on a turning disc under a dead load
=========================================

``pin_on_disc.toml``: a cylindrical pin of Voronoi prisms is pressed by its holder
(a ``[[boundary.rigid]]`` part) with a dead load ramped in over the first tenth of the
run, onto a coated disc turning about the axis x = -1, y = 0. Only contact holds the
pin vertically (load control); the holder carries the load and the friction.

It shows the wear over the pin's face at the last level: the side farther from the
disc's axis slides faster and wears more. Then the worn volume against the sliding
distance of the pin's centre, with Archard's law V = kappa P s: under load control the
contact forces are the dead load P at every level, so the volume grows linearly with
the distance (the first level wears nothing, as the explicit step starts from P = 0)
until the coating is worn through at the outer edge: the rigid layer then carries part
of the load, which wears nothing, and the volume falls below Archard's line.
Pinned: the largest wear at T. Full size:
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

# %%
# The worn volume, sum of w_i wear_i (the nodal weights of the face), against the
# sliding distance of the pin's centre, s = omega r_c t (r_c = 1, omega = 1).
weights = cfg.problem.discrete.system.weights
volume = result.wear @ weights
distance = 1.0 * 1.0 * result.t
load = 0.02 * np.minimum(result.t / 0.1, 1.0)
step = np.diff(result.t, prepend=0.0)
archard = 0.5 * np.concatenate([[0.0], np.cumsum(load[:-1] * step[1:])])  # kappa = 0.5
fig, ax = plt.subplots(figsize=(5.0, 3.4))
ax.plot(distance, volume, "o-", label="vemwear")
ax.plot(distance, archard, "k--", label="Archard, V = kappa P s (explicit steps)")
ax.set(xlabel="sliding distance of the pin's centre", ylabel="worn volume")
ax.legend()
fig.tight_layout()
on_rigid = result.p_rigid @ weights  # the load the rigid layer carries
print(f"worn volume at T {volume[-1]:.6g}, Archard's {archard[-1]:.6g}; on the rigid layer")
print(np.round(on_rigid, 5))
