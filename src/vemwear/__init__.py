"""vemwear: quasistatic frictional contact with wear by the virtual element method.

The main API is available at the top level and imported on first use, so that
``import vemwear`` stays cheap (no NumPy until a name is used)::

    import vemwear

    mesh = vemwear.tag_rectangle(
        vemwear.rectangle_squares((2.0, 1.0), (32, 16)),
        {"clamped": "left", "traction": ["top", "right"], "contact": "bottom"},
    )
    problem = vemwear.Problem(
        mesh=mesh,
        material=vemwear.Material(lam=4.0, eta=4.0),
        time=vemwear.TimeGrid.uniform(1.0, 64),
        f1=(0.0, -0.06),
        p=vemwear.LinearCompliance(0.4),
        g=0.1, mu=0.2, kappa=2.0, v_star=(1.0, 0.0),
    )
    result = vemwear.simulate(problem)
    vemwear.save_result(result, "out")

- problems and runs: :func:`simulate`, :class:`Problem`, :class:`TimeGrid`,
  :class:`SolverOptions`, :class:`Result`, :class:`Material`;
- compliance laws p(r) of the soft layer: :class:`LinearCompliance`,
  :class:`TableCompliance`, :class:`CallableCompliance`;
- configuration files: :func:`load_config`, :func:`parse_config`,
  :func:`apply_overrides`, :class:`ConfigError`;
- results on disk: :func:`save_result`, :func:`load_result`;
- meshes: :class:`Mesh`, :func:`rectangle_squares`, :func:`rectangle_triangles`,
  :func:`rectangle_voronoi`, :func:`voronoi_mesh`, :func:`tag_rectangle`,
  :func:`read_mesh`, :func:`write_mesh`.

The subpackages (``vemwear.mesh``, ``vem``, ``contact``, ``solvers``, ``simulate``,
``post``, ``config``, ``paper``) hold the rest; docs/architecture.md describes them and
docs/method.md the method's discrete choices. The name ``vemwear.simulate`` is the
function, also after its subpackage has been imported: import from the subpackage
with ``from vemwear.simulate import Problem`` or ``importlib.import_module``
(``import vemwear.simulate as m`` binds the function).

Type checkers read the same names from ``__init__.pyi`` (the lazy-loading stub of
SPEC 1), so that the lazy names keep their types.
"""

from __future__ import annotations

import sys
from types import ModuleType
from typing import Any

from .util.lazy import lazy_names

__version__ = "0.1.0"

#: Top-level name -> the module that defines it (imported on first use).
_API: dict[str, str] = {
    "simulate": "vemwear.simulate",
    "Problem": "vemwear.simulate",
    "TimeGrid": "vemwear.simulate",
    "SolverOptions": "vemwear.simulate",
    "Result": "vemwear.simulate",
    "Material": "vemwear.vem",
    "LinearCompliance": "vemwear.contact",
    "TableCompliance": "vemwear.contact",
    "CallableCompliance": "vemwear.contact",
    "load_config": "vemwear.config",
    "run_config": "vemwear.runner",
    "parse_config": "vemwear.config",
    "apply_overrides": "vemwear.config",
    "ConfigError": "vemwear.config",
    "save_result": "vemwear.post.results",
    "load_result": "vemwear.post.results",
    "Mesh": "vemwear.mesh",
    "rectangle_squares": "vemwear.mesh",
    "rectangle_triangles": "vemwear.mesh",
    "rectangle_voronoi": "vemwear.mesh",
    "voronoi_mesh": "vemwear.mesh",
    "tag_rectangle": "vemwear.mesh",
    "read_mesh": "vemwear.mesh",
    "write_mesh": "vemwear.mesh",
}

__all__ = [
    "CallableCompliance",
    "ConfigError",
    "LinearCompliance",
    "Material",
    "Mesh",
    "Problem",
    "Result",
    "SolverOptions",
    "TableCompliance",
    "TimeGrid",
    "__version__",
    "apply_overrides",
    "load_config",
    "load_result",
    "parse_config",
    "read_mesh",
    "rectangle_squares",
    "rectangle_triangles",
    "rectangle_voronoi",
    "run_config",
    "save_result",
    "simulate",
    "tag_rectangle",
    "voronoi_mesh",
    "write_mesh",
]


# the top-level API, imported on first use (PEP 562)
__getattr__, __dir__ = lazy_names(__name__, _API)


class _Package(ModuleType):
    """This package's module type: an API name that is also the name of a subpackage
    (``simulate``) stays bound to the API object when the import system binds the
    subpackage to its parent."""

    def __setattr__(self, name: str, value: Any) -> None:
        if (
            name in _API
            and isinstance(value, ModuleType)
            and value.__name__ == f"{__name__}.{name}"
            and hasattr(value, name)
        ):
            value = getattr(value, name)
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
