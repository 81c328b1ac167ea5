"""The package face: the lazy top-level API and its numpydoc docstrings."""

from __future__ import annotations

import inspect
import re
import subprocess
import sys

import pytest

import vemwear

API = [n for n in vemwear.__all__ if n != "__version__"]


def test_import_is_cheap_and_names_resolve_lazily() -> None:
    code = (
        "import sys, vemwear; heavy = [m for m in ('numpy', 'scipy', 'vemwear.simulate') "
        "if m in sys.modules]; assert not heavy, heavy; "
        "vemwear.TimeGrid; assert 'vemwear.simulate' in sys.modules"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_the_top_level_api() -> None:
    from vemwear.config import load_config
    from vemwear.simulate import Problem, simulate

    assert vemwear.simulate is simulate and vemwear.Problem is Problem
    assert vemwear.load_config is load_config
    assert sorted(dir(vemwear)) == sorted(vemwear.__all__)
    assert {"simulate", "Problem", "TimeGrid", "SolverOptions", "Material", "Result"} <= set(API)
    assert {"LinearCompliance", "TableCompliance", "save_result", "load_result"} <= set(API)
    assert {"rectangle_squares", "rectangle_voronoi", "tag_rectangle", "read_mesh"} <= set(API)
    with pytest.raises(AttributeError, match="no attribute 'simulat'"):
        vemwear.simulat  # noqa: B018


@pytest.mark.parametrize("package", ["config", "post", "runner", "studies", "study"])
def test_every_lazy_package_resolves_its_names_and_lists_them(package: str) -> None:
    """The subpackages' lazy names (one helper, ``vemwear.util.lazy``) resolve to the
    objects of the modules that define them, in a fresh interpreter."""
    code = (
        f"import importlib, sys; pkg = importlib.import_module('vemwear.{package}'); "
        "names = [n for n in pkg.__all__ if n != 'ConfigError']; "
        "assert set(pkg.__all__) <= set(dir(pkg)), dir(pkg); "
        "objs = [getattr(pkg, n) for n in names]; "
        "assert all(getattr(sys.modules[o.__module__], o.__name__) is o "
        "for o in objs if hasattr(o, '__qualname__')); "
        "assert all(n in vars(pkg) for n in names)  # kept: later look-ups are plain reads\n"
        "try:\n    pkg.no_such_name\nexcept AttributeError as e:\n"
        f"    assert str(e) == \"module 'vemwear.{package}' has no attribute 'no_such_name'\", e\n"
        "else:\n    raise AssertionError('no AttributeError')"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_the_stub_declares_the_same_names() -> None:
    """Type checkers read ``__init__.pyi``; it re-exports exactly the lazy names."""
    import ast
    from importlib.resources import files

    tree = ast.parse((files("vemwear") / "__init__.pyi").read_text(encoding="utf-8"))
    stub = {
        (a.asname or a.name): (node.module, a.name)
        for node in tree.body
        if isinstance(node, ast.ImportFrom)
        for a in node.names
    }
    assert set(stub) == set(API) == set(vemwear._API)
    for name, (module, orig) in stub.items():
        assert orig == name and vemwear._API[name] == f"vemwear.{module}", name


def _parameters(obj: object) -> list[str]:
    try:
        sig = inspect.signature(obj)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return []
    return [p.name for p in sig.parameters.values() if p.name != "self"]


def _section(doc: str, title: str) -> str:
    m = re.search(
        rf"^{title}\n-{{{len(title)}}}\n(.*?)(?=^\w[\w ]*\n-{{3,}}\n|\Z)", doc, re.M | re.S
    )
    return m.group(1) if m else ""


def _documented(section: str) -> dict[str, tuple[str, str]]:
    """``{name: (type, description)}`` of a numpydoc Parameters section."""
    out: dict[str, tuple[str, str]] = {}
    lines = section.splitlines()
    for i, line in enumerate(lines):
        if line and not line.startswith(" "):
            names, _, typ = line.partition(" : ")
            desc = []
            for follow in lines[i + 1 :]:
                if follow and not follow.startswith(" "):
                    break
                desc.append(follow.strip())
            for n in names.split(","):
                out[n.strip().lstrip("*")] = (typ.strip(), " ".join(desc).strip())
    return out


def _check(name: str) -> None:
    obj = getattr(vemwear, name)
    doc = inspect.getdoc(obj) or ""
    assert doc.strip(), f"{name}: no docstring"
    params = _parameters(obj)
    if not params:
        return
    section = _section(doc, "Parameters")
    assert section, f"{name}: no Parameters section"
    documented = _documented(section)
    missing = [p for p in params if p not in documented]
    assert not missing, f"{name}: parameters not documented: {missing}"
    for p in params:
        typ, desc = documented[p]
        assert typ or p in ("args", "kwargs", "options"), f"{name}: {p} has no type"
        assert desc, f"{name}: {p} has no description"


@pytest.mark.parametrize("name", API)
def test_every_top_level_name_has_a_numpydoc_docstring(name: str) -> None:
    _check(name)
