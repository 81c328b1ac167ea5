"""Partial results of stopped runs and ``vemwear run CONFIG -o OUTDIR --resume``.

When ``vemwear run`` stops after some time levels were finished (the solver did not
converge, Ctrl-C, SIGTERM, any other error), the finished levels are written, atomically,
into ``OUTDIR.partial/`` next to the output directory:

``result.npz``
    The arrays of :func:`vemwear.post.save_result`; ``completed`` counts the finished
    levels (the later ones are zero).
``summary.json``
    ``"partial": true``, the ``reason``, ``completed`` and ``levels``; under
    ``inputs.extra.resume`` the hashes that ``--resume`` checks.
``PARTIAL.txt``
    What happened and the command that continues the run.
``config.toml``
    A copy of the configuration file (its SHA-256 is ``config_sha256``).

The exit code is the one of the error (3 no convergence, 130 interrupted, ...).
``vemwear run CONFIG -o OUTDIR --resume`` checks that the inputs are unchanged (the
*inputs hash*: the configuration without ``title`` and ``[output]``, the effective
solver options, the contents of a mesh file and the vemwear version), rebuilds the
:class:`~vemwear.simulate.Result` of the finished levels and continues with
``simulate(..., resume=partial)``: the result is bitwise the one of an uninterrupted
run. On success ``OUTDIR`` is written as usual and ``OUTDIR.partial`` is removed.
"""

from __future__ import annotations

import hashlib
import json
import math
import shlex
import shutil
from collections.abc import Mapping
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import __version__
from ..post.outputs import write_outputs
from .output import OutputDirError, atomic_output_dir, check_output_dir

if TYPE_CHECKING:
    from ..config import Config
    from ..simulate import Result, SolverOptions

__all__ = [
    "CONFIG_COPY",
    "PARTIAL_SUFFIX",
    "README_NAME",
    "ResumeError",
    "RunPlan",
    "execute_run",
    "fingerprint",
    "inputs_sha256",
    "load_partial",
    "partial_path",
    "prepare_run",
    "save_partial",
]

#: Suffix of the directory of a partial result: ``OUTDIR.partial``.
PARTIAL_SUFFIX = ".partial"
#: Explanation written into the partial directory.
README_NAME = "PARTIAL.txt"
#: Copy of the configuration file in the partial directory.
CONFIG_COPY = "config.toml"


class ResumeError(OutputDirError):
    """``--resume`` is not possible (no partial result, other inputs, damaged files)."""


def partial_path(outdir: str | Path) -> Path:
    """``OUTDIR.partial``: the sibling directory holding a partial result."""
    out = Path(outdir)
    return out.with_name(out.name + PARTIAL_SUFFIX)


