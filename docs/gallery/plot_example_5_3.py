"""
Example 5.3: four time partitions
=================================

The data of Example 5.2, data set 1, on four time grids of [0, 1]: uniform steps k, an
alternating grid k/2, 3k/2, and the uniform steps 2k and 4k (the paper's Fig. 6, with
k = 1/16 instead of 1/64 and 16 x 8 squares).

It shows that the wear at t = 1 barely depends on the partition, and that its change
is first order in the step (the left-rectangle rule). Pinned: the largest difference
of w(1) between the grids 4k and k. Full size: ``vemwear example 5.3 -o OUTDIR``.
"""

import matplotlib.pyplot as plt
import numpy as np

import vemwear
from vemwear.paper import ex53

labels = {name: label for name, (label, _) in ex53.time_grids(16).items()}
results = {
    name: vemwear.simulate(pr)
    for name, pr in ex53.problems(divisions=(16, 8), base_steps=16).items()
}

x = results["k64"].contact_points[:, 0]
order = x.argsort()
fig, ax = plt.subplots(figsize=(6.4, 3.2))
for name, r in results.items():
    ax.plot(x[order], r.wear[-1][order], label=labels[name])
ax.set(xlabel="x on the contact boundary", ylabel="w(1)", title="w(1) on four time grids")
ax.legend()
fig.tight_layout()

# %%
# The differences to the grid k = 1/16 grow with the step (first order: the grid
# 1/8 has half the error of 1/4 against the exact solution in time).
diff = {
    name: float(np.abs(r.wear[-1] - results["k64"].wear[-1]).max()) for name, r in results.items()
}
print({labels[n]: f"{d:.2e}" for n, d in diff.items()})
max_difference = diff["k16"]
