"""
Hertz contact under load control
================================

``vemwear example hertz``: a block with the initial gap of a cylinder of radius R is
pressed by a rigid holder with the force P on the rigid layer (no soft layer, Signorini
contact); the squares are refined towards the contact zone (hanging nodes). Hertz's
line contact gives the half-width a = sqrt(4 P R / (pi E*)) and the pressure
p0 sqrt(1 - x^2/a^2), p0 = 2 P / (pi a).

It shows the computed pressure on the closed form. Pinned: the relative error of the
half-width (from the pressure's second moment). The full example, with the 3D sphere
and the errors against refinement: ``vemwear example hertz -o OUTDIR``.
"""

import matplotlib.pyplot as plt
import numpy as np

import vemwear
from vemwear.paper.hertz import WIDTH, closed_form, line_contact, measure

a = 0.05
result = vemwear.simulate(line_contact(a, levels=6), "newton")
exact = closed_form(2, a)

# %%
x = result.contact_points[:, 0] - WIDTH / 2
near = np.abs(x) < 1.5 * a
xs = np.linspace(-1.5 * a, 1.5 * a, 301)
fig, ax = plt.subplots(figsize=(6.4, 3.2))
ax.plot(xs, exact["p0"] * np.sqrt(np.maximum(1 - xs**2 / a**2, 0)), "k-", label="Hertz")
ax.plot(x[near], result.p_rigid[-1][near], "o", ms=3, label="vemwear")
ax.set(xlabel="x", ylabel="contact pressure")
ax.legend()
fig.tight_layout()

errors = measure(result, a)
a_error = errors["a_err"]
print(f"half-width {100 * a_error:+.2f} %, peak {100 * errors['p0_err']:+.2f} %")
