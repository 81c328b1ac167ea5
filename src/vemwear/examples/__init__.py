"""The configuration files of the paper's examples, shipped with the package.

``example_5_2_set{1,2,3}.toml`` (paper Example 5.2, Figs. 3-5) and
``example_5_4_voronoi.toml`` (Example 5.4, mesh B); the format is docs/config.md.
They describe the same discrete problems as :mod:`vemwear.paper.ex52` and
:mod:`vemwear.paper.ex54` (checked by the tests). From an installed package::

    from vemwear.examples import config_path
    cfg = vemwear.load_config(config_path("example_5_2_set1"))
"""

from __future__ import annotations

from importlib.resources import files
from importlib.resources.abc import Traversable
from pathlib import Path

__all__ = ["config_path", "configs"]


def configs() -> dict[str, Traversable]:
    """The shipped configuration files by name (the file name without ``.toml``), sorted."""
    found = (f for f in files(__name__).iterdir() if f.name.endswith(".toml"))
    return {f.name[: -len(".toml")]: f for f in sorted(found, key=lambda f: f.name)}


def config_path(name: str) -> Path:
    """The path of the shipped configuration file ``name`` (with or without ``.toml``).

    Parameters
    ----------
    name : str
        E.g. ``"example_5_2_set1"``.

    Raises
    ------
    KeyError
        If there is no such file; the message lists the available ones.
    """
    found = configs()
    key = name.removesuffix(".toml")
    if key not in found:
        raise KeyError(f"no example configuration {name!r}; available: {', '.join(found)}")
    return Path(str(found[key]))
