"""The ``[adapt]`` table: its settings reach the adaptive run, and settings that
contradict each other or that the adaptive path cannot honour are refused in one line
naming the key, before anything is built or solved."""

from __future__ import annotations

import tomllib

import pytest

from conftest import CONFIG_3D, small_config
from vemwear.config import ConfigError, parse_config


def _config(adapt: dict | None, **sections: dict) -> dict:
    data = tomllib.loads(small_config("adapt", **sections))
    if adapt is not None:
        data["adapt"] = adapt
    return data


def test_the_settings_reach_the_adaptive_run() -> None:
    keys = {"every": 3, "theta": 0.4, "max_cells": 200, "coarsen": True}
    cfg = parse_config(_config({**keys, "coarsen_fraction": 0.2, "max_level": 2}))
    a = cfg.adapt
    assert a is not None
    assert (a.every, a.theta, a.max_cells, a.target_error) == (3, 0.4, 200, None)
    assert (a.coarsen, a.max_level, a.max_difference) == (0.2, 2, 1)
    off = parse_config(_config({"every": 2, "target_error": 1e-3})).adapt
    assert off is not None and off.coarsen == 0.0 and off.target_error == 1e-3
    assert a.curved and off.curved  # new boundary vertices onto curved parts by default
    flat = parse_config(_config({"every": 2, "max_cells": 200, "curved": False})).adapt
    assert flat is not None and not flat.curved
    assert parse_config(_config(None)).adapt is None
    # whole runs first: without every the mesh they make stays for every level
    runs = parse_config(_config({"passes": 3, "max_cells": 200, "estimator": "wear"}))
    assert runs.adapt is not None and runs.adapt.passes == 3
    assert runs.adapt.every == len(runs.problem.time.t) - 1


@pytest.mark.parametrize(
    ("adapt", "sections", "message"),
    [
        ({"every": 2}, {}, "[adapt] needs max_cells or target_error"),
        ({"max_cells": 100}, {}, "[adapt] needs every (time levels between mesh changes)"),
        ({"max_cells": 100, "passes": 1}, {}, "[adapt] needs every"),
        ({"max_cells": 100, "passes": 0}, {}, "[adapt] needs every"),
        ({"every": 2, "max_cells": 100, "passes": 0}, {}, "[adapt] passes input should be"),
        ({"every": 0, "max_cells": 100}, {}, "[adapt] every input should be greater"),
        ({"every": 2, "max_cells": 100, "theta": 0.0}, {}, "[adapt] theta input should be"),
        ({"every": 2, "max_cells": 100, "theta": 1.5}, {}, "[adapt] theta input should be"),
        ({"every": 2, "target_error": 0.0}, {}, "[adapt] target_error input should be"),
        ({"every": 2, "max_cells": 10}, {}, "[adapt] max_cells = 10 is below the initial"),
        ({"every": 2, "max_cells": 100, "coarsen": 1}, {}, "[adapt] coarsen must be true"),
        ({"every": 2, "max_cells": 100, "coarsen_fraction": 0.2}, {}, "but coarsen is not"),
        (
            {"every": 2, "max_cells": 100, "theta": 0.8, "coarsen": True, "coarsen_fraction": 0.3},
            {},
            "[adapt] coarsen_fraction = 0.3 and theta = 0.8 overlap",
        ),
        ({"every": 2, "max_cells": 100, "estimator": "zz"}, {}, "[adapt] estimator must be"),
        ({"every": 2, "max_cells": 100, "max_cell": 3}, {}, "did you mean 'max_cells'"),
        ({"every": 2, "max_cells": 100}, {"output": {"store_u": "all"}}, "[output] store_u"),
        ({"every": 2, "max_cells": 100}, {"output": {"every": 2}}, "[output] every"),
        (
            {"every": 2, "max_cells": 100},
            {"time": {"cycle_jump": {"cycles": 4}}},
            "[time] cycle_jump does not go with [adapt]",
        ),
    ],
)
def test_inconsistent_settings_are_refused(adapt: dict, sections: dict, message: str) -> None:
    with pytest.raises(ConfigError) as info:
        parse_config(_config(adapt, **sections), source="case.toml")
    text = str(info.value)
    assert text.startswith("case.toml: ") and message in text and "\n" not in text


def test_a_3d_mesh_is_refused() -> None:
    data = tomllib.loads(CONFIG_3D)
    data["adapt"] = {"every": 2, "max_cells": 100}
    with pytest.raises(ConfigError, match=r"\[adapt\] .* 2D meshes; \[mesh\] is 3D"):
        parse_config(data, source="case.toml")


def test_the_plan_counts_every_level_on_the_largest_mesh() -> None:
    from vemwear.runner.plan import estimate_config

    plain = estimate_config(parse_config(_config(None, output={"times": [1.0]})))
    adaptive = estimate_config(parse_config(_config({"every": 2, "max_cells": 320})))
    bounded = estimate_config(parse_config(_config({"every": 2, "target_error": 1.0})))
    assert adaptive.disk > bounded.disk > plain.disk
