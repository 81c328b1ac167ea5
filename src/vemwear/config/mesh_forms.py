"""The ``[mesh]`` section of configuration files: a generator and its options, or a file.

The forms are built from the mesh registries (:data:`vemwear.mesh.registry.FAMILIES`
and :data:`vemwear.mesh.registry3d.FAMILIES_3D`): one model per family, whose keys are
the family's options with their types, defaults and help, picked by ``generator`` (the
family's name or an alias; an unknown name is an error suggesting the closest), and
:class:`MeshFile` for ``file``. :func:`mesh_family` finds a family by any of its names.
"""

import types
from typing import Annotated, Any, Literal, TypeAlias, Union, get_args, get_origin

from pydantic import Field, create_model

from ..mesh.registry import FAMILIES, Family, lookup
from ..mesh.registry3d import FAMILIES_3D
from .errors import got, suggest
from .sections import Section, by_kind, choice

__all__ = ["MESH_FORMS", "MeshFile", "MeshForm", "mesh_family"]


def mesh_family(name: str) -> Family[Any]:
    """The 2D or 3D mesh family called ``name`` (or an alias); a ValueError suggests the
    closest name among all."""
    return lookup(name, _BY_NAME, _EVERY)


_EVERY: dict[str, Family[Any]] = {**FAMILIES, **FAMILIES_3D}
_BY_NAME = {n: f for f in _EVERY.values() for n in (f.name, *f.aliases)}


def _pytype(tp: Any) -> Any:
    """A registry option type for pydantic: fixed-size tuples become arrays."""
    args = get_args(tp)
    if get_origin(tp) is tuple:
        if args[-1] is Ellipsis:
            return list[_pytype(args[0])]  # type: ignore[misc]
        return Annotated[list[_pytype(args[0])], Field(min_length=len(args), max_length=len(args))]  # type: ignore[misc]
    if get_origin(tp) in (Union, types.UnionType):
        forms = {"array" if get_origin(a) is tuple else "number": _pytype(a) for a in args}
        return by_kind(" or ".join(map(_words, args)), **forms)
    return tp


def _words(tp: Any) -> str:
    """``'an integer'``, ``'an array of 2 numbers'``, ... (for messages)."""
    if get_origin(tp) is tuple:
        return f"an array of {len(get_args(tp))} {_words(get_args(tp)[0]).split()[-1]}s"
    return {int: "an integer", float: "a number"}.get(tp, str(tp))


class MeshFile(Section):
    """A mesh file."""

    file: str = Field(
        description="mesh file (meshio: .vtu, .msh, ...), relative to the configuration file; "
        "a file with volume cells (tetrahedra, hexahedra, wedges, pyramids, polyhedra) is a 3D "
        "mesh"
    )


class Generated(Section):
    """A generated mesh; the other keys are the options of the family."""

    @classmethod
    def _unknown(cls, key: str, names: list[str], data: dict[str, Any]) -> str:
        return f"unknown key {key!r} for generator {data.get('generator')!r}{suggest(key, names)}"


def _family_model(fam: Family) -> type[Generated]:
    fields: dict[str, Any] = {
        "generator": (Literal[(fam.name, *fam.aliases)], Field(description=fam.description))
    }
    for o in fam.options:
        tp = _pytype(o.type) if o.default is not None else _pytype(o.type) | None
        fields[o.name] = (tp, Field(o.default, description=o.help))
    return create_model(  # type: ignore[no-any-return]
        f"{fam.name.title()}Mesh", __base__=Generated, __doc__=fam.description, **fields
    )


MESH_FORMS: dict[str, type[Section]] = {n: _family_model(f) for n, f in _EVERY.items()}
MESH_FORMS["file"] = MeshFile


def _mesh_form(v: Any) -> str | None:
    if not isinstance(v, dict) or ("file" in v) == ("generator" in v):
        return None
    try:
        return "file" if "file" in v else mesh_family(v["generator"]).name
    except (ValueError, TypeError):
        return None


def _mesh_error(v: Any) -> str:
    if not isinstance(v, dict):
        return f"must be a table, {got(v)}"
    if ("file" in v) == ("generator" in v):
        return "needs exactly one of 'generator' or 'file'" + (", not both" if "file" in v else "")
    if not isinstance(v["generator"], str):
        return f"generator must be a string, {got(v['generator'])}"
    try:
        mesh_family(v["generator"])
    except ValueError as exc:
        return f"generator = {exc}"
    return "is invalid"  # pragma: no cover - _mesh_form accepted it


MeshForm: TypeAlias = choice(_mesh_form, _mesh_error, **MESH_FORMS)  # type: ignore[valid-type]
