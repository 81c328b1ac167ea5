"""Names of a package imported on first use (PEP 562), so that importing the package
stays cheap: the one implementation of the packages' module-level ``__getattr__``."""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping
from importlib import import_module
from typing import Any

__all__ = ["lazy_names"]


def lazy_names(
    package: str, where: Mapping[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The module-level ``__getattr__`` and ``__dir__`` of a package whose names are
    defined in modules imported on first use.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    where : mapping of str to str
        Name -> the module that defines it, absolute (``"vemwear.simulate"``) or
        relative to the package (``".build"``).

    Returns
    -------
    (__getattr__, __dir__)
        ``__getattr__(name)`` imports the module of ``name`` and keeps the value in the
        package's namespace (later look-ups are plain attribute reads); other names
        raise :class:`AttributeError`. ``__dir__()`` lists the package's ``__all__``
        and the lazy names.

    Examples
    --------
    In a package's ``__init__.py``::

        __getattr__, __dir__ = lazy_names(__name__, {"load_config": ".build"})
    """
    names = dict(where)

    def __getattr__(name: str) -> Any:
        try:
            module = names[name]
        except KeyError:
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        value = getattr(import_module(module, package), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(getattr(sys.modules[package], "__all__", ())) | set(names))

    return __getattr__, __dir__
