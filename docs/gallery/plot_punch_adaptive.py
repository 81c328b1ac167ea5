"""
A punch on a mesh adapted for the wear
======================================

``punch_adaptive.toml``: the rounded punch of ``punch.toml`` on a mesh that adapts for
the wear. Every 4 time levels the wear is predicted at the final time from the level's
pressure, and the cells along the arc where that profile is least resolved are refined
(hanging nodes on their neighbours, new vertices on the arc) until its interpolation
error has fallen as one uniform refinement would make it fall; the wear moves to the new
contact nodes as a monotone cubic (docs/method.md section 11).

It shows the meshes the run went through, refined along the part of the arc that the
contact zone reaches and nowhere else, and the wear at t = 1 against the shipped 24 x 8
mesh and a uniform mesh with 16 times its cells: the adapted mesh follows the fine one
with a sixth of its dofs. Pinned: the largest wear at t = 1 with 16 steps.
Full size: ``vemwear run src/vemwear/examples/punch_adaptive.toml -o OUTDIR``.
"""

import tomllib
from pathlib import Path
from tempfile import TemporaryDirectory

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import PolyCollection

import vemwear
from vemwear.config import apply_overrides, parse_config
from vemwear.examples import config_path
from vemwear.examples.punch_mesh import punch_mesh
from vemwear.mesh import write_mesh
from vemwear.simulate import simulate_adaptive


def read(path: Path, base: Path):
    """The configuration at ``path`` with 16 time steps, its mesh file read from ``base``."""
    raw = apply_overrides(tomllib.loads(path.read_text(encoding="utf-8")), {"time.steps": 16})
    return parse_config(raw, source=path.name, base_dir=base)


path = config_path("punch_adaptive")
cfg = read(path, path.parent)
assert cfg.adapt is not None
segments = simulate_adaptive(cfg.problem, solver=cfg.solver, **vars(cfg.adapt))
print([s.problem.mesh.n_cells for s in segments], "cells")

# %%
# The first and the last mesh: the cells along the middle of the arc, where the punch
# wears, are refined; the rest of the body keeps its 24 x 8 cells.
fig, axes = plt.subplots(1, 2, figsize=(8.0, 2.6))
for ax, seg, name in zip(axes, (segments[0], segments[-1]), ("first", "last"), strict=True):
    mesh = seg.problem.mesh
    ax.add_collection(
        PolyCollection([mesh.points[c] for c in mesh.cells], facecolors="none", lw=0.3)
    )
    ax.set(aspect="equal", title=f"{name} mesh, {mesh.n_cells} cells")
    ax.autoscale_view()
    ax.axis("off")
fig.tight_layout()

# %%
# The wear at t = 1 along the arc: the adapted mesh against the shipped mesh and the
# uniform 96 x 32 mesh (written as a gmsh file with the same parts, read by the same
# configuration).
last = segments[-1].result
plain = vemwear.simulate(cfg.problem, cfg.solver)
with TemporaryDirectory() as tmp:
    write_mesh(punch_mesh(96, 32), Path(tmp) / "punch.msh")
    fine_cfg = read(config_path("punch"), Path(tmp))
    fine = vemwear.simulate(fine_cfg.problem, fine_cfg.solver)

fig, ax = plt.subplots(figsize=(6.4, 3.2))
for res, label in (
    (fine, f"uniform 96 x 32 ({fine_cfg.problem.space.n_dofs} dofs)"),
    (plain, f"uniform 24 x 8 ({cfg.problem.space.n_dofs} dofs)"),
    (last, f"adapted ({segments[-1].problem.space.n_dofs} dofs)"),
):
    x = res.contact_points[:, 0]
    order = x.argsort()
    ax.plot(x[order], res.wear[-1][order], label=label)
ax.set(xlim=(-0.3, 0.3), xlabel="x on the arc", ylabel="wear w(1)")
ax.legend(fontsize=8)
fig.tight_layout()

max_wear = float(np.max(last.wear[-1]))
print(f"max w(1) = {max_wear:.6f}")
