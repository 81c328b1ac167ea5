"""Running a validated configuration: the output directory, partial results, resume.

The layer between the clients (``vemwear`` command, the paper's examples) and the
library: it takes a :class:`vemwear.config.Config`, checks where the run writes,
solves it with :func:`vemwear.simulate.simulate`, writes the standard files through
:func:`vemwear.post.outputs.write_outputs`, keeps the finished levels of a stopped
run and resumes it.

- :mod:`~vemwear.runner.outdir`: the output directory (checks, atomic writing).
- :mod:`~vemwear.runner.run`: :func:`prepare_run`, :func:`execute_run`, partial
  results and ``--resume``.
- :mod:`~vemwear.runner.signals`: SIGTERM and SIGHUP like Ctrl-C; protected saves.
- :mod:`~vemwear.runner.describe`: what ``check`` and ``run`` report.

Names are imported on first use, so that importing the package stays cheap.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..util.lazy import lazy_names

if TYPE_CHECKING:
    from .describe import check_rows, result_rows, smallness_report
    from .entry import RunOutcome, run_config
    from .outdir import OutputDirError, atomic_output_dir, check_output_dir
    from .run import ResumeError, RunPlan, abandon_run, execute_run, prepare_run
    from .signals import Terminated, signals_as_interrupts

_WHERE = {
    "RunOutcome": "entry",
    "run_config": "entry",
    "check_rows": "describe",
    "result_rows": "describe",
    "smallness_report": "describe",
    "OutputDirError": "outdir",
    "atomic_output_dir": "outdir",
    "check_output_dir": "outdir",
    "ResumeError": "run",
    "RunPlan": "run",
    "execute_run": "run",
    "abandon_run": "run",
    "prepare_run": "run",
    "Terminated": "signals",
    "signals_as_interrupts": "signals",
}
__all__ = [
    "OutputDirError",
    "ResumeError",
    "RunOutcome",
    "RunPlan",
    "Terminated",
    "abandon_run",
    "atomic_output_dir",
    "check_output_dir",
    "check_rows",
    "execute_run",
    "prepare_run",
    "result_rows",
    "run_config",
    "signals_as_interrupts",
    "smallness_report",
]


__getattr__, __dir__ = lazy_names(__name__, {k: f".{v}" for k, v in _WHERE.items()})
