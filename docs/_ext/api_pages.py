"""The API reference pages, generated from the packages' ``__all__`` at build time.

Every name a public package exports gets a page of its own (autosummary stubs under
``reference/generated/``); a name exported by two packages is documented where it is
defined first in the layer order and linked from the other. ``tests/test_docs.py``
checks on the built site that every name has its page.
"""

from __future__ import annotations

import importlib
import inspect
from pathlib import Path
from typing import Any

#: The public library, in layer order (lowest first), with a one-line description.
PACKAGES: tuple[tuple[str, str], ...] = (
    ("vemwear.mesh", "Meshes: generators, checks, quality, files, point location"),
    ("vemwear.vem", "The virtual element space: projection, element matrices, loads"),
    ("vemwear.contact", "The contact boundary, compliance laws, data along it, v*(t)"),
    ("vemwear.solvers", "The step problem: condensed and full Newton, Uzawa, backends"),
    ("vemwear.simulate", "Problems, time grids, the time loop and its result"),
    ("vemwear.config", "Configuration files: schema, validation, overrides"),
    ("vemwear.post", "Results on disk, figures, ParaView output, norms and errors"),
    ("vemwear.runner", "Running a validated configuration: output directory, plan, resume"),
    ("vemwear.studies", "Parameter studies and calibration on Dask"),
)


def _kind(obj: Any) -> str:
    if inspect.isclass(obj):
        return "Exceptions" if issubclass(obj, BaseException) else "Classes"
    if callable(obj):
        return "Functions"
    return "Data"


def public_names() -> dict[str, list[tuple[str, str]]]:
    """Package -> its ``__all__`` as (name, canonical dotted path), in order."""
    owner: dict[int, str] = {}
    out: dict[str, list[tuple[str, str]]] = {}
    for pkg, _ in PACKAGES:
        mod = importlib.import_module(pkg)
        rows = []
        for name in mod.__all__:
            obj = getattr(mod, name)
            key = id(obj)
            documented = inspect.isclass(obj) or inspect.isfunction(obj)
            if documented and key in owner:
                rows.append((name, owner[key]))
            else:
                if documented:
                    owner[key] = f"{pkg}.{name}"
                rows.append((name, f"{pkg}.{name}"))
        out[pkg] = rows
    return out


def _page(pkg: str, title: str, rows: list[tuple[str, str]]) -> str:
    mod = importlib.import_module(pkg)
    groups: dict[str, list[str]] = {}
    elsewhere: list[str] = []
    for name, path in rows:
        if path != f"{pkg}.{name}":
            elsewhere.append(path)
        else:
            groups.setdefault(_kind(getattr(mod, name)), []).append(name)
    head = f"``{pkg}``"
    lines = [
        head,
        "=" * len(head),
        "",
        title + ".",
        "",
        f".. automodule:: {pkg}",
        "   :no-members:",
        "",
    ]
    lines += [f".. currentmodule:: {pkg}", ""]
    for kind in ("Classes", "Functions", "Exceptions", "Data"):
        if kind in groups:
            lines += [kind, "-" * len(kind), "", ".. autosummary::", "   :toctree: generated/"]
            if kind == "Classes" or kind == "Exceptions":
                lines.append("   :template: class.rst")
            lines += ["", *(f"   {n}" for n in groups[kind]), ""]
    if elsewhere:
        lines += ["Documented elsewhere", "--------------------", "", ".. autosummary::", ""]
        lines += [*(f"   ~{p}" for p in elsewhere), ""]
    return "\n".join(lines)


def _top_level() -> str:
    import vemwear

    names = [n for n in vemwear.__all__ if not n.startswith("_")]
    where = {}
    for rows in public_names().values():
        for name, path in rows:
            where.setdefault(name, path)
    lines = ["``vemwear``", "===========", "", ".. automodule:: vemwear", "   :no-members:", ""]
    lines += ["The names of the top level, each documented in its package:", ""]
    lines += [".. autosummary::", ""]
    lines += [f"   ~{where[n].removeprefix('vemwear.')}" for n in names if n in where]
    lines.append("")
    return "\n".join(lines)


def write_api_pages(folder: Path) -> list[str]:
    """Write ``vemwear.rst`` and one page per package into ``folder``; their names."""
    folder.mkdir(parents=True, exist_ok=True)
    pages = {"vemwear": _top_level()}
    titles = dict(PACKAGES)
    for pkg, rows in public_names().items():
        pages[pkg] = _page(pkg, titles[pkg], rows)
    for name, text in pages.items():
        path = folder / f"{name}.rst"
        if not path.is_file() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
    return list(pages)
