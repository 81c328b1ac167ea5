"""
3D: a box on the coated foundation
==================================

The 3D analogue of Section 5 with lowest-order virtual elements on polyhedra: the box
(0, 2) x (0, 1) x (0, 1) clamped at x = 0, contact on z = 0, its weight f1 = (0, 0,
-0.06), the foundation sliding along x; the paper's data (lam = eta = 4, p(r) = 0.4 r_+,
g = 0.1, mu = 0.2, kappa = 2). Here 8 x 4 x 4 hexahedra and 4 steps
(``example_3d.toml`` has 16 x 8 x 8 and 8 steps).

It shows the wear on the contact face at t = 1, largest away from the clamped edge.
Pinned: its maximum. Full size: ``vemwear example 3d -o OUTDIR`` (hexahedra and
Voronoi polyhedra).
"""

import matplotlib.pyplot as plt
from matplotlib.tri import Triangulation

import vemwear
from vemwear.mesh.generate3d import box_hexahedra
from vemwear.paper import ex3d

problem = ex3d.problem3d(box_hexahedra((2.0, 1.0, 1.0), (8, 4, 4)), steps=4)
print(f"{problem.mesh.n_cells} hexahedra, {len(problem.time.t) - 1} steps")
result = vemwear.simulate(problem)

# %%
# The wear on the contact face z = 0 (0 on the clamped edge x = 0).
xy, w = ex3d.face_wear(result)
fig, ax = plt.subplots(figsize=(6.4, 3.4))
tri = Triangulation(xy[:, 0], xy[:, 1])
cs = ax.tricontourf(tri, w, levels=12, cmap="viridis")
fig.colorbar(cs, ax=ax, label="w(1)")
ax.set(xlabel="x", ylabel="y", aspect="equal", title="wear on the contact face, t = 1")
fig.tight_layout()

max_wear = float(result.wear[-1].max())
print(f"max w(1) = {max_wear:.6f}")
