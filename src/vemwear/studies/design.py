"""The study file: a base configuration, the axes over its keys, and the design.

A study file is TOML (docs/studies.md)::

    base = "case.toml"                 # relative to the study file
    title = "kappa and mu"             # optional

    [overrides]                        # optional: set in every run
    "mesh.divisions" = [16, 8]
    "output.figures" = false

    [axes]                             # dotted key paths of the configuration
    "contact.kappa" = [2.0, 5.0, 10.0]                  # a list
    "contact.mu" = { start = 0.2, stop = 0.6, num = 3 }  # or step = 0.2; scale = "log"

    [design]
    kind = "grid"                      # grid | zip | lhs | sobol

``grid`` runs every combination (the first axis varies slowest), ``zip`` the i-th values
of every axis together (all of one length). ``lhs`` and ``sobol`` draw ``samples``
points (``seed``) by :mod:`scipy.stats.qmc` in the box of the axes' bounds, each given
as ``{ low = 1.0, high = 10.0 }`` (integer bounds give integer values; ``scale = "log"``
draws the logarithm uniformly).

:func:`load_study` reads the file, expands the design into :class:`RunSpec` objects
and validates every run's configuration (:func:`vemwear.config.parse_config`: the mesh,
the time grid and the data are built) before any run starts: a bad combination is one
:class:`StudyError` naming the study file, the run's parameters and the key path.
"""

from __future__ import annotations

import inspect
import itertools
import math
import os
import tomllib
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..config import ConfigError
from ..util.hashing import sha256_json
from . import _toml

__all__ = [
    "KINDS",
    "MAX_RUNS",
    "RunSpec",
    "Study",
    "StudyError",
    "count_runs",
    "expand",
    "load_study",
    "params_text",
]

#: The kinds of design.
KINDS = ("grid", "zip", "lhs", "sobol")
_RANDOM = ("lhs", "sobol")


class StudyError(ConfigError):
    """An invalid study file or run (an input error: exit code 2 on the command line)."""


@dataclass(frozen=True)
class RunSpec:
    """One run of a study.

    Attributes
    ----------
    id : str
        A stable hash of the run's configuration (its parameters applied to the base):
        the name of its output directory ``OUTDIR/runs/<id>``.
    index : int
        Its position in the design.
    params : dict
        The axis values, by dotted key path.
    data : dict
        The run's whole configuration data (base, overrides, parameters; a relative
        mesh file made absolute).
    """

    id: str
    index: int
    params: dict[str, Any]
    data: dict[str, Any]

    def toml(self) -> str:
        """The TOML text of the run's configuration (``OUTDIR/configs/<id>.toml``)."""
        head = f"run {self.id} of a vemwear study: {params_text(self.params)}"
        return _toml.dumps(self.data, header=head)


@dataclass
class Study:
    """A parsed study file.

    Attributes
    ----------
    path : Path or None
        The study file (None for a study given as data).
    base_path : Path
        The base configuration file.
    axes : dict
        The axes: dotted key path -> the list of values (grid, zip) or the
        ``(low, high, log, integer)`` bounds (lhs, sobol).
    kind : str
        One of :data:`KINDS`.
    samples, seed : int
        For the random designs.
    overrides : dict
        Keys set in every run.
    title : str
    text, base_text : str
        The study file and base configuration as written (kept in ``study.nc``).
    runs : list of RunSpec
        The expanded, validated runs.
    """

    path: Path | None
    base_path: Path
    axes: dict[str, Any]
    kind: str = "grid"
    samples: int = 0
    seed: int = 0
    overrides: dict[str, Any] = field(default_factory=dict)
    title: str = "study"
    text: str = ""
    base_text: str = ""
    runs: list[RunSpec] = field(default_factory=list)

    @property
    def keys(self) -> list[str]:
        """The axis names (dotted key paths), in order."""
        return list(self.axes)

    @property
    def shape(self) -> tuple[int, ...]:
        """The grid's shape (``(n_runs,)`` for the other designs)."""
        if self.kind == "grid":
            return tuple(len(v) for v in self.axes.values())
        return (len(self.runs),)


def _python(v: Any) -> Any:
    """NumPy scalars and arrays as Python numbers and lists (TOML types)."""
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray | list | tuple):
        return [_python(x) for x in v]
    return v


