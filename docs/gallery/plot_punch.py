"""
A rounded punch from a gmsh file
================================

``punch.toml``: a rounded punch of radius 1, meshed by gmsh (``punch.msh``: 24 x 8
mapped quadrilaterals with the physical groups ``top``, ``sides`` and ``arc``), starts
out of contact (its initial gap y / (1 - y) is the height of the arc over its lowest
point), is pushed down by its top and slides on the coated foundation.

It shows a configuration file read from Python with an override, the gmsh groups as
boundary parts by name, and the wear concentrated under the lowest point, where the
punch touches first. Pinned: the largest wear at t = 1 with 16 steps.
Full size: ``vemwear run src/vemwear/examples/punch.toml -o OUTDIR``.
"""

import tomllib

import matplotlib.pyplot as plt

import vemwear
from vemwear.config import apply_overrides, parse_config
from vemwear.examples import config_path
from vemwear.mesh.plot import plot_mesh

path = config_path("punch")
data = apply_overrides(tomllib.loads(path.read_text(encoding="utf-8")), {"time.steps": 16})
cfg = parse_config(data, source=path.name, base_dir=path.parent)
print(cfg.problem.mesh)
result = vemwear.simulate(cfg.problem, cfg.solver)

# %%
# The mesh with its parts: ``contact`` on the arc, ``press`` on the top, ``free`` sides.
fig = plot_mesh(cfg.problem.mesh, title="punch.msh")

# %%
# Wear and contact pressure along the arc at t = 1: only the middle of the arc is in
# contact.
x = result.contact_points[:, 0]
order = x.argsort()
fig, ax = plt.subplots(figsize=(6.4, 3.2))
ax.plot(x[order], result.wear[-1][order], label="wear w(1)")
ax.plot(x[order], result.p_soft[-1][order], label="soft-layer pressure p(1)")
ax.set(xlabel="x on the arc", title="under the punch at t = 1")
ax.legend()
fig.tight_layout()

max_wear = float(result.wear[-1].max())
print(f"max w(1) = {max_wear:.6f} at x = {x[result.wear[-1].argmax()]:.3f}")
