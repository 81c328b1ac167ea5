"""The JSON Schema of configuration files and the key tables of ``docs/config.md``.

The tables are generated from the schema models (types, defaults, field
descriptions) into ``docs/config.md`` between ``<!-- schema: NAME -->`` and
``<!-- /schema -->``; a test checks that the file is up to date. Rewrite it with
``python -m vemwear.config.reference docs/config.md``.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path
from typing import Any

from pydantic import BaseModel

from ..mesh.registry import FAMILIES
from . import schema as s
from .mesh_forms import MESH_FORMS, MeshFile
from .sections import Section

__all__ = ["config_json_schema", "reference_tables", "update_reference"]

_SIMPLE = ("number", "integer", "string", "boolean")


def _build_all() -> None:
    """Build every table's deferred validator and serializer.

    A JSON Schema encodes defaults that are tables with their classes' serializers,
    which ``defer_build`` leaves unbuilt until a first validation (pydantic < 2.14
    then fails with "'MockValSer' object is not an instance of 'SchemaSerializer'").
    """
    todo: list[type[BaseModel]] = [Section]
    while todo:
        cls = todo.pop()
        todo.extend(cls.__subclasses__())
        cls.model_rebuild(force=True)


def config_json_schema() -> dict[str, Any]:
    """The JSON Schema of a configuration file (for editors' completion and checks)."""
    _build_all()
    return s.ConfigFile.model_json_schema()


def _type(js: dict[str, Any], defs: dict[str, Any]) -> str:
    """A short text for the type of a JSON Schema (its title if not a generated one)."""
    if js.get("title") and not js["title"][0].isupper():
        return str(js["title"])
    if "$ref" in js:
        return _type(defs[js["$ref"].rsplit("/", 1)[-1]], defs)
    if "oneOf" in js or "anyOf" in js:
        forms = [_type(x, defs) for x in js.get("oneOf", js.get("anyOf", []))]  # no TOML null
        forms = [f for f in forms if f != "null"]
        return " or ".join(dict.fromkeys(forms))
    if "const" in js or "enum" in js:
        return ", ".join(f'`"{v}"`' for v in js.get("enum", [js.get("const")]))
    t = js.get("type")
    if t == "array":
        item = _type(js["items"], defs)
        n = js.get("minItems") if js.get("minItems") == js.get("maxItems") else None
        return f"array of {f'{n} ' if n else ''}" + (f"{item}s" if item in _SIMPLE else f"({item})")
    return str(js["title"] if t == "object" else t)


def _value(v: Any) -> str:
    if v is None or isinstance(v, BaseModel):
        return "—"
    if isinstance(v, bool):
        return f"`{str(v).lower()}`"
    if isinstance(v, list | tuple):
        return "`[" + ", ".join(_value(x).strip("`") for x in v) + "]`"
    return f'`"{v}"`' if isinstance(v, str) else f"`{v!r}`"


def _rows(model: type[BaseModel], skip: tuple[str, ...] = ()) -> list[list[str]]:
    js = model.model_json_schema()
    rows = []
    for name, f in model.model_fields.items():
        key = f.alias or name
        if key not in skip:
            t = _type(js["properties"][key], js.get("$defs", {}))
            default = "required" if f.is_required() else _value(f.default)
            rows.append([f"`{key}`", t, default, (f.description or "").replace("|", "\\|")])
    return rows


def _table(head: list[str], rows: list[list[str]]) -> str:
    lines = [head, ["---"] * len(head), *rows]
    return "\n".join("| " + " | ".join(r) + " |" for r in lines)


def reference_tables() -> dict[str, str]:
    """The key tables of ``docs/config.md`` by name."""
    _build_all()
    head = ["key", "type", "default", "meaning"]
    fams = [
        [f"`{f.name}`", ", ".join(f"`{a}`" for a in f.aliases) or "—", f.description]
        for f in FAMILIES.values()
    ]
    options = [
        [f"`{n}`", *r]
        for n, m in MESH_FORMS.items()
        if n != "file"
        for r in _rows(m, ("generator",))
    ]
    time: dict[str, list[str]] = {}  # T is in every form, the others in one each
    needs_T = [f"`{k}`" for k, m in s.TIME_FORMS.items() if m.model_fields["T"].is_required()]
    for form, m in s.TIME_FORMS.items():
        for key, t, _, text in _rows(m):
            row = time.setdefault(key, [key, t, "—", ""])
            if key == "`T`":
                row[3] += f"{'; ' * bool(row[3])}with `{form}`: {text}"
            elif text not in row[3]:  # keys of every form (cycle_jump) once
                row[3] += text
    time["`T`"][2] = f"required with {', '.join(needs_T)}"
    laws = [[f'`"{n}"`', *r] for n, m in s.LAWS.items() for r in _rows(m, ("type",))]
    tables = {
        "top": _table(head, _rows(s.ConfigFile)[:1]),
        "mesh": _table(head, _rows(MeshFile)),
        "mesh.families": _table(["generator", "also called", "meshes"], fams),
        "mesh.options": _table(["generator", *head], options),
        "contact.p": _table(["type", *head], laws),
        "contact.table": _table(head, _rows(s.CoefficientTable)),
        "contact.v_star": _table(head, _rows(s.VelocityTable)),
        "contact.rotation": _table(head, _rows(s.Rotation)),
        "time": _table(head, list(time.values())),
        "boundary.displacement": _table(head, _rows(s.DisplacementPart)),
        "time.cycle_jump": _table(head, _rows(s.CycleJumpTable)),
        "boundary.traction": _table(head, _rows(s.TractionPart)),
        "boundary.rigid": _table(head, _rows(s.RigidPartTable)),
    }
    for name in ("boundary", "material", "vem", "loads", "contact", "solver", "output", "adapt"):
        tables[name] = _table(head, _rows(getattr(s, name.title())))
    return tables


def update_reference(text: str) -> str:
    """``text`` (``docs/config.md``) with its generated tables brought up to date."""
    tables = reference_tables()

    def fill(m: re.Match[str]) -> str:
        return f"{m.group(1)}\n{tables[m.group(2)]}\n{m.group(3)}"

    return re.sub(r"(<!-- schema: ([\w.]+) -->)\n.*?\n?(<!-- /schema -->)", fill, text, flags=re.S)


if __name__ == "__main__":  # pragma: no cover - python -m vemwear.config.reference FILE
    doc = Path(sys.argv[1])
    doc.write_text(update_reference(doc.read_text(encoding="utf-8")), encoding="utf-8")