def params_text(params: Mapping[str, Any]) -> str:
    """``contact.kappa = 2, contact.mu = 0.2``."""
    return ", ".join(f"{k} = {_fmt(v)}" for k, v in params.items())


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return repr(v) if isinstance(v, str) else str(v)


def _number(src: str, where: str, v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise StudyError(f"{src}: {where} must be a finite number, got {v!r}")
    return float(v)


def _range(src: str, key: str, spec: Mapping[str, Any]) -> list[Any]:
    """The values of ``{start, stop, num | step[, scale]}``."""
    where = f"[axes] {key!r}"
    extra = set(spec) - {"start", "stop", "num", "step", "scale"}
    if extra or "start" not in spec or "stop" not in spec or ("num" in spec) == ("step" in spec):
        raise StudyError(
            f"{src}: {where}: a range is {{ start, stop, num }} or {{ start, stop, step }} "
            f"(optionally scale = 'log'), got keys {sorted(spec)}"
        )
    a, b = (
        _number(src, f"{where} start", spec["start"]),
        _number(src, f"{where} stop", spec["stop"]),
    )
    log = spec.get("scale", "linear")
    if log not in ("linear", "log"):
        raise StudyError(f"{src}: {where}: scale must be 'linear' or 'log', got {log!r}")
    if log == "log" and (a <= 0 or b <= 0):
        raise StudyError(f"{src}: {where}: a log range needs start and stop > 0")
    ints = all(isinstance(spec.get(k, 0), int) for k in ("start", "stop", "step"))
    if "num" in spec:
        n = spec["num"]
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise StudyError(f"{src}: {where}: num must be a positive integer, got {n!r}")
        vals = np.asarray(np.geomspace(a, b, n) if log == "log" else np.linspace(a, b, n))
    else:
        h = _number(src, f"{where} step", spec["step"])
        if log == "log":
            raise StudyError(f"{src}: {where}: a log range takes num, not step")
        if h == 0 or (b - a) / h < 0:
            raise StudyError(f"{src}: {where}: step {h:g} does not lead from {a:g} to {b:g}")
        n = math.floor((b - a) / h * (1 + 1e-12) + 1e-9) + 1
        if n > 1_000_000:
            raise StudyError(f"{src}: {where}: {n} values; more than a study should have")
        vals = np.asarray(a + h * np.arange(n), dtype=np.float64)
    if ints and np.allclose(vals, np.round(vals)):
        return [round(float(x)) for x in vals]
    return [float(x) for x in vals]


def _bounds(src: str, key: str, spec: Any) -> tuple[float, float, bool, bool]:
    where = f"[axes] {key!r}"
    if not isinstance(spec, Mapping) or not {"low", "high"} <= set(spec):
        raise StudyError(
            f"{src}: {where}: a random design needs bounds {{ low = ..., high = ... }}, "
            f"got {spec!r}"
        )
    extra = set(spec) - {"low", "high", "scale"}
    if extra:
        raise StudyError(f"{src}: {where}: unknown keys {sorted(extra)} (low, high, scale)")
    lo, hi = _number(src, f"{where} low", spec["low"]), _number(src, f"{where} high", spec["high"])
    if not lo < hi:
        raise StudyError(f"{src}: {where}: low = {lo:g} must be below high = {hi:g}")
    log = spec.get("scale", "linear") == "log"
    if log and lo <= 0:
        raise StudyError(f"{src}: {where}: log bounds need low > 0")
    ints = isinstance(spec["low"], int) and isinstance(spec["high"], int)
    return lo, hi, log, ints


def _qmc(kind: str, d: int, n: int, seed: int) -> np.ndarray:
    """``n`` points of the unit cube ``[0, 1)^d``."""
    from scipy.stats import qmc

    cls = qmc.LatinHypercube if kind == "lhs" else qmc.Sobol
    kw = "rng" if "rng" in inspect.signature(cls).parameters else "seed"
    engine = cls(d, **{kw: seed})
    with warnings.catch_warnings():  # Sobol: n not a power of 2 is allowed, less balanced
        warnings.simplefilter("ignore", UserWarning)
        return np.asarray(engine.random(n))


def expand(study: Study) -> list[dict[str, Any]]:
    """The parameters of every run of ``study``'s design, in order."""
    keys = study.keys
    if study.kind == "grid":
        combos = itertools.product(*study.axes.values())
        return [dict(zip(keys, c, strict=True)) for c in combos]
    if study.kind == "zip":
        return [dict(zip(keys, c, strict=True)) for c in zip(*study.axes.values(), strict=True)]
    u = _qmc(study.kind, len(keys), study.samples, study.seed)
    out = []
    for row in u:
        p: dict[str, Any] = {}
        for key, x in zip(keys, row, strict=True):
            lo, hi, log, ints = study.axes[key]
            v = math.exp(math.log(lo) + x * math.log(hi / lo)) if log else lo + x * (hi - lo)
            p[key] = round(v) if ints else float(v)
        out.append(p)
    return out


def _design(src: str, raw: Any) -> tuple[str, int, int]:
    raw = {} if raw is None else raw
    if not isinstance(raw, Mapping):
        raise StudyError(f"{src}: [design] must be a table")
    extra = set(raw) - {"kind", "samples", "seed"}
    if extra:
        raise StudyError(f"{src}: [design] unknown keys {sorted(extra)} (kind, samples, seed)")
    kind = raw.get("kind", "grid")
    if kind not in KINDS:
        raise StudyError(f"{src}: [design] kind must be one of {', '.join(KINDS)}, got {kind!r}")
    samples, seed = raw.get("samples", 0), raw.get("seed", 0)
    for name, v in (("samples", samples), ("seed", seed)):
        if isinstance(v, bool) or not isinstance(v, int) or v < 0:
            raise StudyError(f"{src}: [design] {name} must be an integer >= 0, got {v!r}")
    if kind in _RANDOM and samples < 1:
        raise StudyError(f"{src}: [design] kind = {kind!r} needs samples >= 1")
    if kind not in _RANDOM and "samples" in raw:
        raise StudyError(f"{src}: [design] samples is for kind = 'lhs' or 'sobol', not {kind!r}")
    return kind, samples, seed


def _axes(src: str, raw: Any, kind: str) -> dict[str, Any]:
    if not isinstance(raw, Mapping) or not raw:
        raise StudyError(f"{src}: [axes] must be a table of at least one dotted key path")
    axes: dict[str, Any] = {}
    for key, spec in raw.items():
        if isinstance(spec, Mapping) and kind not in _RANDOM and "low" not in spec:
            axes[key] = _range(src, key, spec)
        elif kind in _RANDOM:
            axes[key] = _bounds(src, key, spec)
        elif isinstance(spec, list) and spec:
            axes[key] = list(spec)
        else:
            raise StudyError(
                f"{src}: [axes] {key!r}: give a non-empty list of values or a range "
                f"{{ start, stop, num }} (bounds {{ low, high }} are for lhs and sobol), "
                f"got {spec!r}"
            )
    if kind == "zip" and len({len(v) for v in axes.values()}) > 1:
        lens = ", ".join(f"{k}: {len(v)}" for k, v in axes.items())
        raise StudyError(f"{src}: [design] kind = 'zip' needs axes of one length, got {lens}")
    return axes


def _absolute_mesh(data: dict[str, Any], base_dir: Path) -> dict[str, Any]:
    mesh = data.get("mesh")
    if isinstance(mesh, dict) and isinstance(mesh.get("file"), str):
        f = Path(mesh["file"]).expanduser()
        mesh["file"] = str(f if f.is_absolute() else (base_dir / f).resolve())
    return data


#: The most runs a study may have unless asked for more (``vemwear sweep --max-runs``).
MAX_RUNS = 100_000


def count_runs(kind: str, axes: Mapping[str, Any], samples: int) -> int:
    """The number of runs of a design, without expanding it."""
    if kind == "grid":
        return math.prod(len(v) for v in axes.values())
    if kind == "zip":
        return len(next(iter(axes.values())))
    return samples


def load_study(
    study: str | os.PathLike[str] | Mapping[str, Any],
    *,
    base_dir: str | os.PathLike[str] | None = None,
    validate: bool = True,
    max_runs: int = MAX_RUNS,
    say: Callable[[str], None] | None = None,
) -> Study:
    """Read a study, expand its design and validate every run.

    Parameters
    ----------
    study : path or mapping
        The study file, or its data (then ``base`` is relative to ``base_dir``,
        default the current directory).
    base_dir : path, optional
        For study data only.
    validate : bool
        Build every run's problem (:func:`vemwear.config.parse_config`); default True.
    max_runs : int
        Refuse a design of more runs (counted before any run is built).
    say : callable, optional
        Receives a line before a long validation (more than 1000 runs).

    Returns
    -------
    Study

    Raises
    ------
    StudyError
        For an invalid study, or the first invalid run (its parameters and key path).
    """
    from ..util.text import NotUtf8Error, read_utf8

    if isinstance(study, Mapping):
        path, src, raw = None, "study", dict(study)
        here = Path(base_dir or ".").resolve()
        text = _toml.dumps(raw)
    else:
        path = Path(study)
        src = str(path)
        try:
            text = read_utf8(path)
            raw = tomllib.loads(text)
        except NotUtf8Error as exc:
            raise StudyError(f"{src}: {exc}") from None
        except OSError as exc:
            raise StudyError(f"{src}: cannot read the study file: {exc.strerror or exc}") from None
        except tomllib.TOMLDecodeError as exc:
            raise StudyError(f"{src}: not valid TOML: {exc}") from None
        here = path.resolve().parent
    extra = set(raw) - {"base", "title", "overrides", "axes", "design"}
    if extra:
        raise StudyError(
            f"{src}: unknown keys or tables {sorted(extra)} (base, title, [overrides], [axes], "
            "[design])"
        )
    if not isinstance(raw.get("base"), str):
        raise StudyError(f"{src}: 'base' must name the base configuration file, e.g. 'case.toml'")
    base_path = Path(raw["base"]).expanduser()
    base_path = base_path if base_path.is_absolute() else here / base_path
    try:
        base_text = read_utf8(base_path)
        base = tomllib.loads(base_text)
    except NotUtf8Error as exc:
        raise StudyError(f"{src}: base {base_path}: {exc}") from None
    except OSError as exc:
        raise StudyError(f"{src}: base {raw['base']!r}: cannot read {base_path}: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"{src}: base {base_path}: not valid TOML: {exc}") from None
    kind, samples, seed = _design(src, raw.get("design"))
    overrides = raw.get("overrides", {})
    if not isinstance(overrides, Mapping):
        raise StudyError(f"{src}: [overrides] must be a table of dotted key paths")
    title = raw.get("title", path.stem if path is not None else "study")
    axes = _axes(src, raw.get("axes"), kind)
    n_runs = count_runs(kind, axes, samples)
    if n_runs > max_runs:
        shape = " x ".join(str(len(v)) for v in axes.values()) if kind == "grid" else kind
        raise StudyError(
            f"{src}: the design has {n_runs} runs ({shape}), more than --max-runs = "
            f"{max_runs}; use fewer values per axis, or raise --max-runs"
        )
    if say is not None and validate and n_runs > 1000:
        say(f"vemwear: {src}: {n_runs} runs ({kind}); validating each before any starts")
    from ..config import apply_overrides, parse_config  # after the cheap refusals

    out = Study(
        path=path,
        base_path=base_path,
        axes=axes,
        kind=kind,
        samples=samples,
        seed=seed,
        overrides=dict(overrides),
        title=str(title),
        text=text,
        base_text=base_text,
    )
    try:
        base = apply_overrides(base, out.overrides)
    except ConfigError as exc:
        raise StudyError(f"{src}: [overrides] {str(exc).removeprefix('overrides: ')}") from None
    for i, params in enumerate(expand(out)):
        params = {k: _python(v) for k, v in params.items()}
        where = f"{src}: run {i} ({params_text(params)})"
        try:
            data = _absolute_mesh(apply_overrides(base, params), base_path.parent)
        except ConfigError as exc:
            raise StudyError(f"{where}: [axes] {str(exc).removeprefix('overrides: ')}") from None
        if validate:
            try:
                parse_config(data, source=where, base_dir=base_path.parent)
            except ConfigError as exc:
                raise StudyError(str(exc)) from None
        rid = "r" + sha256_json({"config": data})[:12]
        out.runs.append(RunSpec(rid, i, params, data))
    ids = [r.id for r in out.runs]
    if len(set(ids)) < len(ids):
        dup = next(r for r in out.runs if ids.count(r.id) > 1)
        raise StudyError(
            f"{src}: run {dup.index} ({params_text(dup.params)}) appears more than once in "
            "the design; make the axis values distinct"
        )
    return out
