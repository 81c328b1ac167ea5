"""A run of a validated configuration: plan, solve, write; partial results and resume.

When a run stops after some time levels were finished (the solver did not converge,
Ctrl-C, SIGTERM, SIGHUP, any other error), the finished levels are written, atomically,
into ``OUTDIR.partial/`` next to the output directory:

``result.npz``
    The arrays of :func:`vemwear.post.save_result`; ``completed`` counts the finished
    levels (the later ones are zero).
``summary.json``
    ``"partial": true``, the ``reason``, ``completed`` and ``levels``; under
    ``inputs.extra.resume`` the fingerprint that ``--resume`` checks.
``PARTIAL.txt``
    What happened and the command that continues the run.
``config.toml``
    A copy of the configuration file (its SHA-256 is ``config_sha256``).

``--resume`` checks that the physics and the discretization are unchanged (the
problem's fingerprint, :meth:`vemwear.simulate.Problem.fingerprint`, hashed by
:func:`vemwear.util.hashing.sha256_json`); the solver options may change (a run
stopped because its solver did not converge may continue with another tolerance,
iteration limit or method). It rebuilds the :class:`~vemwear.simulate.Result` of the
finished levels and continues with ``simulate(..., resume=partial)``: with the same
solver the result is bitwise the one of an uninterrupted run. On success ``OUTDIR``
is written as usual and ``OUTDIR.partial`` is removed.
"""

from __future__ import annotations

import json
import shlex
import shutil
from collections.abc import Mapping
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..post.outputs import write_outputs
from ..util.hashing import sha256_file, sha256_json
from .outdir import OutputDirError, atomic_output_dir, check_output_dir
from .signals import stop_reason

if TYPE_CHECKING:
    from ..config import Config
    from ..simulate import Result, SolverOptions

