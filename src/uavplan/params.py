"""Declared configuration fields, below every layer: :func:`option` gives a config
dataclass's field its one-line documentation and its valid values (range, choices), which the
configs check when built (:func:`bad_value`) and ``uavplan planners NAME`` prints
(:func:`describe_options`). Planner options (``uavplan.planners.core.options``) and optimizer
hyperparameters (``uavplan.optimizers.base.OptimizerConfig``) both use it."""

from __future__ import annotations

import dataclasses
import math
import typing
from collections.abc import Callable, Mapping, Sequence
from dataclasses import field, fields
from typing import Any

import numpy as np


def option(
    default: Any = dataclasses.MISSING,
    doc: str = "",
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    choices: Sequence[Any] | None = None,
    default_factory: Callable[[], Any] | None = None,
) -> Any:
    """A config field with its documentation and valid values.

    Args:
        default: the default (the paper's, cited in ``doc``); or ``default_factory``.
        doc: one line for ``describe_options`` and ``uavplan planners NAME``.
        low: the least value of a number (inclusive unless ``low_open``).
        high: the largest value of a number (inclusive unless ``high_open``).
        low_open: whether ``low`` itself is refused.
        high_open: whether ``high`` itself is refused.
        choices: the allowed values.
        default_factory: makes the default (a mutable one).
    """
    meta = {"doc": doc, "low": low, "high": high, "low_open": low_open, "high_open": high_open,
            "choices": tuple(choices) if choices is not None else None}  # fmt: skip
    if default_factory is not None:
        return field(default_factory=default_factory, metadata=meta)
    return field(default=default, metadata=meta)


_HINTS: dict[type, dict[str, Any]] = {}


def type_hints(cls: type) -> dict[str, Any]:
    """A config class's field types (each base's annotations in its own module's names)."""
    if cls not in _HINTS:
        _HINTS[cls] = typing.get_type_hints(cls)
    return _HINTS[cls]


def _kinds(hint: Any) -> tuple[set[type], bool]:
    """The plain types a hint admits and whether it admits None."""
    args = typing.get_args(hint) if typing.get_origin(hint) in (typing.Union, type(int | None)) \
        else (hint,)  # fmt: skip
    out: set[type] = set()
    none_ok = False
    for a in args:
        if a is type(None):
            none_ok = True
            continue
        origin = typing.get_origin(a) or a
        if origin in (dict, Mapping) or (isinstance(origin, type) and issubclass(origin, Mapping)):
            out.add(dict)
        elif isinstance(origin, type):
            out.add(origin)
    return out, none_ok


def _is_kind(value: Any, kinds: set[type]) -> bool:
    if not kinds or object in kinds:
        return True
    if isinstance(value, bool | np.bool_):
        return bool in kinds
    if isinstance(value, int | np.integer):
        return bool(kinds & {int, float})
    if isinstance(value, float | np.floating):
        return float in kinds
    if isinstance(value, Mapping):
        return dict in kinds
    return any(isinstance(value, k) for k in kinds)


def bad_value(value: Any, hint: Any, meta: Mapping[str, Any]) -> str | None:
    """Why ``value`` is not valid for a field of type ``hint`` declared with ``meta``, or None."""
    kinds, none_ok = _kinds(hint)
    if value is None:
        return None if none_ok else "must be given (not None)"
    if not _is_kind(value, kinds):
        return f"must be {_kind_words(kinds)}, got {value!r}"
    if isinstance(value, float | np.floating) and not math.isfinite(value):
        return f"must be a finite number, got {value!r}"
    choices = meta.get("choices")
    if choices is not None and value not in choices:
        return f"must be one of {list(choices)}, got {value!r}"
    low, high = meta.get("low"), meta.get("high")
    if isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool):
        if low is not None and (value < low or (meta.get("low_open") and value == low)):
            return f"must be {'>' if meta.get('low_open') else '>='} {low:g}, got {value!r}"
        if high is not None and (value > high or (meta.get("high_open") and value == high)):
            return f"must be {'<' if meta.get('high_open') else '<='} {high:g}, got {value!r}"
    return None


def _kind_words(kinds: set[type]) -> str:
    names = {int: "an integer", float: "a number", bool: "true or false", str: "a string",
             dict: "a mapping"}  # fmt: skip
    return " or ".join(sorted(names.get(k, k.__name__) for k in kinds))


def float_kinds(hint: Any) -> bool:
    """Whether a field of type ``hint`` takes floats (an int given for it becomes a float)."""
    return float in _kinds(hint)[0]


def check_fields(config: Any) -> tuple[str, str] | None:
    """The first field of a config dataclass instance whose value its declaration refuses, as
    ``(name, why)``, or None; ints given for float fields become floats (frozen or not)."""
    hints = type_hints(type(config))
    for f in fields(config):
        v = getattr(config, f.name)
        why = bad_value(v, hints.get(f.name, Any), f.metadata)
        if why is not None:
            return f.name, why
        if float_kinds(hints.get(f.name, Any)) and isinstance(v, int) and not isinstance(v, bool):
            object.__setattr__(config, f.name, float(v))
    return None


def describe_options(config_cls: type) -> list[dict[str, Any]]:
    """Every option of a config class: name, default, doc, range or choices."""
    out = []
    for f in fields(config_cls):
        default = f.default if f.default is not dataclasses.MISSING else (
            f.default_factory() if f.default_factory is not dataclasses.MISSING else None
        )  # fmt: skip
        m = f.metadata
        rng = ""
        if m.get("choices") is not None:
            rng = " | ".join(str(c) for c in m["choices"])
        elif m.get("low") is not None or m.get("high") is not None:
            rng = "x"
            if m.get("low") is not None:
                rng = f"{m['low']:g} {'<' if m.get('low_open') else '<='} {rng}"
            if m.get("high") is not None:
                rng = f"{rng} {'<' if m.get('high_open') else '<='} {m['high']:g}"
        out.append({"name": f.name, "default": default, "doc": m.get("doc", ""), "range": rng})
    return out
