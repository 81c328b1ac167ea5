"""
An adaptive mesh that follows a moving load
===========================================

Example 5.2's body and coated foundation (lam = eta = 4, p(r) = 0.4 r+, g = 0.1,
mu = 0.2, kappa = 2, clamped at x = 0), without gravity, pressed by a traction on its top
that travels from x = 0.3 to x = 1.7 over T = 1:
f2 = (0, -0.3 exp(-((x - x0(t)) / 0.15)^2)). The mesh starts as 16 x 8 squares and
changes every 4 of the 32 time levels (docs/method.md, section 11): the residual
estimator marks the cells that carry half of eta^2 (Doerfler, theta = 0.5) and they are
split in four, leaving hanging nodes on their neighbours, graded to one level between
neighbours; families whose indicators are small are merged back; the wear moves to the
new contact nodes.

It shows the adaptive path of the library (:func:`vemwear.simulate.simulate_adaptive`)
on a problem whose singular zone moves: the finest cells stay under the load as it
travels, and the cells it has left are coarsened again, while the wear grows along
Gamma_C. Pinned: the largest wear at t = 1. The same run from a configuration file is an
``[adapt]`` table (docs/config.md; ``src/vemwear/examples/example_5_2_adaptive.toml``).
"""

import dataclasses

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import PolyCollection

from vemwear.paper import ex52
from vemwear.simulate import simulate_adaptive


def x0(t: float) -> float:
    """Where the load is at time t."""
    return 0.3 + 1.4 * t


def traction(x: np.ndarray, t: float) -> np.ndarray:
    """The travelling load on the top side (zero elsewhere)."""
    out = np.zeros((len(x), 2))
    out[:, 1] = -0.3 * np.exp(-(((x[:, 0] - x0(t)) / 0.15) ** 2)) * (x[:, 1] > 0.99)
    return out


base = ex52.problem(0.2, 2.0, divisions=(16, 8), steps=32)
problem = dataclasses.replace(base, f1=(0.0, 0.0), f2=traction)
segments = simulate_adaptive(problem, every=4, theta=0.5, coarsen=0.1, max_level=3)
for s in segments:
    t = float(s.problem.time.t[s.first])
    print(
        f"levels {s.first:2d}-{s.last:2d}: load at x = {x0(t):.2f}, {s.problem.mesh.n_cells} "
        f"cells, estimate {s.estimate.total:.3e}"
    )

# %%
# The meshes of four segments, with the load's centre (red): the refined cells travel
# with it, those it left behind are merged again.
fig, axes = plt.subplots(4, 1, figsize=(6.4, 11))
for ax, k in zip(axes, np.linspace(0, len(segments) - 1, 4).round().astype(int), strict=True):
    s = segments[k]
    mesh, t = s.problem.mesh, float(s.problem.time.t[s.first])
    cells = [mesh.points[c] for c in mesh.cells]
    ax.add_collection(PolyCollection(cells, facecolors="none", edgecolors="k", lw=0.4))
    ax.axvline(x0(t), color="tab:red", lw=1.0)
    ax.set(xlim=(0, 2), ylim=(0, 1), aspect="equal")
    ax.set_title(f"levels {s.first}-{s.last} (t = {t:.2f}): {mesh.n_cells} cells", fontsize=10)
fig.tight_layout()

# %%
# The wear along Gamma_C at the last level of each segment, on that segment's own contact
# nodes: it grows where the load has passed.
fig, ax = plt.subplots(figsize=(6.4, 3.2))
for s in segments[1::2]:
    x = s.result.contact_points[:, 0]
    order = x.argsort()
    ax.plot(x[order], s.result.wear[-1][order], label=f"t = {s.problem.time.t[s.last]:.2f}")
ax.set(xlabel="x on Gamma_C", ylabel="wear w")
ax.legend(fontsize=8)
fig.tight_layout()

max_wear = float(segments[-1].result.wear[-1].max())
print(f"largest wear at t = 1: {max_wear:.9g}")
