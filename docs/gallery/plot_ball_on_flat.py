"""
A ball on a reciprocating flat: the wear scar widens
====================================================

``ball_on_flat.toml``: a ball of radius R = 2 (the initial gap (x^2 + y^2) / (2R)
over a block) is pressed by its holder with a dead load P ramped in over the first
tenth of the run, while a coated flat slides back and forth under it. Only contact
holds the ball vertically (load control).

It shows the width of the wear scar (the diameter of a disc of the worn zone's area,
where the wear exceeds 1 % of its largest value) against time, with the contact diameter of a rigid
ball pressed into the soft layer taken as a Winkler foundation, 2 a with
a = sqrt(2 R delta) and P = pi c R delta^2 (a reference for the start: the ball is
elastic, so its first contact is a little wider). As the scar flattens the ball the
pressure spreads and the scar widens. Pinned: the scar's width at T. Full size:
``vemwear run src/vemwear/examples/ball_on_flat.toml -o OUTDIR``.
"""

import tomllib

import matplotlib.pyplot as plt
import numpy as np

import vemwear
from vemwear.config import apply_overrides, parse_config
from vemwear.examples import config_path

path = config_path("ball_on_flat")
small = {"mesh.divisions": [12, 12, 6], "time.steps": 16}
data = apply_overrides(tomllib.loads(path.read_text(encoding="utf-8")), small)
cfg = parse_config(data, source=path.name, base_dir=path.parent)
result = vemwear.simulate(cfg.problem, cfg.solver, store="final")

# %%
# The scar's width at every level: the diameter of the disc of the worn area, the sum
# of the nodal weights w_i of the face where the wear exceeds 1 % of its largest value.
weights = cfg.problem.discrete.system.weights
worn = result.wear > 0.01 * result.wear.max(axis=1, keepdims=True)
width = 2 * np.sqrt((worn & (result.wear > 0)) @ weights / np.pi)
R, P, c = 2.0, 0.02, 4.0
delta = np.sqrt(P / (np.pi * c * R))
winkler = 2 * np.sqrt(2 * R * delta)

fig, ax = plt.subplots(figsize=(5.2, 3.4))
ax.plot(result.t, width, "o-", label="vemwear: scar width")
ax.axhline(winkler, color="k", ls="--", label="rigid ball on the layer (Winkler)")
ax.set(xlabel="t", ylabel="width of the wear scar", ylim=(0, None))
ax.legend(loc="lower right")
fig.tight_layout()

scar_width = float(width[-1])
print(f"scar width at T {scar_width:.6g}; Winkler contact diameter {winkler:.6g}")
