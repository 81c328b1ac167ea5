"""The building blocks of the configuration schema: the base model of every table and
the types its keys are declared with.

:class:`Section` is a TOML table with known keys only (an unknown one is an error with
a suggestion), strict types and finite numbers. :func:`choice` and :func:`by_kind` are
unions whose one form is picked by the value (by a key, or by its TOML type), so that
an invalid value gets one message; :func:`expression` is a string parsed by
:mod:`vemwear.config.expr`, :func:`components` an array of numbers or expressions, and
:func:`library_default` the default of a key taken from the library object it becomes.
The sections themselves are in :mod:`vemwear.config.schema`.
"""

import dataclasses
from collections.abc import Callable
from typing import Annotated, Any, Union

from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    PlainValidator,
    Tag,
    model_validator,
)
from pydantic.json_schema import SkipJsonSchema

from .errors import error, got, suggest
from .expr import ExpressionError, parse_expression

__all__ = ["Section", "by_kind", "choice", "components", "expression", "library_default"]


def library_default(cls: type, name: str) -> Any:
    """The default of a field of a library dataclass (one place for each default); a
    tuple (the dataclass's immutable default) as a list, the type of a TOML array."""
    value = {f.name: f for f in dataclasses.fields(cls)}[name].default
    return list(value) if isinstance(value, tuple) else value


class Section(BaseModel):
    """A TOML table: known keys only, strict types, finite numbers."""

    # defer_build: the validators are built once, for the whole configuration, when the
    # first one is validated (not once per table at import: a fifth of a run's start)
    model_config = ConfigDict(
        strict=True, extra="forbid", allow_inf_nan=False, frozen=True, defer_build=True
    )

    @model_validator(mode="before")
    @classmethod
    def _known_keys(cls, data: Any) -> Any:
        if isinstance(data, dict):
            names = [f.alias or n for n, f in cls.model_fields.items()]
            for key in data:
                if key not in names:
                    raise error(cls._unknown(str(key), names, data))
        return data

    @classmethod
    def _unknown(cls, key: str, names: list[str], data: dict[str, Any]) -> str:
        return f"unknown key {key!r}{suggest(key, names)}"


# ---------------------------------------------------------------------------- unions
def choice(pick: Callable[[Any], str | None], explain: Callable[[Any], str], **forms: Any) -> Any:
    """A union of ``forms``: ``pick(value)`` names the form to validate; None is the
    error ``explain(value)``."""

    def fail(value: Any) -> Any:
        raise error(explain(value))

    members = [Annotated[t, Tag(f"<{k}>")] for k, t in forms.items()]
    members.append(Annotated[Any, PlainValidator(fail), SkipJsonSchema(), Tag("<error>")])
    return Annotated[Union[tuple(members)], Discriminator(lambda v: f"<{pick(v) or 'error'}>")]  # noqa: UP007


def _toml_kind(v: Any) -> str | None:
    if isinstance(v, int | float) and not isinstance(v, bool):
        return "number"
    kinds: dict[type, str] = {str: "string", list: "array", dict: "table"}
    return kinds.get(type(v))


def by_kind(what: str, **forms: Any) -> Any:
    """A union of forms ``number``, ``string``, ``array``, ``table`` picked by the TOML type."""
    return choice(
        lambda v: _toml_kind(v) if _toml_kind(v) in forms else None,
        lambda v: f"must be {what}, {got(v)}",
        **forms,
    )


def expression(*names: str) -> Any:
    """An expression string in the variables ``names``, parsed into an ``Expression``."""

    def parse(text: str) -> Any:
        try:
            return parse_expression(text, names, where="")
        except ExpressionError as exc:
            raise error(str(exc)) from None

    return Annotated[str, AfterValidator(parse), Field(title=f"expression in {', '.join(names)}")]


def components(*names: str) -> Any:
    """An array of 2 (a 2D mesh) or 3 (a 3D mesh) numbers or expression strings in
    ``names``."""
    what = f"a number or an expression string in {', '.join(names)}"
    item = by_kind(what, number=float, string=expression(*names))
    return Annotated[list[item], Field(min_length=2, max_length=3)]  # type: ignore[valid-type]
