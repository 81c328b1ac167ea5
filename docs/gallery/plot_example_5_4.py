"""
Example 5.4: squares against Voronoi polygons
=============================================

The virtual element method runs on any polygonal mesh. Example 5.4 solves Example 5.2's
problem (data set 1) on squares (mesh A) and on centroidal Voronoi polygons (mesh B),
here 16 x 8 squares against 128 Voronoi cells, 16 steps.

It shows that the two meshes give nearly the same wear. Pinned: the largest wear at
t = 1 on the Voronoi mesh. Full size: ``vemwear example 5.4 -o OUTDIR`` (64 x 32
squares against 2048 polygons).
"""

import matplotlib.pyplot as plt

import vemwear
from vemwear.mesh.plot import plot_mesh
from vemwear.paper import ex54

problems = ex54.problems(divisions=(16, 8), n_cells=128, steps=16)
results = {name: vemwear.simulate(pr) for name, pr in problems.items()}

# %%
# Mesh B: 128 centroidal Voronoi cells, with its contact part at the bottom.
fig = plot_mesh(problems["voronoi"].mesh, title="mesh B: 128 Voronoi cells")

# %%
# The wear at t = 1 on both meshes.
fig, ax = plt.subplots(figsize=(6.4, 3.2))
for name, r in results.items():
    x = r.contact_points[:, 0]
    ax.plot(x[x.argsort()], r.wear[-1][x.argsort()], marker=".", label=name)
ax.set(xlabel="x on the contact boundary", ylabel="w(1)")
ax.legend()
fig.tight_layout()

max_wear_voronoi = float(results["voronoi"].wear[-1].max())
print(f"max w(1): squares {results['squares'].wear[-1].max():.6f}, Voronoi {max_wear_voronoi:.6f}")
