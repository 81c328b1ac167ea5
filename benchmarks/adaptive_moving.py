"""An adaptive run whose contact zone moves: the mesh follows it (docs/method.md,
section 11).

Example 5.2's body and layer (lam = eta = 4, p(r) = 0.4 r+, g = 0.1, mu = 0.2,
kappa = 2, clamped at x = 0) without gravity, pressed by a traction on its top that moves
from x = 0.3 to x = 1.7 over T = 1, f2 = (0, -0.3 exp(-((x - x0(t)) / 0.15)^2)): the
pressure on Gamma_C and the wear follow the load. The mesh starts as 16 x 8 squares and
changes every ``--every`` levels (theta = 0.5, coarsening fraction ``--coarsen``, cells at
most 3 levels finer); the table gives, per segment, its levels, cells, dofs, the
estimate at its last level, the largest wear, the refinement level of the cell under the
load (on the top side) and of the cell where the load started (x = 0.3, top); the
figure (``--figure``) draws the mesh of four segments with the load's position.

Usage::

    python benchmarks/adaptive_moving.py --figure adaptive_moving.png
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from vemwear.mesh.locate import locate_cells
from vemwear.paper import ex52
from vemwear.simulate import Problem
from vemwear.simulate.adaptive_time import simulate_adaptive


def centre(t: float) -> float:
    return 0.3 + 1.4 * t


def load(x: np.ndarray, t: float) -> np.ndarray:
    out = np.zeros((len(x), 2))
    out[:, 1] = -0.3 * np.exp(-(((x[:, 0] - centre(t)) / 0.15) ** 2)) * (x[:, 1] > 0.99)
    return out


def problem(steps: int) -> Problem:
    base = ex52.problem(0.2, 2.0, divisions=(16, 8), steps=steps)
    return dataclasses.replace(base, f1=(0.0, 0.0), f2=load)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=32)
    ap.add_argument("--every", type=int, default=4)
    ap.add_argument("--coarsen", type=float, default=0.1)
    ap.add_argument("--figure", default=None, help="PNG of the meshes of four segments")
    args = ap.parse_args()
    segs = simulate_adaptive(
        problem(args.steps), every=args.every, theta=0.5, coarsen=args.coarsen, max_level=3
    )
    print(
        "| levels | t | load at | cells | dofs | estimate | max wear | level under load | level at 0.3 |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for s in segs:
        m = s.problem.mesh
        t = float(s.problem.time.t[s.first])
        under, start = s.tree.level[locate_cells(m, np.array([[centre(t), 0.99], [0.3, 0.99]]))]
        print(
            f"| {s.first}-{s.last} | {t:.3f} | {centre(t):.2f} | {m.n_cells} | "
            f"{s.problem.space.n_dofs} | {s.estimate.total:.3e} | "
            f"{s.result.wear[-1].max():.3e} | {under} | {start} |"
        )
    if args.figure:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.collections import PolyCollection

        pick = np.linspace(0, len(segs) - 1, 4).round().astype(int)
        fig, axes = plt.subplots(4, 1, figsize=(7, 12))
        for ax, k in zip(axes, pick, strict=True):
            s = segs[k]
            m = s.problem.mesh
            polys = [m.points[c] for c in m.cells]
            ax.add_collection(PolyCollection(polys, facecolors="none", edgecolors="k", lw=0.4))
            t = float(s.problem.time.t[s.first])
            ax.axvline(centre(t), color="tab:red", lw=1.0)
            ax.set_xlim(0, 2)
            ax.set_ylim(0, 1)
            ax.set_aspect("equal")
            ax.set_title(f"levels {s.first}-{s.last} (t = {t:.2f}): {m.n_cells} cells")
        fig.tight_layout()
        fig.savefig(args.figure, dpi=120)
        print(f"\nwrote {args.figure}")


if __name__ == "__main__":
    main()
