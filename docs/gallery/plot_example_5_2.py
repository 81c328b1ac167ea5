"""
Example 5.2: wear for three data sets
=====================================

The paper's Example 5.2 at a quarter of its size: an elastic block (0, 2) x (0, 1),
clamped on the left, pressed by its own weight onto a soft layer over a rigid
foundation that slides to the right. Three data sets: (mu, kappa) = (0.2, 2),
(0.2, 10), (0.6, 10).

It shows the paper's findings: the wear grows with kappa, and a larger friction
coefficient changes it only slightly. Pinned in ``tests/test_examples.py``: the
largest wear of data set 2 at t = 1 on 16 x 8 squares with 16 steps.
Full size: ``vemwear example 5.2 -o OUTDIR`` (32 x 16 squares, 64 steps).
"""

import matplotlib.pyplot as plt

import vemwear
from vemwear.paper import ex52

problems = ex52.problems(divisions=(16, 8), steps=16)
results = {name: vemwear.simulate(pr) for name, pr in problems.items()}

# %%
# The wear w along the contact boundary at four times, data set 2 (the paper's Fig. 4).
res = results["set2"]
x = res.contact_points[:, 0]
order = x.argsort()
fig, ax = plt.subplots(figsize=(6.4, 3.2))
for t in (0.25, 0.5, 0.75, 1.0):
    n = int(abs(res.t - t).argmin())
    ax.plot(x[order], res.wear[n][order], marker=".", label=f"t = {t:g}")
ax.set(
    xlabel="x on the contact boundary", ylabel="wear w", title="data set 2: mu = 0.2, kappa = 10"
)
ax.legend()
fig.tight_layout()

# %%
# The wear at t = 1 of the three data sets: kappa raises it, mu hardly changes it.
fig, ax = plt.subplots(figsize=(6.4, 3.2))
for name, r in results.items():
    ax.plot(x[order], r.wear[-1][order], label=name)
ax.set(xlabel="x on the contact boundary", ylabel="w(1)")
ax.legend()
fig.tight_layout()

max_wear = {name: float(r.wear[-1].max()) for name, r in results.items()}
print({name: round(w, 6) for name, w in max_wear.items()})
