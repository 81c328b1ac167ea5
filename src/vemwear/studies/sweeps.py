"""``sweep``: a whole study, from the study file to ``study.nc``, figures and report."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from .design import Study, load_study

__all__ = ["sweep"]


def _stderr(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def sweep(
    study: str | os.PathLike[str] | Mapping[str, Any] | Study,
    out: str | os.PathLike[str],
    client: Any = None,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    progress: bool = True,
    retries: int = 1,
    chunk: int | None = None,
    figures: bool = True,
    say: Callable[[str], None] | None = _stderr,
) -> Any:
    """Run a parameter study on Dask and return its Dataset.

    Every run is validated before any starts. The runs not yet complete in ``out``
    (from an earlier, stopped execution) are run as Dask tasks, each into
    ``out/runs/<id>``; the Dataset is written to ``out/study.nc``, with
    ``out/summary.png``, ``out/wear_profiles.png`` and ``out/report.md``.

    Parameters
    ----------
    study : path, mapping or Study
        The study file (docs/studies.md), its data, or a loaded :class:`Study`.
    out : path
        The study's output directory: new, empty, or one an earlier sweep wrote (its
        finished runs are skipped).
    client : distributed.Client, optional
        A client of the user's own cluster; it is left open.
    scheduler : str, optional
        Without ``client``: the address of a running Dask scheduler.
    workers : int, optional
        Without ``client`` and ``scheduler``: the workers of the embedded
        ``LocalCluster`` (default: one per core, one thread each).
    progress : bool
        Show a progress bar over the runs.
    retries : int
        Retries of a failed run before it is recorded as failed (default 1).
    chunk : int, optional
        Runs per Dask task (default: at least four tasks per worker thread, at most 16
        runs per task; :func:`vemwear.studies.execute.chunk_size`).
    figures : bool
        Write the figures and the report.
    say : callable or None
        Where the dashboard's address goes (standard error by default).

    Returns
    -------
    xarray.Dataset
        See :mod:`vemwear.studies.dataset`; ``attrs["runs_failed"]`` counts the failures.

    Raises
    ------
    StudyError
        An invalid study or run (before any run starts).
    OutputDirError
        An output directory that cannot be used.
    """
    from ..runner.outdir import output_lock, read_marker, write_marker
    from .dataset import STUDY_NC, build_dataset, run_arrays, write_dataset
    from .execute import run_all, study_client
    from .layout import CONFIGS_DIR, LOG_DIR, open_study_dir, remove_temporaries

    st = study if isinstance(study, Study) else load_study(study)
    outdir = open_study_dir(out, "sweep", protect=[st.path, st.base_path])
    with output_lock(outdir):
        remove_temporaries(outdir, CONFIGS_DIR, LOG_DIR)  # of a killed execution
        if st.path is not None:
            from ..util.atomic import write_atomic

            write_atomic(outdir / "study.toml", st.text)
        state, names = "partial", ["study.toml"]
        try:
            with study_client(client, scheduler=scheduler, workers=workers, say=say) as c:
                ex = run_all(
                    st.runs,
                    outdir,
                    c,
                    retries=retries,
                    progress=progress,
                    chunk=chunk,
                    extract=run_arrays,
                )
            ds = build_dataset(st, ex, outdir)
            write_dataset(ds, outdir / STUDY_NC)
            names.append(STUDY_NC)
            if figures:
                names += _figures(ds, outdir)
            state = "complete" if ex.failed == 0 else "partial"
        finally:
            old = read_marker(outdir) or {}
            files = [*old.get("files", []), *names]
            write_marker(outdir, state, files, command="sweep")
    return ds


def _figures(ds: Any, outdir: Path) -> list[str]:
    from .plots import plot_profiles, plot_summary, write_report

    figs = [plot_summary(ds, outdir / "summary.png")]
    prof = plot_profiles(ds, outdir / "wear_profiles.png")
    if prof is not None:
        figs.append(prof)
    report = write_report(ds, outdir / "report.md", figs)
    return [p.name for p in [*figs, report]]
