"""The ``>>>`` examples of the docstrings run as doctests, and the main entry points have
one (the API reference of the documentation site shows them)."""

from __future__ import annotations

import doctest
import importlib
import inspect
import pkgutil

import pytest

import vemwear

#: The entry points whose docstrings must show an example.
ENTRY_POINTS = (
    "vemwear.simulate.Problem",
    "vemwear.simulate.TimeGrid",
    "vemwear.simulate.simulate",
    "vemwear.mesh.rectangle_squares",
    "vemwear.mesh.rectangle_triangles",
    "vemwear.mesh.rectangle_voronoi",
    "vemwear.mesh.voronoi_mesh",
    "vemwear.mesh.tag_rectangle",
    "vemwear.contact.LinearCompliance",
    "vemwear.contact.TableCompliance",
    "vemwear.contact.CallableCompliance",
    "vemwear.runner.run_config",
)


def _doctests(module: str) -> list[doctest.DocTest]:
    mod = importlib.import_module(module)
    return [t for t in doctest.DocTestFinder().find(mod, module) if t.examples]


def _modules_with_examples() -> list[str]:
    """Every module of the package whose docstrings hold ``>>>`` examples."""
    names = ["vemwear"]
    names += [m.name for m in pkgutil.walk_packages(vemwear.__path__, "vemwear.")]
    return sorted(n for n in names if not n.endswith("__main__") and _doctests(n))


MODULES = _modules_with_examples()


def _obj(path: str) -> object:
    module, name = path.rsplit(".", 1)
    return getattr(importlib.import_module(module), name)


@pytest.mark.parametrize("path", ENTRY_POINTS)
def test_entry_points_show_an_example(path: str) -> None:
    obj = _obj(path)
    doc = inspect.getdoc(obj) or ""
    assert "Examples\n--------" in doc and ">>> " in doc, f"{path}: no Examples section"
    # ... which the doctest of the module that defines it runs
    defined = obj.__module__  # type: ignore[attr-defined]
    assert defined in MODULES, path
    assert any(t.name.endswith("." + path.rsplit(".", 1)[1]) for t in _doctests(defined))


@pytest.mark.parametrize("module", MODULES)
def test_docstring_examples_run(module: str) -> None:
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for t in _doctests(module):
        runner.run(t)
    res = runner.summarize(verbose=False)
    assert res.failed == 0, f"{module}: {res.failed} of {res.attempted} examples failed"
    # a module whose examples are all skipped (+SKIP) is checked for syntax only
    assert res.attempted > 0 or module == "vemwear.util.atomic"


def test_the_examples_are_found() -> None:
    """The collection above is not empty by accident (e.g. a changed finder)."""
    assert {"vemwear.simulate.loop", "vemwear.contact.law", "vemwear.mesh.generate"} <= set(MODULES)
