"""Writing: a Scenario or spec back to file data (:func:`scenario_to_dict`), to YAML/JSON text and
to a file, atomically (:func:`save_scenario`).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

import yaml

from uavplan.io.atomic import write_text_atomic
from uavplan.io.scenario_file.build import builtin_terrain
from uavplan.io.scenario_file.errors import ScenarioFileError
from uavplan.io.scenario_file.read import JSON_SUFFIXES, YAML_SUFFIXES, parse_scenario_spec
from uavplan.io.scenario_file.schema import MAX_YAML_BYTES, ScenarioSpec, dump_spec
from uavplan.world import UAV, Scenario
from uavplan.world.terrain import BUILTIN_TERRAINS


def _num_or_none(v: float) -> float | None:
    return None if math.isinf(v) else float(v)


def _uav_data(uav: UAV) -> dict[str, Any]:
    """A UAV's block: every limit, the optional ones only when given (null means the default)."""
    out: dict[str, Any] = {
        "speed": uav.speed,
        "turn_radius": uav.turn_radius,
        "s1": uav.s1,
        "s2": uav.s2,
        "size": uav.size,
        "min_speed": uav.min_speed,
    }
    for name in ("max_speed", "max_climb_angle", "max_descent_angle"):
        value = getattr(uav, name)
        if value is not None:
            out[name] = value
    if uav.s2_axes is not None:
        out["s2_axes"] = list(uav.s2_axes)
    if uav.airframe is not None:
        out["airframe"] = uav.airframe
    return out


def spec_from_scenario(scenario: Scenario) -> ScenarioSpec:
    """The file-level spec of a Scenario built in code (absolute task z, full bounds).

    Raises:
        ScenarioFileError: the terrain is not a built-in one (a file cannot embed a DEM).
    """
    s = scenario
    terrain: dict[str, Any] | None = None
    if s.terrain is not None:
        t = s.terrain
        same = False
        if t.name in BUILTIN_TERRAINS:
            b = builtin_terrain(t.name)
            same = (t.shape, t.x0, t.y0, t.dx, t.dy) == (b.shape, b.x0, b.y0, b.dx, b.dy)
        if not same:
            raise ScenarioFileError(
                [
                    f"{s.name}: terrain = {t.name!r}: not a built-in terrain; a scenario file "
                    "cannot embed a DEM (save the heights to .npy and use terrain.file)"
                ]
            )
        terrain = {"builtin": t.name}
    data: dict[str, Any] = {
        "name": s.name,
        "description": s.description,
        "bounds": {"lower": list(s.bounds.lower), "upper": list(s.bounds.upper)},
        "terrain": terrain,
        "cylinders": [
            {
                "center": list(c.center),
                "radius": c.radius,
                "z_min": _num_or_none(c.z_min),
                "z_max": _num_or_none(c.z_max),
                "margin": c.margin,
            }
            for c in s.cylinders
        ],
        "circles": [
            {"center": list(c.center), "radius": c.radius, "margin": c.margin} for c in s.circles
        ],
        "polygons": [
            {"vertices": [list(v) for v in p.vertices], "margin": p.margin} for p in s.polygons
        ],
        "danger_areas": [{"center": list(d.center), "radius": d.radius} for d in s.danger_areas],
        "uncertain_areas": [
            {"x": u.x, "y": u.y, "width": u.width, "height": u.height, "revealed": u.revealed}
            for u in s.uncertain_areas
        ],
        "moving_obstacles": [
            {
                "radius": m.radius,
                "times": m.times.tolist(),
                "positions": m.positions[:, : s.dim].tolist(),
            }
            for m in s.moving_obstacles
        ],
        "uav": _uav_data(s.uav),
        "task_z": "absolute",
        "tasks": [
            {"id": t.id, "start": list(t.start), "goal": list(t.goal), "start_time": t.start_time}
            for t in s.tasks
        ],
        "planning": {"cost": s.cost, "n_waypoints": s.n_waypoints},
    }
    if s.altitude is not None:
        a = s.altitude
        data["altitude"] = {"min": a.min, "max": a.max, "reference": a.reference}
    if terrain is None:
        del data["terrain"]
    if s.origin is not None:
        data["origin"] = s.origin.record()
    return _validated(data, s.name)


def _validated(data: Any, source: str) -> ScenarioSpec:
    return parse_scenario_spec(data, source)


def scenario_to_dict(spec: ScenarioSpec | Mapping[str, Any] | Scenario) -> dict[str, Any]:
    """The file form of a scenario: the validated spec dumped to plain data.

    Accepts a :class:`ScenarioSpec`, a mapping (validated first) or a :class:`Scenario` (its
    ``metadata["spec"]`` when it was loaded from a file, else :func:`spec_from_scenario`). Keys
    that were not given are left out, so a file round-trips to the same content.
    """
    if isinstance(spec, ScenarioSpec):
        model = spec
    elif isinstance(spec, Scenario):
        stored = spec.metadata.get("spec")
        if isinstance(stored, Mapping):
            model = _validated(dict(stored), spec.metadata.get("source", spec.name))
        else:
            model = spec_from_scenario(spec)
    else:
        model = _validated(spec, "<scenario>")
    return dump_spec(model)


