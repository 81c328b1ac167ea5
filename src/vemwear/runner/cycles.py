"""``vemwear run`` of a configuration with ``[time] cycle_jump``: a long fretting history.

The run computes one cycle in every ``jump`` (:func:`vemwear.simulate.cycles.
simulate_cycles`) in memory and writes into OUTDIR the standard files of the last
computed cycle (``result.npz``, ``summary.json`` with the history, figures, ParaView),
``cycles.npz`` (the wear at the start of every jump) and ``wear_by_cycle.png``. Such a
run keeps only the wear between cycles, so it is not checkpointed: a stopped run
leaves nothing and is started again.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..util.atomic import atomic_file
from .outdir import write_marker
from .run import abandon_run, hold_lock

if TYPE_CHECKING:
    from ..simulate.cycles import CycleResult
    from ..simulate.loop import Result
    from .run import RunPlan

__all__ = ["CYCLES_NAME", "execute_cycles"]

#: The wear history of a cycle-jump run.
CYCLES_NAME = "cycles.npz"
FIGURE_NAME = "wear_by_cycle.png"


def execute_cycles(plan: RunPlan, *, progress: bool = True) -> tuple[Result, CycleResult]:
    """Run the cycles of ``plan.cfg`` and write the outputs into ``plan.out``."""
    from ..post.outputs import write_outputs
    from ..simulate.cycles import simulate_cycles

    cfg, out = plan.cfg, plan.out
    assert cfg.cycles is not None
    hold_lock(plan)
    with plan.lock:
        try:
            write_marker(out, "running", [], command="run")
            cres = simulate_cycles(cfg.problem, cfg.cycles, plan.solver, progress=progress)
            last = cres.last
            extra: dict[str, Any] = {
                "config": cfg.data,
                "config_path": str(plan.config_path.resolve()),
                "title": cfg.title,
                "inputs_sha256": plan.meta["inputs_sha256"],
                "cycles": {
                    "cycles": cfg.cycles.cycles,
                    "jump": cfg.cycles.jump,
                    "max_increment": cfg.cycles.max_increment,
                    "computed_cycles": len(cres.computed),
                    "jumps": cres.jumps,
                    "wear_max_final": float(cres.wear[-1].max(initial=0.0)),
                    "seconds": cres.seconds,
                },
            }
            times = [t for t in cfg.output.times if t <= float(last.t[-1])]
            written = write_outputs(
                last,
                out,
                times=times,
                figures=cfg.output.figures,
                vtk=cfg.output.vtk,
                extra=extra,
                paraview=cfg.output.paraview,
            )
            with atomic_file(out / CYCLES_NAME) as tmp, open(tmp, "wb") as fh:
                np.savez(
                    fh,
                    cycle=cres.cycle,
                    computed=cres.computed,
                    jumps=np.asarray(cres.jumps, dtype=np.int64),
                    wear=cres.wear,
                    contact_s=last.contact_s,
                    contact_points=last.contact_points,
                )
            files = [CYCLES_NAME, *(f.split("/")[0] for names in written.values() for f in names)]
            if cfg.output.figures:
                plot_wear_by_cycle(cres, out / FIGURE_NAME)
                files.append(FIGURE_NAME)
            write_marker(out, "complete", sorted(set(files)), command="run")
        except BaseException:
            abandon_run(plan)
            raise
    return last, cres


def plot_wear_by_cycle(cres: CycleResult, path: Any) -> None:
    """The wear along Gamma_C at up to eight cycle counts of the history."""
    from matplotlib import colormaps
    from matplotlib.figure import Figure

    last = cres.last
    x = np.asarray(last.contact_points)[:, 0]
    order = np.argsort(x, kind="stable")
    pick = np.unique(np.linspace(0, len(cres.cycle) - 1, min(8, len(cres.cycle))).astype(int))
    fig = Figure(figsize=(7.5, 4.2), layout="constrained")
    ax = fig.subplots()
    cmap = colormaps["viridis"]
    for j, i in enumerate(pick):
        ax.plot(
            x[order],
            cres.wear[i][order],
            color=cmap(0.85 - 0.85 * j / max(len(pick) - 1, 1)),
            lw=1.6,
            label=f"after {int(cres.cycle[i])} cycles",
        )
    ax.set_xlabel(r"$x_1$")
    ax.set_ylabel(r"wear $w$")
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.legend(loc="best", frameon=False, fontsize=8)
    ax.set_title("Wear scar, cycle by cycle")
    fig.savefig(path, dpi=150)
