"""
Example 5.5: errors and convergence orders
==========================================

Example 5.5 measures the errors of h = k = 1/4, 1/8, 1/16 against a fine reference
solution (the paper's Tables 1 and 2, whose reference is h = k = 1/256; here 1/32):
the displacement in the H1 norm of its projection, the wear in L2 along the contact
boundary, both relative, at t = 1.

It shows first-order convergence of both (the order of the left-rectangle wear update
with k = h). Pinned: the order of the wear error between h = 1/8 and 1/16. Full size:
``vemwear example 5.5 -o OUTDIR``.
"""

import matplotlib.pyplot as plt
import numpy as np

import vemwear
from vemwear.paper import ex55_reference
from vemwear.post.compare import Comparison

levels = (4, 8, 16)
reference = vemwear.simulate(ex55_reference.problem(32), store=[0.25, 0.5, 0.75, 1.0])
compare = Comparison(reference)
errors = {n: compare.errors(vemwear.simulate(ex55_reference.problem(n))) for n in levels}

u_err = np.array([errors[n].at_T("displacement") for n in levels])
w_err = np.array([errors[n].at_T("wear") for n in levels])
orders = np.log2(w_err[:-1] / w_err[1:])
for n, eu, ew in zip(levels, u_err, w_err, strict=True):
    print(f"h = k = 1/{n:<3d} displacement {eu:.3e}   wear {ew:.3e}")
print("orders of the wear error:", np.round(orders, 2))

# %%
h = 1.0 / np.array(levels)
fig, ax = plt.subplots(figsize=(5.0, 3.6))
ax.loglog(h, u_err, "o-", label="displacement, H1")
ax.loglog(h, w_err, "s-", label="wear, L2 on the contact boundary")
ax.loglog(h, w_err[0] * h / h[0], "k--", lw=0.8, label="order 1")
ax.set(xlabel="h = k", ylabel="relative error at t = 1", title="against h = k = 1/32")
ax.legend()
fig.tight_layout()

wear_order = float(orders[-1])