def _json_text(obj: Any, indent: int = 0) -> str:
    """JSON with lists of plain numbers/strings kept on one line."""
    pad = "  " * (indent + 1)
    end = "  " * indent
    if isinstance(obj, dict):
        if not obj:
            return "{}"
        items = [f"{pad}{json.dumps(k)}: {_json_text(v, indent + 1)}" for k, v in obj.items()]
        return "{\n" + ",\n".join(items) + "\n" + end + "}"
    if isinstance(obj, list):
        if all(not isinstance(v, dict | list) for v in obj) or all(
            isinstance(v, list) and all(not isinstance(w, dict | list) for w in v) for v in obj
        ):
            return json.dumps(obj, ensure_ascii=False)
        return "[\n" + ",\n".join(pad + _json_text(v, indent + 1) for v in obj) + "\n" + end + "]"
    return json.dumps(obj, ensure_ascii=False)


_HEADER = "# uavplan scenario file (format: docs/scenario-format.md)\n"


def dumps_scenario(data: Mapping[str, Any], fmt: Literal["yaml", "json"]) -> str:
    """Text of a scenario file dict in ``"yaml"`` or ``"json"``."""
    if fmt == "json":
        return _json_text(dict(data)) + "\n"
    body = yaml.safe_dump(
        dict(data), sort_keys=False, default_flow_style=None, allow_unicode=True, width=100
    )
    return _HEADER + body


def _rebase(name: str, from_dir: Path, to_dir: Path) -> str:
    f = Path(name).expanduser()
    if f.is_absolute():
        return name
    target = (from_dir / f).resolve()
    try:
        return Path(os.path.relpath(target, to_dir.resolve())).as_posix()
    except ValueError:  # another drive (Windows)
        return str(target)


def _rebase_terrain_file(data: dict[str, Any], from_dir: Path, to_dir: Path) -> None:
    """The files a scenario names (DEM, SRTM tiles, GeoJSON no-fly zones), relative to
    ``from_dir``, made relative to ``to_dir`` where the scenario is written."""
    terrain = data.get("terrain")
    if isinstance(terrain, dict):
        if terrain.get("file"):
            terrain["file"] = _rebase(terrain["file"], from_dir, to_dir)
        if terrain.get("srtm"):
            terrain["srtm"] = [_rebase(n, from_dir, to_dir) for n in terrain["srtm"]]
    if data.get("no_fly"):
        data["no_fly"] = [_rebase(n, from_dir, to_dir) for n in data["no_fly"]]


def _atomic_write(path: Path, text: str) -> None:
    where = str(path)
    parent = path.parent
    if not parent.is_dir():
        raise ScenarioFileError(
            [f"{where}: cannot write: directory {os.path.abspath(parent)} does not exist"]
        )
    if path.is_dir():
        raise ScenarioFileError([f"{where}: cannot write: it is a directory"])
    try:
        write_text_atomic(path, text)
    except OSError as exc:
        raise ScenarioFileError([f"{where}: cannot write: {exc.strerror or exc}"]) from None


def save_scenario(
    spec: ScenarioSpec | Mapping[str, Any] | Scenario,
    path: str | Path,
    *,
    base_dir: str | Path | None = None,
) -> Path:
    """Write a scenario file, YAML (``.yaml``/``.yml``) or JSON (``.json``) by ``path``'s suffix.

    The file is written to a temporary file beside ``path`` and moved over it, so an existing
    file is replaced whole or not at all. A relative ``terrain.file`` is rewritten relative to the
    new file's directory (it is taken relative to ``base_dir``, or to the directory the Scenario
    was loaded from, or else to the current directory).

    Raises:
        ScenarioFileError: invalid content, an unknown suffix, or a failed write (the old file,
            if any, is left intact).
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in YAML_SUFFIXES + JSON_SUFFIXES:
        raise ScenarioFileError(
            [f"{path}: cannot write: unknown suffix {suffix or '(none)'!r} (.yaml, .yml, .json)"]
        )
    data = scenario_to_dict(spec)
    if base_dir is None and isinstance(spec, Scenario):
        base_dir = spec.metadata.get("base_dir")
    _rebase_terrain_file(data, Path(base_dir) if base_dir else Path.cwd(), p.parent)
    text = dumps_scenario(data, "json" if suffix in JSON_SUFFIXES else "yaml")
    size = len(text.encode("utf-8"))
    if suffix in YAML_SUFFIXES and size > MAX_YAML_BYTES:
        raise ScenarioFileError(
            [
                f"{path}: cannot write: {size:,} bytes of YAML, more than a YAML scenario file may "
                f"hold ({MAX_YAML_BYTES:,}); write it as .json"
            ]
        )
    _atomic_write(p, text)
    return p
