"""Reading: YAML/JSON text (duplicate keys rejected) to data, data to a validated spec and to a
Scenario (:func:`load_scenario`, :func:`scenario_from_dict`).
"""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Hashable, Mapping
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from uavplan.io.scenario_file.build import build_scenario
from uavplan.io.scenario_file.errors import (
    Problems,
    ScenarioFileError,
    fmt_value,
    validation_problems,
)
from uavplan.io.scenario_file.schema import MAX_FILE_BYTES, MAX_YAML_BYTES, ScenarioSpec
from uavplan.world import Scenario
from uavplan.world.terrain import not_a_regular_file

YAML_SUFFIXES = (".yaml", ".yml")
JSON_SUFFIXES = (".json",)


def _libyaml_limits_nesting() -> bool:
    """True when PyYAML has libyaml 0.2.6 or later, which refuses nesting deeper than 1,000
    levels. Older libyaml (PyYAML 6.0.3 bundles 0.2.5) has no limit, and its composer recurses
    in C: ``[`` x 100,000 overflows the C stack and kills the process (a segfault, not an
    exception), so with it we read with the pure-Python parser, whose recursion Python catches.
    """
    if not getattr(yaml, "__with_libyaml__", False):
        return False
    try:
        from yaml import _yaml

        return tuple(_yaml.get_version()) >= (0, 2, 6)
    except (ImportError, AttributeError, TypeError):
        return False


def _construct_mapping(loader: Any, node: yaml.MappingNode) -> dict[Any, Any]:
    seen: set[Any] = set()
    for key_node, _ in node.value:
        if key_node.tag == "tag:yaml.org,2002:merge":  # '<<: *anchor' (merged keys may repeat)
            continue
        key = loader.construct_object(key_node, deep=True)
        if isinstance(key, Hashable):
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r}", key_node.start_mark
                )
            seen.add(key)
    return loader.construct_mapping(node, deep=True)


def _construct_text(loader: Any, node: yaml.ScalarNode) -> str:
    return str(loader.construct_scalar(node))


def _unique_key_loader(base: Any) -> Any:
    """A safe YAML loader on ``base`` that rejects duplicate keys (PyYAML keeps the last one
    silently). The constructor is the safe one either way: no tag builds a Python object, runs
    code or reads a file."""
    loader: Any = type("UniqueKeyLoader", (base,), {})
    loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)
    # No field of a scenario is a date: a timestamp-like scalar stays the text it is, so the
    # schema names the field and value ("2026-13-45" is not a date PyYAML can build: ValueError).
    loader.add_constructor("tag:yaml.org,2002:timestamp", _construct_text)
    return loader


#: Pure-Python parsing (safe at any nesting: its recursion raises RecursionError).
PY_LOADER: Any = _unique_key_loader(yaml.SafeLoader)
#: libyaml's parser where it is safe (above; about 3 times faster), else the pure-Python one.
LOADER: Any = _unique_key_loader(yaml.CSafeLoader) if _libyaml_limits_nesting() else PY_LOADER


