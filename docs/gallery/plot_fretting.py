"""
Fretting: cycle jumps
=====================

``fretting.toml``: the punch held pressed down while the foundation moves back and
forth, v* = (cos 2 pi t, 0). The time grid is one cycle; ``[time] cycle_jump`` computes
one cycle in every ``jump`` and extrapolates the wear in between (docs/method.md,
section 6d). Here 12 cycles in jumps of 3 with 8 steps per cycle; the shipped file runs
100 cycles in jumps of 10 with 16 steps.

It shows the wear scar growing cycle by cycle. Pinned: the largest wear after 12
cycles. Full size: ``vemwear run src/vemwear/examples/fretting.toml -o OUTDIR``.
"""

import dataclasses
import tomllib

import matplotlib.pyplot as plt

from vemwear.config import apply_overrides, parse_config
from vemwear.examples import config_path
from vemwear.simulate.cycles import simulate_cycles

path = config_path("fretting")
data = apply_overrides(tomllib.loads(path.read_text(encoding="utf-8")), {"time.steps": 8})
cfg = parse_config(data, source=path.name, base_dir=path.parent)
assert cfg.cycles is not None
cycles = dataclasses.replace(cfg.cycles, cycles=12, jump=3)
run = simulate_cycles(cfg.problem, cycles, cfg.solver)
print("computed cycles:", run.computed.tolist(), "of", cycles.cycles)

# %%
x = run.last.contact_points[:, 0]
order = x.argsort()
fig, ax = plt.subplots(figsize=(6.4, 3.2))
for c, w in zip(run.cycle, run.wear, strict=True):
    if c:
        ax.plot(x[order], w[order], label=f"after {c} cycles")
ax.set(xlabel="x on the arc", ylabel="wear", title="the fretting scar", xlim=(-0.5, 0.5))
ax.legend(fontsize="small")
fig.tight_layout()

max_wear = float(run.wear[-1].max())
print(f"max wear after {run.cycle[-1]} cycles: {max_wear:.6f}")
