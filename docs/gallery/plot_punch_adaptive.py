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
with a sixth of its dofs. Then the same punch on a mesh made by whole runs first
(``punch_passes.toml``, ``[adapt] passes``): each pass solves the whole run and refines
for its wear at t = 1, and the last pass's mesh serves every level.
Pinned: the largest wear at t = 1 with 16 steps (the mesh that adapts in time).
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
from vemwear.simulate.adapt import adapt_passes


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

# %%
# Whole runs for the wear: ``punch_passes.toml`` solves the whole run on the shipped
# mesh, refines the cells along the arc for that run's wear at t = 1 until the estimate
# of its error reaches ``target_error``, and solves again; under a punch pressed down
# the contact zone only grows, so the last mesh is fine wherever any level needs it.
passes_cfg = read(config_path("punch_passes"), path.parent)
a = passes_cfg.adapt
assert a is not None
steps, _, _ = adapt_passes(passes_cfg.problem, a, a.passes)  # the [adapt] settings
print([s.problem.mesh.n_cells for s in steps], "cells", [f"{s.eta:.2e}" for s in steps])
fig, axes = plt.subplots(1, 2, figsize=(9.0, 3.4), width_ratios=[1.2, 1.0])
mesh = steps[-1].problem.mesh
axes[0].add_collection(
    PolyCollection([mesh.points[c] for c in mesh.cells], facecolors="none", lw=0.3)
)
axes[0].set(aspect="equal", title=f"after {len(steps) - 1} passes, {mesh.n_cells} cells")
axes[0].autoscale_view()
axes[0].axis("off")
for res, label in (
    (fine, "uniform 96 x 32"),
    (last, "adapted in time"),
    (steps[-1].result, f"whole runs ({steps[-1].n_dofs} dofs)"),
):
    x = res.contact_points[:, 0]
    order = x.argsort()
    axes[1].plot(x[order], res.wear[-1][order], label=label)
axes[1].set(xlim=(-0.3, 0.3), xlabel="x on the arc", ylabel="wear w(1)")
axes[1].legend(fontsize=8)
fig.tight_layout()

max_wear = float(np.max(last.wear[-1]))
print(f"max w(1) = {max_wear:.6f}")