def _no_duplicate_pairs(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(f"duplicate key {key!r}")
        out[key] = value
    return out


def _parse_text(text: str, fmt: str, source: str) -> Any:
    if fmt == "json":
        try:
            return json.loads(text, object_pairs_hook=_no_duplicate_pairs)
        except json.JSONDecodeError as exc:
            raise ScenarioFileError(
                [f"{source}: line {exc.lineno}, column {exc.colno}: not valid JSON: {exc.msg}"]
            ) from None
        except ValueError as exc:
            raise ScenarioFileError([f"{source}: not valid JSON: {exc}"]) from None
        except RecursionError:
            raise ScenarioFileError([f"{source}: not valid JSON: nested too deeply"]) from None
    try:
        return yaml.load(text, Loader=LOADER)  # a SafeLoader subclass
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
        what = " ".join(str(exc.problem or exc.context or "syntax error").split())
        raise ScenarioFileError([f"{source}: {where}not valid YAML: {what}"]) from None
    except yaml.YAMLError as exc:
        what = " ".join(str(exc).split())
        raise ScenarioFileError([f"{source}: not valid YAML: {what}"]) from None
    except RecursionError:
        raise ScenarioFileError([f"{source}: not valid YAML: nested too deeply"]) from None
    except (ValueError, TypeError, OverflowError) as exc:  # an explicit tag on the wrong text
        what = " ".join(str(exc).split())[:200]  # ('!!int abc', '!!float x'): a constructor's
        raise ScenarioFileError([f"{source}: not valid YAML: {what}"]) from None  # own error


def _format_for(path: Path) -> str:
    return "json" if path.suffix.lower() in JSON_SUFFIXES else "yaml"


def read_scenario_data(path: str | Path) -> Any:
    """The parsed (not yet validated) content of a scenario file.

    Raises:
        ScenarioFileError: the file is missing, unreadable, binary, or not YAML/JSON.
    """
    p = Path(path)
    source = str(path)
    if not p.exists():
        raise ScenarioFileError([f"{source}: no such file ({os.path.abspath(p)})"])
    why = not_a_regular_file(p)
    if why is not None:
        tail = ", not a scenario file" if why.startswith("is ") else ""
        raise ScenarioFileError([f"{source}: {why}{tail}"])
    try:
        size = p.stat().st_size
    except OSError as exc:
        raise ScenarioFileError([f"{source}: cannot read: {exc.strerror or exc}"]) from None
    if size > MAX_FILE_BYTES:
        raise ScenarioFileError(
            [f"{source}: {size:,} bytes; a scenario file is at most {MAX_FILE_BYTES:,} bytes "
             "(a DEM goes in its own file)"]
        )  # fmt: skip
    if size > MAX_YAML_BYTES and _format_for(p) == "yaml":
        raise ScenarioFileError(
            [f"{source}: {size:,} bytes of YAML; a YAML scenario file is at most "
             f"{MAX_YAML_BYTES:,} bytes (YAML reads at about 1 MB in a few seconds): write a "
             f"larger scene as JSON (.json, up to {MAX_FILE_BYTES:,} bytes)"]
        )  # fmt: skip
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise ScenarioFileError([f"{source}: cannot read: {exc.strerror or exc}"]) from None
    if b"\x00" in data:
        raise ScenarioFileError([f"{source}: not a YAML or JSON file (binary data)"])
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ScenarioFileError(
            [f"{source}: not a YAML or JSON file (not UTF-8 text: byte {exc.start})"]
        ) from None
    return _parse_text(text, _format_for(p), source)


def _check_mapping(data: Any, source: str) -> dict[str, Any]:
    if data is None:
        raise ScenarioFileError([f"{source}: the file is empty (expected a mapping of keys)"])
    if not isinstance(data, Mapping):
        kind = "a list" if isinstance(data, list) else f"a single value {fmt_value(data, 60)}"
        raise ScenarioFileError(
            [f"{source}: the top level must be a mapping of keys (name, tasks, ...), got {kind}"]
        )
    return dict(data)


def parse_scenario_spec(data: Any, source: str = "<scenario>") -> ScenarioSpec:
    """Validate parsed file content against the schema (structure only, no semantic checks)."""
    mapping = _check_mapping(data, source)
    problems = Problems(source, mapping)
    try:
        return ScenarioSpec.model_validate(mapping)
    except ValidationError as exc:
        validation_problems(exc, problems)
        problems.raise_if_any()
        raise  # pragma: no cover - a ValidationError always has errors


_LIST_KEYS = (
    "cylinders",
    "circles",
    "polygons",
    "danger_areas",
    "uncertain_areas",
    "moving_obstacles",
    "tasks",
)
#: Top-level keys that can be left out, after their problems are reported, without changing any
#: other check (they do not affect bounds, obstacles or where tasks start and end).
_DROPPABLE_KEYS = ("description", "uav", "planning")


def _pruned(
    data: dict[str, Any], exc: ValidationError
) -> tuple[dict[str, Any], dict[str, list[int]]] | None:
    """``data`` without the parts that failed validation, when the rest can still be checked.

    Invalid list items (an obstacle, a task) and unknown or droppable top-level keys are left
    out; any other structural problem (bounds, terrain, altitude, ...) stops the checks there.
    Returns the pruned data and, per pruned list, the file index of each remaining item.
    """
    drop_keys: set[str] = set()
    drop_items: dict[str, set[int]] = {}
    fill_name = False
    for err in exc.errors():
        loc = tuple(err["loc"])
        if not loc or not isinstance(loc[0], str):
            return None
        top = loc[0]
        if (len(loc) == 1 and err["type"] == "extra_forbidden") or top in _DROPPABLE_KEYS:
            drop_keys.add(top)
        elif top == "name" and len(loc) == 1:
            fill_name = True
        elif top in _LIST_KEYS and len(loc) >= 2 and isinstance(loc[1], int):
            drop_items.setdefault(top, set()).add(loc[1])
        else:
            return None
    out = {k: v for k, v in data.items() if k not in drop_keys}
    if fill_name:
        out["name"] = "unnamed"
    index_map: dict[str, list[int]] = {}
    for key, bad in drop_items.items():
        items = out[key]
        keep = [i for i in range(len(items)) if i not in bad]
        out[key] = [items[i] for i in keep]
        index_map[key] = keep
    if not out.get("tasks") and out.get("fleet") is None:
        return None
    return out, index_map


def load_scenario(path: str | Path) -> Scenario:
    """Read a scenario file (``.yaml``/``.yml``/``.json``; YAML for other suffixes).

    The returned Scenario keeps the validated file-level spec in ``metadata["spec"]`` (a plain
    dict), the file in ``metadata["source"]`` and its directory in ``metadata["base_dir"]``.

    Raises:
        ScenarioFileError: with every problem found, one line each.
    """
    p = Path(path)
    data = read_scenario_data(p)
    return scenario_from_dict(data, source=str(path), base_dir=p.resolve().parent)


def scenario_from_dict(
    data: Any, source: str = "<scenario>", base_dir: str | Path | None = None
) -> Scenario:
    """Build a Scenario from parsed file content.

    Args:
        data: the mapping read from a file (or written by hand).
        source: the name used in problem lines (usually the file name).
        base_dir: directory relative terrain file paths start from (default: the current one).

    Raises:
        ScenarioFileError: with every problem found, one line each.
    """
    mapping = _check_mapping(data, source)
    problems = Problems(source, mapping)
    base = (Path(base_dir) if base_dir is not None else Path.cwd()).resolve()
    try:
        spec = ScenarioSpec.model_validate(mapping)
    except ValidationError as exc:
        validation_problems(exc, problems)
        # Check what is left too, so that one pass reports every problem it can.
        pruned = _pruned(mapping, exc)
        if pruned is not None:
            rest: ScenarioSpec | None = None
            with contextlib.suppress(ValidationError):
                rest = ScenarioSpec.model_validate(pruned[0])
            if rest is not None:
                problems.index_map = pruned[1]
                with contextlib.suppress(ScenarioFileError):
                    build_scenario(rest, problems, base)
        problems.raise_if_any()
        raise  # pragma: no cover - a ValidationError always has errors
    return build_scenario(spec, problems, base)