__all__ = [
    "CONFIG_COPY",
    "PARTIAL_SUFFIX",
    "README_NAME",
    "ResumeError",
    "RunPlan",
    "differences",
    "execute_run",
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
def _flatten(x: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(x, Mapping):
        out: dict[str, Any] = {}
        for k, v in x.items():
            out.update(_flatten(v, f"{prefix}.{k}" if prefix else str(k)))
        return out
    return {prefix: x}


#: Section of the configuration of each entry of ``Problem.describe()``.
_SECTIONS = {
    "mesh": "[mesh]",
    "material": "[material]",
    "time": "[time]",
    "f1": "[loads]",
    "f2": "[loads]",
    "p": "[contact]",
    "g": "[contact]",
    "mu": "[contact]",
    "kappa": "[contact]",
    "v_star": "[contact]",
    "stabilization": "[vem]",
}
#: What the hashed parts of the fingerprint are, and the described entries they cover.
_HASHED = {
    "mesh": ("the mesh (vertices, cells or boundary parts)", ("mesh",)),
    "time": ("the time levels", ("time",)),
    "nodal": ("the values of g, mu or kappa at the contact nodes", ("g", "mu", "kappa")),
    "v_star": ("the foundation velocity v_star", ("v_star",)),
    "load": ("the loads f1, f2", ("f1", "f2")),
    "vemwear_version": ("the vemwear version", ()),
    "format": ("the fingerprint format", ()),
}


def _key_name(path: str) -> str:
    """``description.material.lam`` -> ``[material] lam``, ``description.mu`` ->
    ``[contact] mu``."""
    parts = path.split(".")[1:]
    section = _SECTIONS.get(parts[0], f"[{parts[0]}]")
    if parts[0] in ("material", "mesh", "time"):
        return f"{section} {'.'.join(parts[1:])}"
    return f"{section} {'.'.join(parts)}"


def _brief(v: Any) -> str:
    s = json.dumps(v) if not isinstance(v, str) or v == "<absent>" else repr(v)
    s = s.replace('"<absent>"', "<absent>")
    return s if len(s) <= 40 else s[:37] + "..."


def differences(old: Mapping[str, Any], new: Mapping[str, Any], limit: int = 3) -> list[str]:
    """What changed between two problem fingerprints, in words (at most ``limit`` items)."""
    a, b = _flatten(old.get("description", {})), _flatten(new.get("description", {}))
    diffs, changed = [], set()
    for k in sorted(set(a) | set(b)):
        x, y = a.get(k, "<absent>"), b.get(k, "<absent>")
        if x != y:
            diffs.append(f"{_key_name('description.' + k)}: {_brief(x)} -> {_brief(y)}")
            changed.add(k.split(".")[0])
    for key, (what, covers) in _HASHED.items():
        if old.get(key) != new.get(key) and not changed & set(covers):
            diffs.append(f"{what} changed")
    if len(diffs) > limit:
        diffs = [*diffs[:limit], f"and {len(diffs) - limit} more"]
    return diffs


# ---------------------------------------------------------------------------- save / load
def _reason(exc: BaseException) -> str:
    from ..solvers import ConvergenceError

    by_signal = stop_reason(exc)
    if by_signal is not None:
        return by_signal
    if isinstance(exc, ConvergenceError):
        return f"the solver did not converge: {exc}"
    return f"error: {type(exc).__name__}: {exc}"


def _resume_command(config_path: str | Path, out: Path, solver_flag: str | None) -> str:
    cmd = ["vemwear", "run", str(Path(config_path).resolve()), "-o", str(out), "--resume"]
    if solver_flag:
        cmd += ["--solver", solver_flag]
    return " ".join(shlex.quote(c) for c in cmd)


def _inputs_extra(cfg: Config, config_path: str | Path) -> dict[str, Any]:
    """What ``summary.json`` stores under ``inputs.extra`` about the configuration."""
    return {
        "config": cfg.data,
        "config_path": str(Path(config_path).resolve()),
        "title": cfg.title,
    }


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
             (the physics and the discretization: mesh, material, loads, contact
             data, time levels, and the vemwear version)
  written:   {datetime.now(UTC).isoformat(timespec="seconds")}

To continue the run from level {c}:

  {command}

The resumed run gives the same numbers as an uninterrupted run with the same solver;
the solver options may change (e.g. a larger max_iter after a convergence failure).
It refuses to start if the physics or the discretization changed. When it completes,
it writes the output directory and removes this directory. To discard the partial
result, delete this directory (or run again without --resume and with --force).

result.npz holds the arrays of the finished levels: the array 'completed' = {c} counts
them, later levels are zero. summary.json says "partial": true and gives the reason.
"""
        (tmp / README_NAME).write_text(text, encoding="utf-8")
    return part


def load_partial(part: Path, cfg: Config, current: Mapping[str, Any]) -> tuple[Result, dict]:
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
    (Result, dict)
        The finished levels, ready for ``simulate(..., resume=...)``, and the solver
        options they were computed with.

    Raises
    ------
    ResumeError
        If ``part`` is missing, not a partial result of vemwear, made from another
        problem (the message lists what changed) or does not fit the problem.
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
        diffs = differences(stored.get("fingerprint", {}), current["fingerprint"])
        what = "; ".join(diffs) if diffs else "the stored fingerprint does not match"
        raise ResumeError(
            f"--resume refused: {part} was computed from another problem ({what}); restore "
            "the inputs of the stopped run, or start over without --resume and with --force"
        )
    try:
        arrays = load_result(part)
        result = result_from_arrays(cfg.problem, arrays, solver=summary.get("solver"))
    except (OSError, ValueError, KeyError) as exc:
        raise ResumeError(f"--resume: {part}/result.npz cannot be used: {exc}") from None
    return result, dict(summary.get("solver") or {})


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
        Replace an existing output directory.
    previous : Result or None
        The partial result to resume from.
    previous_solver : dict
        The solver options of the partial result (recorded in ``summary.json``).
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
    previous_solver: dict[str, Any] = field(default_factory=dict)
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
    """Everything a run checks before solving: the output place, the partial result.

    Without ``resume`` an existing ``OUTDIR.partial`` is refused unless ``force``
    (which replaces it); with ``resume`` it must exist and hold the same problem.

    Raises
    ------
    ResumeError
        As described; an :class:`OutputDirError` if ``OUTDIR.partial`` cannot be used.
    """
    part = partial_path(out)
    check_output_dir(part, force=True, protect=[config_path])
    fp = cfg.problem.fingerprint()
    info = {
        "inputs_sha256": sha256_json(fp),
        "config_sha256": sha256_file(config_path),
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
        plan.previous, plan.previous_solver = load_partial(part, cfg, info)
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
        extra["previous_solver"] = plan.previous_solver
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
    from .signals import saving

    c, L = int(partial.completed), len(partial.t)
    try:
        with saving(reraise=False):
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
    except BaseException as err:  # a second failure must not hide the first one
        note = f"; the {c} finished time levels could not be saved ({type(err).__name__}: {err})"
    try:
        exc.vemwear_note = note  # type: ignore[attr-defined]
    except AttributeError:  # pragma: no cover - exceptions with __slots__
        pass
