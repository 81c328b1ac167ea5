"""
A displacement-controlled block against its closed form
=======================================================

``block_displacement.toml``: a block on rollers (left and right sides held in x) whose
top is pushed down at the rate 0.08 over an initial gap 0.02 into a linear layer. Its
field is uniaxial, so the discrete wear has a closed form: contact starts at
t0 = gap / rate, and then w^{n+1} = w^n + k kappa k_s (rate t_n - gap - w^n)_+ with
the layer's effective stiffness k_s = c M / (M + c H), M = lam + 2 eta.

It shows the computed wear on the closed form, to round-off. Pinned: the largest
difference (below 1e-14). Full size: ``vemwear run
src/vemwear/examples/block_displacement.toml -o OUTDIR``.
"""

import tomllib

import matplotlib.pyplot as plt
import numpy as np

import vemwear
from vemwear.config import apply_overrides, parse_config
from vemwear.examples import config_path

path = config_path("block_displacement")
data = apply_overrides(tomllib.loads(path.read_text(encoding="utf-8")), {"time.steps": 16})
cfg = parse_config(data, source=path.name, base_dir=path.parent)
result = vemwear.simulate(cfg.problem, cfg.solver)

c, lam, eta, H, kappa, gap, rate = 0.4, 4.0, 4.0, 1.0, 2.0, 0.02, 0.08
M = lam + 2 * eta
ks = c * M / (M + c * H)
t = result.t
w = np.zeros(len(t))
for n in range(len(t) - 1):
    w[n + 1] = w[n] + (t[n + 1] - t[n]) * kappa * ks * max(rate * t[n] - gap - w[n], 0.0)

# %%
fig, ax = plt.subplots(figsize=(6.4, 3.2))
ax.plot(t, result.wear.max(axis=1), "o", label="vemwear, every contact node")
ax.plot(t, w, "k-", label="closed form")
ax.axvline(gap / rate, color="gray", lw=0.8, ls=":")
ax.set(xlabel="t", ylabel="wear", title="contact from t0 = gap / rate = 0.25")
ax.legend()
fig.tight_layout()

max_difference = float(np.abs(result.wear - w[:, None]).max())
print(f"largest difference to the closed form: {max_difference:.1e}")
