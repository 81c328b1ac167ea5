"""The configuration reference page, generated from the schema at build time.

The tables come from :func:`vemwear.config.reference.reference_tables`, the same
function that keeps the tables of ``docs/config.md`` up to date, so the site and the
Markdown page cannot disagree with the pydantic models of :mod:`vemwear.config.schema`.
"""

from __future__ import annotations

import json
from pathlib import Path

#: (table name, heading, text before the table), in the order of a configuration file.
SECTIONS: tuple[tuple[str, str, str], ...] = (
    ("top", "Top level", ""),
    ("mesh", "`[mesh]` from a file", "A mesh read from a file (meshio) instead of a generator."),
    ("mesh.families", "`[mesh]` generators", "`generator = NAME` selects a mesh family:"),
    ("mesh.options", "`[mesh]` generator options", "The keys each generator takes:"),
    ("boundary", "`[boundary]`", "Boundary parts by side or by the mesh file's groups."),
    ("boundary.displacement", "`[[boundary.displacement]]`", "Prescribed displacements."),
    ("boundary.traction", "`[[boundary.traction]]`", "Tractions on named parts."),
    (
        "boundary.rigid",
        "`[[boundary.rigid]]`",
        "Rigid parts: a holder that translates as one body, loaded or prescribed.",
    ),
    ("material", "`[material]`", "Lamé coefficients of the body."),
    ("vem", "`[vem]`", "The virtual element space."),
    ("loads", "`[loads]`", "Body force f1 and the traction f2."),
    ("contact", "`[contact]`", "The contact law, friction, wear and the foundation."),
    ("contact.p", "`[contact] p`", "The compliance law p(r) of the soft layer, by `type`:"),
    ("contact.table", "`[contact]` tables", "A coefficient given as a table along the boundary:"),
    ("contact.v_star", "`[contact] v_star` as a table", "The foundation velocity in time:"),
    (
        "contact.rotation",
        "`[contact] v_star` as a rotation",
        "A counterface turning about an axis:",
    ),
    ("time", "`[time]`", "The time grid, in one of its forms."),
    ("time.cycle_jump", "`[time] cycle_jump`", "Cycle jumps of a periodic history."),
    ("solver", "`[solver]`", "The step solver."),
    ("output", "`[output]`", "What a run writes."),
    ("adapt", "`[adapt]`", "Adaptive meshes in time: the estimator, marking and mesh changes."),
)


def render() -> str:
    """The page's Markdown: every key table of the schema, and its JSON Schema."""
    from vemwear.config.reference import config_json_schema, reference_tables

    tables = reference_tables()
    missing = set(tables) - {name for name, _, _ in SECTIONS}
    if missing:  # a table added to the schema must get a place on the page
        raise RuntimeError(f"config reference: no section for tables {sorted(missing)}")
    out = [
        "# Configuration keys",
        "",
        "Generated from the schema (`vemwear.config.schema`) when the site is built: every",
        "key of a configuration file with its type, default and meaning. The guide with",
        "examples, the expression language and the checks is [](../config.md);",
        "`vemwear schema` prints the JSON Schema below for editors.",
        "",
    ]
    for name, heading, text in SECTIONS:
        out += [f"## {heading}", ""]
        if text:
            out += [text, ""]
        out += [tables[name], ""]
    out += [
        "## JSON Schema",
        "",
        "```{code-block} json",
        ":class: vemwear-schema",
        json.dumps(config_json_schema(), indent=1),
        "```",
        "",
    ]
    return "\n".join(out)


def write_config_reference(path: Path) -> None:
    """Write the page if its text changed (an unchanged page is not rebuilt)."""
    text = render()
    if not path.is_file() or path.read_text(encoding="utf-8") != text:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
