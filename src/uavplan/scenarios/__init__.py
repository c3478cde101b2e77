"""Built-in scenarios, shipped as scenario files (``<name>.yaml`` beside this module).

* ``spso``: the SPSO benchmark (Phung & Ha 2021) on its ChrismasTerrain DEM.
* ``simple2d``: a small 2-D scene with circles and a non-convex polygon.
* ``jacksboro``: a 3-D scene on the Jacksboro fault DEM with finite cylinders and areas.
* ``topobathy``: a long sea-to-mountains mission on the Pacific Northwest DEM.
* ``ppswarm1`` ... ``ppswarm4``: the PPSwarm scenarios (SPSO terrain, 6-20 cylinders, 40 UAVs).
* ``open``: the PPSwarm map with no terrain and no obstacles (large fleets, the crowd alone).
* ``dense``: the PPSwarm setup with 40 generated cylinders and narrow passages
  (:func:`uavplan.scenarios.generators.dense_cylinders` reproduces its cylinders).

:func:`resolve` takes a built-in name or a scenario file path.
"""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

import yaml

if TYPE_CHECKING:
    from uavplan.world import Scenario

__all__ = ["builtin_names", "builtin_path", "list_builtin", "load_builtin", "resolve"]


def _dir() -> Path:
    return Path(str(resources.files(__name__)))


def builtin_names() -> list[str]:
    """Names of the built-in scenarios, sorted."""
    return sorted(p.stem for p in _dir().glob("*.yaml"))


def builtin_path(name: str) -> Path:
    """The YAML file of a built-in scenario.

    Raises:
        ScenarioFileError: no built-in of that name.
    """
    names = builtin_names()
    if name not in names:
        from uavplan.io.scenario_file import ScenarioFileError

        raise ScenarioFileError(
            [f"{name}: no such built-in scenario (choose from {', '.join(names)})"]
        )
    return _dir() / f"{name}.yaml"


def list_builtin() -> list[tuple[str, str]]:
    """``(name, description)`` of every built-in scenario, sorted by name."""
    out: list[tuple[str, str]] = []
    for name in builtin_names():
        data = yaml.safe_load((_dir() / f"{name}.yaml").read_text(encoding="utf-8"))
        description = data.get("description", "") if isinstance(data, dict) else ""
        out.append((name, " ".join(str(description).split())))
    return out


def load_builtin(name: str) -> Scenario:
    """Load a built-in scenario by name (``metadata["builtin"]`` holds the name)."""
    from uavplan.io.scenario_file import load_scenario

    scenario = load_scenario(builtin_path(name))
    scenario.metadata["builtin"] = name
    return scenario


def resolve(name_or_path: str | Path) -> Scenario:
    """A built-in scenario by name, a scene of the RGG-PSO+ family by its name
    (``rgg-n07-i042``, optionally ``-s<root seed>``), or else a scenario file by path; any of
    them followed by ``@N`` (``ppswarm1@200``, ``city.yaml@40``): the same world with a
    generated fleet of N UAVs (:func:`uavplan.world.fleet_tasks.with_fleet`, with the pattern
    and seed of the world's own ``fleet`` block if it has one), named ``NAME@N``.

    Raises:
        ScenarioFileError: neither a built-in name nor an existing file, or an invalid file,
            or a fleet of N UAVs that does not fit.
    """
    text = str(name_or_path)
    if text in builtin_names():
        return load_builtin(text)
    at = re.fullmatch(r"(.+)@(\d+)", text)
    if at and not Path(text).is_file():  # a folder of that name is no scenario file
        import dataclasses

        from uavplan.world.fleet_tasks import with_fleet

        base = resolve(at.group(1))
        fleet = dict(base.metadata.get("fleet") or {})
        try:
            sc = with_fleet(base, int(at.group(2)), seed=int(fleet.get("seed", 0)),
                            pattern=str(fleet.get("pattern", "crossing")),
                            min_spacing=fleet.get("min_spacing"))  # fmt: skip
        except ValueError as exc:
            from uavplan.io.scenario_file import ScenarioFileError

            raise ScenarioFileError([f"{text}: {exc}"]) from None
        # the planning world places a generated fleet again when an execution model's
        # tracking error leaves some of these tasks outside the world it is planned in
        sc.metadata["generated_fleet"] = {"n_uavs": int(at.group(2)),
                                          "seed": int(fleet.get("seed", 0)),
                                          "pattern": str(fleet.get("pattern", "crossing")),
                                          "min_spacing": fleet.get("min_spacing")}  # fmt: skip
        return dataclasses.replace(sc, name=text)
    m = re.fullmatch(r"rgg-n(\d+)-i(\d+)(?:-s(\d+))?", text)
    if m:  # a scene of the RGG-PSO+ family, generated deterministically
        from uavplan.scenarios.generators import rgg_scenario

        return rgg_scenario(int(m.group(1)), int(m.group(2)), int(m.group(3) or 0))
    path = Path(name_or_path)
    if path.exists():
        from uavplan.io.scenario_file import load_scenario

        return load_scenario(path)
    from uavplan.io.scenario_file import ScenarioFileError

    raise ScenarioFileError(
        [
            f"{text}: no such scenario file, and not a built-in scenario "
            f"(built-ins: {', '.join(builtin_names())})"
        ]
    )
