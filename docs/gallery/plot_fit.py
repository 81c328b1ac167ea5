"""
Calibrating kappa from measured wear
====================================

``vemwear.studies.fit`` (the command ``vemwear fit``) calibrates the wear coefficient
kappa (and optionally mu, c, g) against measured wear profiles by bounded least
squares, its finite-difference runs in parallel on Dask. Here the "measurements" are
made by vemwear itself with kappa = 5 and 2 % noise, at t = 0.5 and 1; the fit starts
from the configuration's kappa = 2 and runs on a ``LocalCluster`` of two workers.

It shows the estimate with its 95 % confidence interval, and the fitted profiles over
the data. Pinned: the estimated kappa, within its interval around 5.
"""

import tempfile
import tomllib
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from distributed import Client, LocalCluster

import vemwear
from vemwear.config import apply_overrides, parse_config
from vemwear.examples import config_path
from vemwear.studies import fit


def measurements(work: Path) -> Path:
    """A small configuration (kappa = 2) and profiles measured with kappa = 5, with 2 %
    multiplicative noise, at t = 0.5 and 1."""
    text = config_path("example_5_2_set1").read_text(encoding="utf-8")
    text = text.replace("divisions = [32, 16]", "divisions = [16, 8]")
    text = text.replace("steps = 64", "steps = 16")
    (work / "case.toml").write_text(text, encoding="utf-8")
    truth = parse_config(apply_overrides(tomllib.loads(text), {"contact.kappa": 5.0}))
    res = vemwear.simulate(truth.problem)
    x = res.contact_points[:, 0]
    rng = np.random.default_rng(0)
    rows = ["x,t,w"]
    for n in (8, 16):
        w = res.wear[n] * (1 + 0.02 * rng.standard_normal(x.size))
        rows += [f"{a:.17g},{res.t[n]:.17g},{b:.17g}" for a, b in zip(x, w, strict=True)]
    (work / "measured.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    return work / "measured.csv"


# %%
# The fit runs on the user's own cluster: two worker processes, one thread each. Its
# workers import the script that starts them (Python's "spawn"), hence the guard.
if __name__ == "__main__":
    work = Path(tempfile.mkdtemp())
    csv = measurements(work)
    with (
        LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster,
        Client(cluster) as client,
    ):
        result = fit(work / "case.toml", csv, ["kappa"], client=client)
    kappa = result.estimate["kappa"]
    lo, hi = result.interval["kappa"]
    print(f"kappa = {kappa:.4f}, 95 % interval [{lo:.4f}, {hi:.4f}] (started at 2)")

    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    fig, ax = plt.subplots(figsize=(6.4, 3.2))
    for t, color in ((0.5, "C0"), (1.0, "C1")):
        on = data[:, 1] == t
        order = data[on, 0].argsort()
        ax.plot(data[on, 0], data[on, 2], ".", color=color, label=f"measured, t = {t:g}")
        ax.plot(data[on, 0][order], result.fitted[on][order], "-", color=color, label="fitted")
    ax.set(xlabel="x on the contact boundary", ylabel="wear", title=f"kappa = {kappa:.3f}")
    ax.legend(fontsize="small")
    fig.tight_layout()
