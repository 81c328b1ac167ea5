"""
A parameter study on a LocalCluster
===================================

``sweep_kappa_mu.toml``: Example 5.2's data set 1 over the wear coefficient kappa = 2,
5, 10 and the friction coefficient mu = 0.2, 0.6 (a grid of 3 x 2 runs on 16 x 8
squares), run as Dask tasks on a ``LocalCluster`` of two workers that the script
starts itself, as on a workstation; ``Client(address)`` of a cluster's scheduler works
the same way (docs/studies.md, "On a cluster").

It shows the study's result, one xarray Dataset with a dimension per axis, and its
finding: the maximal wear grows with kappa, nearly independently of mu. Pinned: the
maximal wear of kappa = 10, mu = 0.2. The command: ``vemwear sweep
src/vemwear/examples/sweep_kappa_mu.toml -o OUTDIR``.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
from distributed import Client, LocalCluster

from vemwear.examples import config_path
from vemwear.studies import sweep


def run_study(out: Path):
    """The study on a LocalCluster of two worker processes, one thread each."""
    with (
        LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster,
        Client(cluster) as client,
    ):
        return sweep(
            config_path("sweep_kappa_mu"),
            out,
            client=client,
            progress=False,
            say=None,
            figures=False,
        )


# %%
# The worker processes of a LocalCluster import the script that starts it (Python's
# "spawn"), so a script starts its cluster under ``if __name__ == "__main__":``.
# The largest wear at t = 1 over kappa, one line per mu:
if __name__ == "__main__":
    ds = run_study(Path(tempfile.mkdtemp()) / "sweep")
    print(ds)
    fig, ax = plt.subplots(figsize=(5.0, 3.4))
    for mu in ds["contact_mu"].values:
        sel = ds["max_wear"].sel({"contact_mu": mu})
        ax.plot(ds["contact_kappa"], sel, "o-", label=f"mu = {mu:g}")
    ax.set(xlabel="kappa", ylabel="max w(1)", title="study.nc: max_wear")
    ax.legend()
    fig.tight_layout()

    max_wear = float(ds["max_wear"].sel({"contact_kappa": 10.0, "contact_mu": 0.2}))
    print(f"max wear at kappa = 10, mu = 0.2: {max_wear:.6f}")
