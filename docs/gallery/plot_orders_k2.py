"""
Second order: k = 1 against k = 2
=================================

Example 5.5's setting solved with virtual elements of order k = 1 and k = 2 on
h = 1/2, 1/4, 1/8, every run on the time grid of the reference (16 steps), against a
reference k = 2 on h = 1/16 (docs/method.md, section 9). With the time step fixed, the
difference is the space error.

It shows the displacement error against the number of unknowns: at equal cost (306
unknowns) k = 2 is the more accurate; the corner singularity at the clamped side
limits both orders. Pinned: the relative H1 error of k = 2 on h = 1/4. Full size:
``vemwear example orders -o OUTDIR``.
"""

import matplotlib.pyplot as plt

from vemwear.paper.orders import orders_study

study = orders_study(levels={1: [2, 4, 8], 2: [2, 4, 8]}, reference=16, small_steps=16, repeats=1)
rows = [r for r in study["rows"] if r["setting"] == "k small"]
for r in rows:
    print(
        f"k = {r['order']}  h = 1/{r['inv_h']:<2d}  dofs {r['dofs']:4d}  "
        f"u H1 {r['u_H1']:.3e}  w L2 {r['w_L2']:.3e}"
    )

# %%
fig, ax = plt.subplots(figsize=(5.0, 3.6))
for k, marker in ((1, "o"), (2, "s")):
    mine = [r for r in rows if r["order"] == k]
    ax.loglog([r["dofs"] for r in mine], [r["u_H1"] for r in mine], marker + "-", label=f"k = {k}")
ax.set(xlabel="unknowns", ylabel="relative H1 error of u at t = 1")
ax.legend()
fig.tight_layout()

u_error_k2_h4 = next(r["u_H1"] for r in rows if r["order"] == 2 and r["inv_h"] == 4)