# ---------------------------------------------------------------------------- fingerprint
def _sha256_file(path: str | Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _normalize(x: Any) -> Any:
    """Numbers as floats (``4`` and ``4.0`` are the same input), keys sorted by json."""
    if isinstance(x, Mapping):
        return {str(k): _normalize(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_normalize(v) for v in x]
    if isinstance(x, bool) or x is None or isinstance(x, str):
        return x
    if isinstance(x, int | float):
        return float(x) if math.isfinite(float(x)) else str(x)
    return str(x)


def fingerprint(cfg: Config, solver: SolverOptions) -> dict[str, Any]:
    """Everything that determines the computed numbers of a run.

    Parameters
    ----------
    cfg : Config
        The validated configuration.
    solver : SolverOptions
        The effective solver options (after ``--solver``).

    Returns
    -------
    dict
        ``config`` (the data without ``title``, ``[output]`` and ``[solver]``),
        ``solver`` (method, tol, max_iter and the resolved backend), ``mesh_file``
        (the SHA-256 of a mesh file, or None) and ``vemwear_version``.
    """
    from ..solvers import resolve_backend

    data = {k: v for k, v in cfg.data.items() if k not in ("title", "output", "solver")}
    mesh_file = cfg.mesh_source.get("file")
    return {
        "config": _normalize(data),
        "solver": {
            "method": solver.method,
            "tol": float(solver.tol),
            "max_iter": solver.max_iter,
            "backend": resolve_backend(solver.backend),
        },
        "mesh_file": _sha256_file(mesh_file) if mesh_file else None,
        "vemwear_version": __version__,
    }


def inputs_sha256(fp: Mapping[str, Any]) -> str:
    """SHA-256 of a :func:`fingerprint` (canonical JSON)."""
    text = json.dumps(fp, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _flatten(x: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(x, Mapping):
        out: dict[str, Any] = {}
        for k, v in x.items():
            out.update(_flatten(v, f"{prefix}.{k}" if prefix else str(k)))
        return out
    return {prefix: x}


def _key_name(path: str) -> str:
    """``config.contact.mu`` -> ``[contact] mu``; ``solver.method`` -> ``solver method``."""
    parts = path.split(".")
    if parts[0] == "config" and len(parts) >= 3:
        return f"[{parts[1]}] {'.'.join(parts[2:])}"
    if parts[0] == "config" and len(parts) == 2:
        return f"[{parts[1]}]"
    return " ".join(parts).replace("_", " ")


def _differences(old: Mapping[str, Any], new: Mapping[str, Any], limit: int = 3) -> list[str]:
    a, b = _flatten(old), _flatten(new)
    diffs = []
    for k in sorted(set(a) | set(b)):
        if a.get(k, "<absent>") != b.get(k, "<absent>"):
            if k == "mesh_file":
                diffs.append("the contents of the mesh file changed")
            else:
                diffs.append(
                    f"{_key_name(k)}: {_brief(a.get(k, '<absent>'))} -> "
                    f"{_brief(b.get(k, '<absent>'))}"
                )
    if len(diffs) > limit:
        diffs = [*diffs[:limit], f"and {len(diffs) - limit} more"]
    return diffs


def _brief(v: Any) -> str:
    s = json.dumps(v) if not isinstance(v, str) or v == "<absent>" else repr(v)
    s = s.replace('"<absent>"', "<absent>")
    return s if len(s) <= 40 else s[:37] + "..."


# ---------------------------------------------------------------------------- save / load
def _reason(exc: BaseException) -> str:
    from ..solvers import ConvergenceError
    from .main import _Interrupted

    if isinstance(exc, _Interrupted):
        return "terminated (SIGTERM)"
    if isinstance(exc, KeyboardInterrupt):
        return "interrupted (Ctrl-C)"
    if isinstance(exc, ConvergenceError):
        return f"the solver did not converge: {exc}"
    return f"error: {type(exc).__name__}: {exc}"


def _resume_command(config_path: str | Path, out: Path, solver_flag: str | None) -> str:
    cmd = ["vemwear", "run", str(Path(config_path).resolve()), "-o", str(out), "--resume"]
    if solver_flag:
        cmd += ["--solver", solver_flag]
    return " ".join(shlex.quote(c) for c in cmd)


def save_partial(
    result: Result,
    part: Path,
    *,
    reason: str,
    cfg: Config,
    config_path: str | Path,
    resume_info: Mapping[str, Any],
    command: str,
) -> Path:
    """Write the finished levels of a stopped run into ``part`` (atomically).

    Parameters
    ----------
    result : Result
        The partial result (``exc.partial_result``) or a complete one whose output
        could not be written.
    part : Path
        ``OUTDIR.partial``; an older partial result there is replaced as a whole.
    reason : str
        Why the run stopped (stored in ``summary.json`` and ``PARTIAL.txt``).
    cfg : Config
        The configuration of the run.
    config_path : path
        The configuration file, copied into ``part``.
    resume_info : mapping
        ``inputs_sha256``, ``config_sha256`` and ``fingerprint``, checked by ``--resume``.
    command : str
        The command line that continues the run.

    Returns
    -------
    Path
        ``part``.
    """
    from .. import post

    extra = {**_inputs_extra(cfg, config_path), "resume": {**resume_info, "command": command}}
    c, L = int(result.completed), len(result.t)
    with atomic_output_dir(part, force=True) as tmp:
        post.save_result(result, tmp, extra=extra, partial=reason)
        shutil.copyfile(config_path, tmp / CONFIG_COPY)
        t_done = f"t = 0 .. {result.t[c - 1]:.6g}" if c > 0 else "none"
        text = f"""\
This directory holds a PARTIAL result of vemwear: the run stopped before the end.

  reason:    {reason}
  finished:  {c} of {L} time levels ({t_done}; T = {result.t[-1]:g})
  config:    {Path(config_path).resolve()}
             (a copy is {CONFIG_COPY}, sha256 {resume_info.get("config_sha256")})
  inputs:    sha256 {resume_info.get("inputs_sha256")}
             (the configuration without title and [output], the solver options,
             the mesh file's contents and the vemwear version)
  written:   {datetime.now(UTC).isoformat(timespec="seconds")}

To continue the run from level {c}, with the same inputs:

  {command}

The resumed run gives the same numbers as an uninterrupted run; it refuses to start if
the inputs have changed. When it completes, it writes the output directory and removes
this directory. To discard the partial result, delete this directory (or run again
without --resume and with --force).

result.npz holds the arrays of the finished levels: the array 'completed' = {c} counts
them, later levels are zero. summary.json says "partial": true and gives the reason.
"""
        (tmp / README_NAME).write_text(text, encoding="utf-8")
    return part


def _inputs_extra(cfg: Config, config_path: str | Path) -> dict[str, Any]:
    """What ``summary.json`` stores under ``inputs.extra`` about the configuration."""
    return {
        "config": cfg.data,
        "config_path": str(Path(config_path).resolve()),
        "title": cfg.title,
    }


def load_partial(part: Path, cfg: Config, current: Mapping[str, Any]) -> Result:
    """Check and read the partial result in ``part`` for the configuration ``cfg``.

    Parameters
    ----------
    part : Path
        ``OUTDIR.partial``.
    cfg : Config
        The configuration of the resumed run.
    current : mapping
        ``inputs_sha256`` and ``fingerprint`` of the resumed run.

    Returns
    -------
    Result
        The finished levels, ready for ``simulate(..., resume=...)``.

    Raises
    ------
    ResumeError
        If ``part`` is missing, not a partial result of vemwear, made from other
        inputs (the message lists what changed) or does not fit the problem.
    """
    from ..post.results import FORMAT, load_result, load_summary, result_from_arrays

    if not part.is_dir():
        raise ResumeError(
            f"--resume: there is no partial result to resume: {part} does not "
            "exist (it is written when a run stops after finishing some time "
            "levels)"
        )
    try:
        summary = load_summary(part)
    except (OSError, ValueError) as exc:
        raise ResumeError(f"--resume: {part} is not a readable partial result: {exc}") from None
    if not isinstance(summary, dict) or summary.get("format") != FORMAT:
        raise ResumeError(f"--resume: {part}/summary.json is not a vemwear result summary")
    if not summary.get("partial"):
        raise ResumeError(f"--resume: {part} is not marked as a partial result")
    extra = summary.get("inputs", {}).get("extra", {})
    stored = extra.get("resume", {}) if isinstance(extra, dict) else {}
    if stored.get("inputs_sha256") != current["inputs_sha256"]:
        diffs = _differences(stored.get("fingerprint", {}), current["fingerprint"])
        what = "; ".join(diffs) if diffs else "the stored hash does not match"
        raise ResumeError(
            f"--resume refused: {part} was computed from other inputs ({what}); restore the "
            "inputs of the stopped run, or start over without --resume and with --force"
        )
    try:
        arrays = load_result(part)
        result = result_from_arrays(cfg.problem, arrays, solver=summary.get("solver"))
    except (OSError, ValueError, KeyError) as exc:
        raise ResumeError(f"--resume: {part}/result.npz cannot be used: {exc}") from None
    return result


# ---------------------------------------------------------------------------- running
@dataclass
class RunPlan:
    """A validated ``vemwear run``: where it writes, what it resumes from.

    Attributes
    ----------
    cfg : Config
        The configuration.
    config_path : Path
        Its file.
    out : Path
        The output directory (absolute).
    part : Path
        ``OUTDIR.partial``.
    solver : SolverOptions
        The effective solver options.
    force : bool
        ``--force``.
    previous : Result or None
        The partial result to resume from (``--resume``).
    resume_info : dict
        ``inputs_sha256``, ``config_sha256`` and ``fingerprint`` of this run.
    command : str
        The command that resumes this run if it stops.
    """

    cfg: Config
    config_path: Path
    out: Path
    part: Path
    solver: SolverOptions
    force: bool
    previous: Result | None = None
    resume_info: dict[str, Any] = field(default_factory=dict)
    command: str = ""


def prepare_run(
    cfg: Config,
    config_path: str | Path,
    out: Path,
    solver: SolverOptions,
    *,
    force: bool = False,
    resume: bool = False,
    solver_flag: str | None = None,
) -> RunPlan:
    """Everything ``vemwear run`` checks before solving: the partial result, ``--resume``.

    Without ``--resume`` an existing ``OUTDIR.partial`` is refused unless ``--force``
    (which replaces it); with ``--resume`` it must exist and match the inputs.

    Raises
    ------
    ResumeError
        As described; an :class:`OutputDirError` if ``OUTDIR.partial`` cannot be used.
    """
    part = partial_path(out)
    check_output_dir(part, force=True, protect=[config_path])
    fp = fingerprint(cfg, solver)
    info = {
        "inputs_sha256": inputs_sha256(fp),
        "config_sha256": _sha256_file(config_path),
        "fingerprint": fp,
    }
    plan = RunPlan(
        cfg=cfg,
        config_path=Path(config_path),
        out=out,
        part=part,
        solver=solver,
        force=force,
        resume_info=info,
        command=_resume_command(config_path, out, solver_flag),
    )
    if resume:
        plan.previous = load_partial(part, cfg, info)
    elif (part.exists() or part.is_symlink()) and not force:
        raise ResumeError(
            f"{part} holds the finished levels of a stopped run; continue it with --resume, "
            "or start over with --force (which replaces it)"
        )
    return plan


def execute_run(plan: RunPlan, *, progress: bool = True) -> Result:
    """Solve and write ``OUTDIR`` atomically; keep the finished levels if the run stops.

    On success an ``OUTDIR.partial`` (resumed or stale) is removed. On any error or
    interruption after at least one finished level, they are saved by
    :func:`save_partial` and the exception propagates with an attribute
    ``vemwear_note`` saying where they are and how to resume.
    """
    from ..simulate import simulate

    cfg = plan.cfg
    extra = {
        **_inputs_extra(cfg, plan.config_path),
        "inputs_sha256": plan.resume_info.get("inputs_sha256"),
    }
    if plan.previous is not None:
        extra["resumed_from_level"] = int(plan.previous.completed)
    done: list[Result] = []
    try:
        with atomic_output_dir(plan.out, plan.force) as tmp:
            result = simulate(cfg.problem, plan.solver, progress=progress, resume=plan.previous)
            done.append(result)
            write_outputs(
                result,
                tmp,
                times=cfg.output.times,
                figures=cfg.output.figures,
                vtk=cfg.output.vtk,
                extra=extra,
            )
    except BaseException as exc:
        partial = getattr(exc, "partial_result", None) or (done[0] if done else None)
        if partial is not None and int(partial.completed) > 0:
            _keep(plan, partial, exc)
        raise
    if plan.part.exists():
        shutil.rmtree(plan.part, ignore_errors=True)
    return result


def _keep(plan: RunPlan, partial: Result, exc: BaseException) -> None:
    """Save the partial result; attach a one-line note to ``exc``."""
    c, L = int(partial.completed), len(partial.t)
    try:
        save_partial(
            partial,
            plan.part,
            reason=_reason(exc),
            cfg=plan.cfg,
            config_path=plan.config_path,
            resume_info=plan.resume_info,
            command=plan.command,
        )
        note = (
            f"; the {c} finished time levels (of {L}) are saved in {plan.part}; "
            f"continue with: {plan.command}"
        )
    except Exception as err:  # a second failure must not hide the first one
        note = f"; the {c} finished time levels could not be saved ({type(err).__name__}: {err})"
    try:
        exc.vemwear_note = note  # type: ignore[attr-defined]
    except AttributeError:  # pragma: no cover - exceptions with __slots__
        pass
