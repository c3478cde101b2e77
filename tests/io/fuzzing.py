"""The input fuzzer shared by ``tests/io/test_fuzz_inputs.py`` (hypothesis, a few hundred cases
in CI) and ``benchmarks/fuzz_inputs.py`` (10,000 cases in worker processes).

A case is a set of files a user could hand uavplan (a scenario file mutated from a built-in one
or from a scene using every field, a plan.json mutated from a real one, a DEM or SRTM tile with
odd contents, or a path that is a directory, a link, a device, a FIFO or missing) and the
commands a user would run on them (``scenario check``, ``plan`` with a tiny budget, ``verify``,
``export``), driven in-process through the real CLI. Every choice comes from a :class:`Draw`:
:class:`RngDraw` (a seeded ``numpy.random.Generator``: the benchmark, where ``(seed, index)``
reproduces a case) or :class:`HypothesisDraw` (hypothesis's ``data.draw``: the tests, which
shrink a failure to a small case).

The oracle (:func:`judge`): every command ends with exit code 2 and a message on stderr naming
the file (or the option) without a traceback, or with exit code 0/1 having written files whose
every number is finite (no ``NaN``/``Infinity``, no ``null`` where a coordinate or a time
belongs) and, for a plan that says feasible, which the independent verifier accepts. Anything
else is a failure of one of the classes in :data:`FAILURES`.
"""

from __future__ import annotations

import copy
import io
import json
import math
import os
import re
import signal
import struct
import traceback
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

#: Outcome classes: the two good ones, then the failures.
CLEAN_ERROR = "clean error (exit 2)"
VALID = "valid (exit 0/1, files checked)"
UNCAUGHT = "uncaught error"
HANG = "hang"
NON_FINITE = "non-finite output"
DISAGREE = "verifier disagreement"
BAD_MESSAGE = "unclear error message"
CRASH = "worker crashed (memory or signal)"
OUTCOMES = (CLEAN_ERROR, VALID, UNCAUGHT, HANG, NON_FINITE, DISAGREE, BAD_MESSAGE, CRASH)
FAILURES = OUTCOMES[2:]

#: Built-in scenarios the scenario mutations start from (small and fast to check).
BASE_SCENARIOS = ("simple2d", "spso", "jacksboro", "hrmaga-popup", "rscdwoa-static")
#: Cheap planners for ``plan`` with a tiny budget (a fleet is planned by the fleet planners or
#: in the prioritized frame).
PLANNERS = ("spso", "pso", "rrt-star", "apf", "ppswarm", "hr-maga", "ga")
#: Keys whose lists hold coordinates or times in a plan file: never null, always finite.
_COORD_KEYS = {"waypoints", "times", "points", "start", "goal"}

_WEIRD_NUMBERS: tuple[Any, ...] = (
    0,
    -0.0,
    1,
    -1,
    0.5,
    2,
    1e-300,
    5e-324,
    -5e-324,
    1e-9,
    1e6,
    9.99e6,
    1e7,
    1.0000001e7,
    2e7,
    1e15,
    1e300,
    1e308,
    -1e308,
    1.7976931348623157e308,
    -1.7976931348623157e308,
    float("nan"),
    float("inf"),
    float("-inf"),
    2**31,
    2**53 + 1,
    2**63,
    2**64,
    -(2**63),
    10**400,
)
_WEIRD_STRINGS: tuple[str, ...] = (
    "",
    "x",
    "nan",
    "inf",
    "1e3",
    "spso",
    "ppswarm",
    "length2d",
    "hrmaga",
    "length",
    "ground",
    "absolute",
    "wgs84",
    "../../../../etc/passwd",
    "/etc/passwd",
    "/dev/zero",
    "/dev/null",
    "~/nothing.tif",
    "dem.tif",
    "dem.npy",
    "dem",
    "\u00e9\u00e8\u4e2d\u6587",
    "a" * 5000,
    "!!python/object/apply:os.system",
    "N36W085.hgt",
)


# ---------------------------------------------------------------------------------- choices
class Draw:
    """Where a case's choices come from."""

    def integer(self, lo: int, hi: int) -> int:  # inclusive
        raise NotImplementedError

    def real(self) -> float:  # in [0, 1)
        raise NotImplementedError

    def blob(self, n: int) -> bytes:
        raise NotImplementedError

    def choice(self, seq: Sequence[Any]) -> Any:
        return seq[self.integer(0, len(seq) - 1)]

    def chance(self, p: float) -> bool:
        return self.real() < p


class RngDraw(Draw):
    """Choices from a seeded ``numpy.random.Generator``."""

    def __init__(self, seed: int | Sequence[int]) -> None:
        self.rng = np.random.default_rng(seed)

    def integer(self, lo: int, hi: int) -> int:
        return int(self.rng.integers(lo, hi, endpoint=True))

    def real(self) -> float:
        return float(self.rng.random())

    def blob(self, n: int) -> bytes:
        return bytes(self.rng.integers(0, 256, n, dtype=np.uint8))


class HypothesisDraw(Draw):
    """Choices from hypothesis (``st.data()``), so that failures shrink."""

    def __init__(self, data: Any) -> None:
        from hypothesis import strategies as st

        self.data = data
        self.st = st

    def integer(self, lo: int, hi: int) -> int:
        return int(self.data.draw(self.st.integers(lo, hi)))

    def real(self) -> float:
        return float(self.data.draw(self.st.floats(0, 1, exclude_max=True)))

    def blob(self, n: int) -> bytes:
        return bytes(self.data.draw(self.st.binary(min_size=n, max_size=n)))


# ---------------------------------------------------------------------------------- values
def weird_value(draw: Draw, depth: int = 0) -> Any:
    """A value of any type a YAML or JSON file can hold, biased to edges."""
    kind = draw.integer(0, 9)
    if kind <= 3:
        return draw.choice(_WEIRD_NUMBERS)
    if kind == 4:
        return (draw.real() - 0.5) * 10.0 ** draw.integer(-12, 12)
    if kind == 5:
        return draw.choice(_WEIRD_STRINGS)
    if kind == 6:
        return draw.choice((None, True, False, [], {}))
    if kind == 7 and depth < 3:
        return [weird_value(draw, depth + 1) for _ in range(draw.integer(0, 4))]
    if kind == 8 and depth < 3:
        return {
            draw.choice(("x", "lower", "radius", "min", "file", "1")): weird_value(draw, depth + 1)
        }
    return draw.integer(-(10**6), 10**6)


def _paths(node: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out = [prefix]
    if isinstance(node, dict):
        for k, v in node.items():
            out += _paths(v, (*prefix, k))
    elif isinstance(node, list):
        for i, v in enumerate(node[:50]):
            out += _paths(v, (*prefix, i))
    return out


def _get(node: Any, path: tuple[Any, ...]) -> Any:
    for p in path:
        node = node[p]
    return node


def _set(root: Any, path: tuple[Any, ...], value: Any) -> Any:
    if not path:
        return value
    _get(root, path[:-1])[path[-1]] = value
    return root


def mutate_tree(draw: Draw, root: Any, n: int | None = None) -> Any:
    """``root`` (a copy) after ``n`` (1-3) structural mutations at random places."""
    root = copy.deepcopy(root)
    for _ in range(n if n is not None else draw.integer(1, 3)):
        paths = _paths(root)
        path = draw.choice(paths)
        node = _get(root, path)
        op = draw.integer(0, 11)
        if op <= 3:  # a weird value in place
            root = _set(root, path, weird_value(draw))
        elif op == 4 and path:  # delete
            del _get(root, path[:-1])[path[-1]]
        elif op == 5 and isinstance(node, dict):  # an unknown key, or a known key elsewhere
            key = draw.choice(("extra", "radius", "tasks", "bounds", "planning", "cost", "file"))
            node[key] = weird_value(draw)
        elif op == 6 and isinstance(node, list) and node:  # duplicate items
            node.extend([copy.deepcopy(node[-1])] * draw.choice((1, 5, 200)))
        elif op == 7 and isinstance(node, (int, float)) and not isinstance(node, bool):
            scale = draw.choice((-1, 0, 1e-300, 1e3, 1e6, 1e9, 1e300, 1e308, float("inf")))
            try:
                scaled = node * scale if node else scale
            except OverflowError:  # an int beyond any float (10**400) times a float
                scaled = scale
            root = _set(root, path, scaled)
        elif op == 8:  # deep nesting
            deep: Any = node
            for _ in range(draw.choice((2, 30, 120))):
                deep = [deep]
            root = _set(root, path, deep)
        elif op == 9 and len(path) >= 1:  # swap with another subtree
            other = draw.choice(paths)
            if other and other[: len(path)] != path and path[: len(other)] != other:
                a, b = copy.deepcopy(_get(root, path)), copy.deepcopy(_get(root, other))
                root = _set(root, path, b)
                root = _set(root, other, a)
        elif op == 10 and isinstance(node, (int, float)) and not isinstance(node, bool):
            root = _set(root, path, str(node))  # a number as a string
        else:  # a planning value
            planning = root.setdefault("planning", {}) if isinstance(root, dict) else None
            if isinstance(planning, dict):
                key = draw.choice(("cost", "n_waypoints", "cost", "n_waypoints"))
                planning[key] = draw.choice(
                    (
                        "spso",
                        "ppswarm",
                        "hrmaga",
                        "length2d",
                        "length",
                        "nope",
                        0,
                        1,
                        2,
                        999,
                        1000,
                        1001,
                        10**9,
                        2.5,
                        None,
                    )
                )
    return root


def mutate_bytes(draw: Draw, data: bytes) -> bytes:
    """``data`` after one or two byte-level mutations."""
    for _ in range(draw.integer(1, 2)):
        n = len(data)
        op = draw.integer(0, 8)
        at = draw.integer(0, n) if n else 0
        if op == 0 and n:  # flip a few bytes
            b = bytearray(data)
            for _ in range(draw.integer(1, 8)):
                b[draw.integer(0, n - 1)] = draw.integer(0, 255)
            data = bytes(b)
        elif op == 1:  # insert random bytes
            data = data[:at] + draw.blob(draw.integer(1, 16)) + data[at:]
        elif op == 2:  # truncate
            data = data[:at]
        elif op == 3 and n:  # delete a range
            data = data[:at] + data[at + draw.integer(1, 64) :]
        elif op == 4:  # duplicate a range
            data = data[:at] + data[max(0, at - 200) : at] + data[at:]
        elif op == 5:  # not UTF-8
            data = (
                data[:at]
                + draw.choice((b"\xff\xfe", b"\xc3\x28", b"\x80", b"\xed\xa0\x80"))
                + data[at:]
            )
        elif op == 6:  # a NUL, a BOM, a tab
            data = data[:at] + draw.choice((b"\x00", b"\xef\xbb\xbf", b"\t", b"\r")) + data[at:]
        elif op == 7:  # YAML oddities
            data = (
                data[:at]
                + draw.choice(
                    (
                        b" !!python/object/apply:os.system ['echo pwned'] ",
                        b" &a ",
                        b" *a ",
                        b" !!binary AAAA ",
                        b"<<: *nothing\n",
                        b"{",
                        b"[",
                        b"'",
                        b'"',
                        b"\n---\n",
                        b" !!float 'nan' ",
                        b" !!set {a, b} ",
                        b" !!timestamp 2001-12-14 ",
                    )
                )
                + data[at:]
            )
        else:  # a whole line repeated
            lines = data.split(b"\n")
            if lines:
                k = draw.integer(0, len(lines) - 1)
                lines[k:k] = [lines[k]] * draw.choice((2, 10))
                data = b"\n".join(lines)
    return data


def dump(draw: Draw, data: Any, fmt: str) -> bytes:
    """``data`` as YAML or JSON text (non-finite numbers as YAML's .nan/.inf or JSON's NaN)."""
    if fmt == "json":
        return json.dumps(data, allow_nan=True, default=str).encode()
    try:
        return yaml.safe_dump(
            data, default_flow_style=draw.chance(0.3), allow_unicode=True
        ).encode()
    except (yaml.YAMLError, RecursionError):
        return json.dumps(data, allow_nan=True, default=str).encode()


def bomb_yaml(levels: int = 9) -> bytes:
    """A 'billion laughs' YAML: few bytes, ``9**levels`` items when expanded."""
    lines = ["name: bomb", "a0: &a0 [1, 2, 3]"]
    for k in range(1, levels):
        lines.append(f"a{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * 9) + "]")
    lines.append(f"tasks: *a{levels - 1}")
    return ("\n".join(lines) + "\n").encode()


# ---------------------------------------------------------------------------------- DEMs
def _tiff(draw: Draw, path: Path) -> None:
    """A GeoTIFF with odd tags, dtypes or shapes (tifffile)."""
    import tifffile

    shape = draw.choice(((2, 2), (1, 5), (30, 40), (64, 64), (3, 20, 20), (20, 20, 3), (2,)))
    dtype = draw.choice(
        (
            np.float32,
            np.float64,
            np.int16,
            np.uint8,
            np.uint16,
            np.int32,
            np.complex64,
            np.bool_,
            np.uint64,
        )
    )
    arr = (np.linspace(-100, 3000, int(np.prod(shape))).reshape(shape)).astype(dtype)
    if draw.chance(0.2) and np.issubdtype(dtype, np.floating):
        arr.flat[draw.integer(0, arr.size - 1)] = draw.choice((np.nan, np.inf, -np.inf))
    extra = []
    if draw.chance(0.8):
        scale = draw.choice(
            (
                (30.0, 30.0, 0.0),
                (0.0, 0.0, 0.0),
                (-1.0, 1.0, 0.0),
                (float("nan"), 1.0, 0.0),
                (1e300, 1e300, 0.0),
                (1e-300, 1e-300, 0.0),
                (0.000833333, 0.000833333, 0.0),
                (1.0,),
            )
        )
        extra.append((33550, "d", len(scale), scale, True))
    if draw.chance(0.7):
        tie = draw.choice(
            (
                (0, 0, 0, 500000.0, 4000000.0, 0),
                (0, 0, 0, -85.0, 36.5, 0),
                (0, 0, 0, 1e308, -1e308, 0),
                (0, 0, 0, float("nan"), 0, 0),
                (0, 0, 0, 200.0, 95.0, 0),
                (0.0,),
            )
        )
        extra.append((33922, "d", len(tie), tie, True))
    if draw.chance(0.6):
        epsg = draw.choice((4326, 32633, 3857, 999999, 32767, 0, 65535))
        key = 3072 if draw.chance(0.5) else 2048
        keys = draw.choice(
            (
                (1, 1, 0, 1, key, 0, 1, epsg),
                (1, 1, 0, 200, key, 0, 1, epsg),
                (1, 1, 0),
                (1, 1, 0, 1, key, 34736, 1, 0),
            )
        )
        extra.append((34735, "H", len(keys), keys, True))
    if draw.chance(0.2):
        extra.append((42113, "s", 0, draw.choice(("-32768", "abc", "nan", "")), True))
    buf = io.BytesIO()
    try:
        tifffile.imwrite(buf, arr, extratags=extra)
    except Exception:  # tifffile refuses the combination: write a plain one
        buf = io.BytesIO()
        tifffile.imwrite(buf, np.zeros((4, 4), np.float32))
    data = buf.getvalue()
    if draw.chance(0.3):
        data = mutate_bytes(draw, data)
    if draw.chance(0.05):  # the first IFD declares an enormous image
        data = _huge_tiff()
    path.write_bytes(data)


def _huge_tiff() -> bytes:
    """A tiny TIFF whose one strip declares 200,000 x 200,000 float64 samples."""
    entries = [
        (256, 4, 1, 200_000),
        (257, 4, 1, 200_000),
        (258, 3, 1, 64),
        (259, 3, 1, 1),
        (262, 3, 1, 1),
        (273, 4, 1, 8),
        (277, 3, 1, 1),
        (278, 4, 1, 200_000),
        (279, 4, 1, 8),
        (339, 3, 1, 3),
    ]
    ifd_at = 16
    out = b"II*\x00" + struct.pack("<I", ifd_at) + b"\x00" * 8
    out += struct.pack("<H", len(entries))
    for tag, typ, count, value in entries:
        out += struct.pack("<HHI", tag, typ, count) + struct.pack("<I", value)
    return out + struct.pack("<I", 0)


def _npy(draw: Draw, path: Path) -> None:
    kind = draw.integer(0, 6)
    if kind == 0:
        arr: Any = np.zeros((draw.integer(0, 3), draw.integer(0, 3)))
    elif kind == 1:
        arr = np.full((10, 10), draw.choice((np.nan, np.inf, 1e308, -1e308, 0.0)))
    elif kind == 2:
        arr = np.arange(24.0).reshape(2, 3, 4)
    elif kind == 3:
        arr = np.array([{"a": 1}, None], dtype=object)  # a pickle inside
    elif kind == 4:
        arr = np.array(["a", "b", "c", "d"]).reshape(2, 2)
    elif kind == 5:  # the header declares an enormous array, the data is not there
        header = "{'descr': '<f8', 'fortran_order': False, 'shape': (100000, 100000), }"
        header += " " * (63 - len(header) % 64) + "\n"
        path.write_bytes(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode())
        return
    else:
        arr = np.linspace(0, 100, 400).reshape(20, 20)
    if draw.chance(0.5) and arr.dtype == np.float64:
        buf = io.BytesIO()
        np.save(buf, arr)
        path.write_bytes(mutate_bytes(draw, buf.getvalue()))
    else:
        np.save(path, arr, allow_pickle=True)


def _npz(draw: Draw, path: Path) -> None:
    arrays: dict[str, Any] = {
        draw.choice(("heights", "elevation", "topo", "other")): np.linspace(0, 50, 100).reshape(
            10, 10
        )
    }
    for k in ("dx", "dy", "x0", "y0"):
        if draw.chance(0.3):
            arrays[k] = np.array(draw.choice((0.0, -1.0, np.nan, np.inf, 1e308, 1e-300, 30.0)))
    with path.open("wb") as f:
        np.savez(f, **arrays)
    if draw.chance(0.3):
        path.write_bytes(mutate_bytes(draw, path.read_bytes()))


def _hgt(draw: Draw, path: Path) -> None:
    n = draw.choice((1201, 3601, 1200, 10, 0))
    if n == 1201 and draw.chance(0.5):
        data = np.full((n, n), draw.choice((-32768, 0, 32767, 500)), dtype=">i2").tobytes()
    elif n >= 1200:
        data = (np.arange(n * n, dtype=np.int64) % 900).astype(">i2").tobytes()
    else:
        data = b"\x00" * (2 * n * n + draw.integer(0, 3))
    path.write_bytes(data)


def make_dem(draw: Draw, folder: Path) -> tuple[dict[str, Any], str]:
    """A terrain block naming an odd DEM made in ``folder``, and what it is."""
    kind = draw.choice(
        (
            "tif",
            "tif",
            "tif",
            "npy",
            "npz",
            "hgt",
            "dir",
            "link-dev",
            "link-dir",
            "dangling",
            "missing",
            "dev",
            "fifo",
            "link-loop",
            "empty",
            "text",
        )
    )
    name = {"npy": "dem.npy", "npz": "dem.npz", "hgt": "N36W085.hgt"}.get(kind, "dem.tif")
    p = folder / name
    if kind == "tif":
        _tiff(draw, p)
    elif kind == "npy":
        _npy(draw, p)
    elif kind == "npz":
        _npz(draw, p)
    elif kind == "hgt":
        _hgt(draw, p)
    elif kind == "dir":
        p.mkdir()
    elif kind == "link-dev":
        p.symlink_to(draw.choice(("/dev/zero", "/dev/null", "/dev/urandom")))
    elif kind == "link-dir":
        p.symlink_to(folder)
    elif kind == "dangling":
        p.symlink_to(folder / "nowhere.tif")
    elif kind == "dev":
        name = draw.choice(("/dev/zero", "/dev/null", "/dev/urandom"))
    elif kind == "fifo":
        os.mkfifo(p)
    elif kind == "link-loop":
        p.symlink_to(p)
    elif kind == "empty":
        p.write_bytes(b"")
    elif kind == "text":
        p.write_text("not a tiff\n" * 10)
    if kind == "hgt" or (kind in ("link-dev", "dev", "empty") and draw.chance(0.3)):
        block: dict[str, Any] = {"srtm": [name]}
    else:
        block = {"file": name}
        if draw.chance(0.4):
            block["cell_size"] = draw.choice((1.0, 30.0, 1e-300, 1e-3, 1e6, 1e7, 90.0))
    return block, kind


# ---------------------------------------------------------------------------------- scenes
def kitchen_sink() -> dict[str, Any]:
    """A small 3-D scene using every field of the format (no terrain file)."""
    return {
        "name": "sink",
        "description": "every field",
        "bounds": {"lower": [0, 0, 0], "upper": [400, 400, 200]},
        "cylinders": [{"center": [200, 200], "radius": 30, "z_min": 0, "z_max": 150, "margin": 1}],
        "circles": [{"center": [100, 300], "radius": 20, "margin": 0.5}],
        "polygons": [{"vertices": [[300, 50], [350, 50], [350, 100], [300, 100]], "margin": 1}],
        "danger_areas": [{"center": [120, 120], "radius": 25}],
        "uncertain_areas": [{"x": 250, "y": 250, "width": 30, "height": 30, "revealed": True}],
        "moving_obstacles": [
            {
                "radius": 5,
                "times": [0, 10, 20],
                "positions": [[50, 350, 50], [150, 350, 50], [250, 350, 50]],
            }
        ],
        "altitude": {"min": 20, "max": 180, "reference": "absolute"},
        "uav": {
            "speed": 15,
            "turn_radius": 10,
            "s1": 5,
            "s2": 8,
            "size": 1,
            "min_speed": 0,
            "max_speed": 20,
            "max_climb_angle": 30,
            "max_descent_angle": 30,
        },
        "tasks": [
            {"id": "a", "start": [20, 20, 50], "goal": [380, 380, 60], "start_time": 0},
            {"id": "b", "start": [20, 380, 70], "goal": [380, 20, 70]},
        ],
        "planning": {"cost": "ppswarm", "n_waypoints": 5},
        "origin": {"lat": 47.0, "lon": 8.0, "alt": 400},
    }


def dem_scene(block: dict[str, Any]) -> dict[str, Any]:
    scene: dict[str, Any] = {
        "name": "dem",
        "terrain": block,
        "altitude": {"min": 10, "max": 300, "reference": "ground"},
        "task_z": "ground",
        "tasks": [{"start": [5, 5, 50], "goal": [25, 25, 50]}],
        "planning": {"n_waypoints": 3},
    }
    if "srtm" in block:
        scene["origin"] = {"lat": 36.5, "lon": -84.5}
        scene["bounds"] = {"lower": [-2000, -2000], "upper": [2000, 2000]}
        scene["tasks"] = [{"start": [-1000, -1000, 50], "goal": [1000, 1000, 50]}]
    return scene


_BASE_CACHE: dict[str, Any] = {}


def base_scenario(name: str) -> Any:
    if name not in _BASE_CACHE:
        if name == "sink":
            _BASE_CACHE[name] = kitchen_sink()
        else:
            from uavplan.scenarios import builtin_path

            _BASE_CACHE[name] = yaml.safe_load(builtin_path(name).read_text(encoding="utf-8"))
    return copy.deepcopy(_BASE_CACHE[name])


# ---------------------------------------------------------------------------------- cases
@dataclass
class Case:
    """What a case runs: CLI argument lists, in order, in ``folder``."""

    kind: str
    folder: Path
    commands: list[list[str]] = field(default_factory=list)
    #: run the next commands only if this one exits 0 (e.g. plan only a valid scenario)
    gate: set[int] = field(default_factory=set)
    note: str = ""


def _plan_args(draw: Draw, scenario: str, out: Path) -> list[str]:
    args = [
        "plan",
        scenario,
        "-o",
        str(out),
        "--iterations",
        str(draw.choice((1, 2, 3))),
        "--pop-size",
        str(draw.choice((4, 8))),
    ]
    if draw.chance(0.85):
        args += ["-a", draw.choice(PLANNERS)]
    if draw.chance(0.2):
        args += ["--waypoints", str(draw.choice((1, 3, 0, -1, 1000, 1001, 10**12)))]
    if draw.chance(0.1):
        args += ["--cost", draw.choice(("spso", "ppswarm", "length2d", "length", "hrmaga", "x"))]
    if draw.chance(0.15):
        name = draw.choice(
            (
                "w",
                "c1",
                "n_restart",
                "max_init_attempts",
                "step_size",
                "goal_bias",
                "flight",
                "encoding",
                "constraints",
                "nope",
                "pop_size",
                "cost",
            )
        )
        value = draw.choice(
            (
                "0",
                "-1",
                "1e308",
                "nan",
                "inf",
                "true",
                "abc",
                "0.5",
                "10**9",
                "1000000000",
                "",
                "in-loop",
            )
        )
        args += ["--param", f"{name}={value}"]
    if draw.chance(0.1):
        args += ["--time", str(draw.choice((0.5, 0, -1, float("nan"), 1e308)))]
    return args


def _tiny_fleet(data: Any) -> Any:
    """A built-in fleet cut to two UAVs, so that planning it stays tiny."""
    if isinstance(data, dict) and isinstance(data.get("tasks"), list):
        data["tasks"] = data["tasks"][:2]
    if isinstance(data, dict) and isinstance(data.get("fleet"), dict):
        data["fleet"]["count"] = 2
    return data


def scenario_case(draw: Draw, folder: Path, plan_scale: float = 1.0) -> Case:
    """A mutated scenario file: check it; plan it if it is valid (sometimes)."""
    base = draw.choice((*BASE_SCENARIOS, "sink", "sink", "ppswarm1"))
    data = _tiny_fleet(base_scenario(base))
    fmt = draw.choice(("yaml", "yaml", "json"))
    how = draw.integer(0, 9)
    if how <= 5:
        text = dump(draw, mutate_tree(draw, data), fmt)
    elif how <= 8:
        text = mutate_bytes(draw, dump(draw, data, fmt))
    else:
        text = dump(draw, mutate_tree(draw, data), fmt)
        text = mutate_bytes(draw, text)
    path = folder / f"scene.{fmt}"
    path.write_bytes(text)
    case = Case("scenario", folder, note=f"{base} as {fmt}")
    case.commands.append(["scenario", "check", str(path)])
    if draw.chance(0.12 * plan_scale):
        case.gate.add(0)
        case.commands.append(_plan_args(draw, str(path), folder / "out"))
    elif draw.chance(0.2):
        case.gate.add(0)
        case.commands.append(["scenario", "export", str(path), str(folder / "again.yaml")])
        case.commands.append(["scenario", "check", str(folder / "again.yaml")])
    return case


def special_scenario_case(
    draw: Draw, folder: Path, plan_scale: float = 1.0, heavy: bool = True
) -> Case:
    """Files no mutation of a valid one reaches: bombs, deep nesting, huge or odd files
    (``heavy``: also 20,000 circles in YAML, which takes seconds to read)."""
    kind = draw.choice(
        (
            "bomb",
            "deep-yaml",
            "deep-json",
            "huge",
            "big-list",
            "python-tag",
            "fifo",
            "dir",
            "dev",
            "empty",
            "top-list",
            "many-waypoints",
            "many-uavs",
            "wide-dem",
        )
    )
    path = folder / "scene.yaml"
    if kind == "bomb":
        path.write_bytes(bomb_yaml(draw.choice((5, 9, 12))))
    elif kind == "deep-yaml":
        path.write_bytes(b"name: deep\ntasks: " + b"[" * 100_000 + b"]" * 100_000 + b"\n")
    elif kind == "deep-json":
        path = folder / "scene.json"
        path.write_bytes(b'{"name": "deep", "tasks": ' + b"[" * 100_000 + b"]" * 100_000 + b"}")
    elif kind == "huge":  # sparse: beyond the size limit without using the disk
        with path.open("wb") as f:
            f.truncate(65 * 2**20)
    elif kind == "big-list":  # below the size limit, many entries
        n = draw.choice((100_001, 20_000) if heavy else (100_001,))
        circles = "".join(f"- {{center: [{i % 97}, {i % 89}], radius: 1}}\n" for i in range(n))
        path.write_text(
            "name: big\nbounds: {lower: [0, 0], upper: [100, 100]}\ncircles:\n"
            + circles
            + "tasks: [{start: [0, 0], goal: [1, 1]}]\n"
        )
    elif kind == "python-tag":
        marker = folder / "pwned"
        path.write_text(
            f"name: !!python/object/apply:os.system ['touch {marker}']\n"
            "bounds: {lower: [0, 0], upper: [10, 10]}\n"
            "tasks: [{start: [1, 1], goal: [9, 9]}]\n"
        )
    elif kind == "fifo":
        os.mkfifo(path)
    elif kind == "dir":
        path.mkdir()
    elif kind == "dev":
        path = Path(draw.choice(("/dev/zero", "/dev/null", "/dev/urandom")))
    elif kind == "empty":
        path.write_bytes(b"" if draw.chance(0.5) else b"---\n")
    elif kind == "top-list":
        path.write_text("- 1\n- 2\n")
    elif kind == "many-waypoints":
        d = base_scenario("simple2d")
        d["planning"] = {"n_waypoints": draw.choice((1000, 1001, 10**6))}
        path.write_text(yaml.safe_dump(d))
    elif kind == "many-uavs":
        d = base_scenario("open")
        d.pop("tasks", None)
        d["fleet"] = {"count": draw.choice((10_000, 10_001, 10**9))}
        path.write_text(yaml.safe_dump(d))
    else:  # a flat DEM over a huge grid, given by its cell size
        d = dem_scene({"file": "dem.npy", "cell_size": draw.choice((1e-3, 1e5, 1e6))})
        np.save(folder / "dem.npy", np.zeros((draw.choice((2, 3000)), 3000), np.float32))
        path.write_text(yaml.safe_dump(d))
    case = Case("special", folder, note=kind)
    case.commands.append(["scenario", "check", str(path)])
    if kind in ("many-waypoints", "wide-dem") and draw.chance(0.5 * plan_scale):
        case.gate.add(0)
        case.commands.append(_plan_args(draw, str(path), folder / "out"))
    return case


def dem_case(draw: Draw, folder: Path, plan_scale: float = 1.0) -> Case:
    block, kind = make_dem(draw, folder)
    scene = dem_scene(block)
    if draw.chance(0.3):
        scene = mutate_tree(draw, scene, 1)
    path = folder / "scene.yaml"
    path.write_text(yaml.safe_dump(scene))
    case = Case("dem", folder, note=kind)
    case.commands.append(["scenario", "check", str(path)])
    if draw.chance(0.15 * plan_scale):
        case.gate.add(0)
        case.commands.append(_plan_args(draw, str(path), folder / "out"))
    return case


#: Real plan files made once per process: (plan.json text, scenario name).
_PLANS: dict[str, tuple[bytes, str]] = {}


def real_plan(name: str, folder: Path) -> tuple[bytes, str]:
    """A plan.json written by ``uavplan plan`` with a tiny budget (made once per process)."""
    if name not in _PLANS:
        from typer.testing import CliRunner

        from uavplan.cli import app

        scene, algo = {
            "2d": ("simple2d", "spso"),
            "3d": ("spso", "spso"),
            "fleet": (str(folder / "sink.yaml"), "ppswarm"),
        }[name]
        if name == "fleet":  # two UAVs in a small 3-D world
            (folder / "sink.yaml").write_text(yaml.safe_dump(kitchen_sink()))
        out = folder / f"real-{name}"
        CliRunner().invoke(
            app, ["plan", scene, "-a", algo, "--iterations", "2", "--pop-size", "8", "-o", str(out)]
        )
        _PLANS[name] = ((out / "plan.json").read_bytes(), scene)
    return _PLANS[name]


def plan_file_case(draw: Draw, folder: Path, cache: Path) -> Case:
    """A mutated plan.json: verify it, export it."""
    text, scene = real_plan(draw.choice(("2d", "3d", "fleet")), cache)
    how = draw.integer(0, 9)
    if how <= 6:
        doc = json.loads(text)
        text = json.dumps(mutate_tree(draw, doc), allow_nan=True, default=str).encode()
    else:
        text = mutate_bytes(draw, text)
    path = folder / "plan.json"
    path.write_bytes(text)
    case = Case("plan-file", folder, note=scene)
    args = ["verify", str(path), scene]
    if draw.chance(0.3):
        args.append(draw.choice(("--polylines", "--smoothed")))
    if draw.chance(0.2):
        args += ["--json", str(folder / "report.json")]
    case.commands.append(args)
    if draw.chance(0.5):
        fmt = draw.choice(("csv", "qgc", "wpl", "geojson", "kml"))
        exp = ["export", str(path), scene, "-f", fmt, "-o", str(folder / f"mission-{fmt}")]
        if draw.chance(0.2):
            exp += [
                "--origin",
                draw.choice(("47,8", "91,0", "nan,1", "1e308,1e308", "a,b", "0,0,1e308")),
            ]
        if draw.chance(0.1):
            exp.append(draw.choice(("--polylines", "--smoothed")))
        case.commands.append(exp)
    return case


#: The kinds of case and how often :func:`make_case` draws each (out of 20).
KINDS = {"scenario": 9, "special": 3, "dem": 4, "plan-file": 4}


def make_case(
    draw: Draw,
    folder: Path,
    cache: Path,
    kind: str | None = None,
    plan_scale: float = 1.0,
    heavy: bool = True,
) -> Case:
    """One case in ``folder`` (fresh and empty); ``cache`` keeps the real plans. ``kind``: one
    of :data:`KINDS` (default: drawn); ``plan_scale`` scales how often a case plans."""
    if kind is None:
        k = draw.integer(0, sum(KINDS.values()) - 1)
        for kind, n in KINDS.items():  # noqa: B007 - the kind whose share holds k
            if k < n:
                break
            k -= n
    if kind == "scenario":
        return scenario_case(draw, folder, plan_scale)
    if kind == "special":
        return special_scenario_case(draw, folder, plan_scale, heavy)
    if kind == "dem":
        return dem_case(draw, folder, plan_scale)
    return plan_file_case(draw, folder, cache)


# ---------------------------------------------------------------------------------- oracle
@dataclass
class Result:
    outcome: str
    detail: str = ""
    command: list[str] = field(default_factory=list)


_NONFINITE_TEXT = re.compile(r"(?<![A-Za-z_])(nan|-?inf(inity)?)(?![A-Za-z_])", re.IGNORECASE)


def _no_nan_constant(token: str) -> Any:
    raise ValueError(f"non-finite JSON constant {token}")


def _json_problems(path: Path) -> str | None:
    """Why a JSON output is not strict and finite where coordinates and times belong."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"), parse_constant=_no_nan_constant)
    except ValueError as exc:
        return f"{path.name}: {exc}"

    def walk(node: Any, key: str) -> str | None:
        if isinstance(node, dict):
            for k, v in node.items():
                why = walk(v, str(k))
                if why:
                    return why
        elif isinstance(node, list):
            for v in node:
                why = walk(v, key)
                if why:
                    return why
        elif key in _COORD_KEYS and (
            node is None or (isinstance(node, float) and not math.isfinite(node))
        ):
            return f"{path.name}: {key} holds {node!r}"
        return None

    return walk(doc, "")


def _output_problems(folder: Path, before: set[Path]) -> str | None:
    """Non-finite numbers in the files a command wrote (plan.json, reports, missions)."""
    for p in sorted(folder.rglob("*")):
        if p in before or not p.is_file() or p.is_symlink():
            continue
        if p.suffix in (".json", ".plan", ".geojson"):
            why = _json_problems(p)
            if why:
                return why
        elif p.suffix in (".csv", ".kml", ".waypoints", ".txt"):
            m = _NONFINITE_TEXT.search(p.read_text(encoding="utf-8", errors="replace"))
            if m:
                return f"{p.name}: {m.group(0)!r} in the text"
    return None


def _alarm(signum: int, frame: Any) -> None:
    raise CaseTimeout("the command ran past its time")


def _verifier_disagrees(plan_json: Path, scenario_arg: str) -> str | None:
    """A plan.json that says feasible, checked again with the independent verifier."""
    from uavplan.io.plan_file import read_plan_file
    from uavplan.scenarios import resolve
    from uavplan.verify import verify_trajectories

    doc = json.loads(plan_json.read_text(encoding="utf-8"))
    if doc.get("feasible") is not True:
        return None
    world = resolve(scenario_arg)
    pf = read_plan_file(plan_json, world.dim)
    report = verify_trajectories(pf.trajectories("flown"), world, pf.scenario)
    if report.ok:
        return None
    return f"plan says feasible, verifier: {[str(v.message) for v in report.violations[:2]]}"


def _names(args: list[str]) -> list[str]:
    """What an exit-2 message may name: the files and the options of the command."""
    out = [a for a in args if a.startswith("--") or a.startswith("-")]
    for a in args[1:]:
        p = Path(a)
        out += [p.name, p.stem] if len(a) > 2 else []
    return [n for n in out if n] + ["--"]


def judge(args: list[str], result: Any, folder: Path, before: set[Path]) -> Result:
    """The outcome of one CLI run (a click ``Result``)."""
    exc = result.exception
    code = result.exit_code
    if isinstance(exc, CaseTimeout):
        return Result(HANG, str(exc), args)
    stderr = result.stderr if result.stderr_bytes is not None else ""
    if exc is not None and not isinstance(exc, SystemExit):
        tb = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
        return Result(UNCAUGHT, f"{type(exc).__name__}: {exc}"[:300] + "\n" + tb[-1500:], args)
    if "Traceback (most recent call last)" in stderr + result.stdout:
        return Result(UNCAUGHT, "a traceback was printed: " + stderr[-800:], args)
    if code == 2:
        lines = [ln for ln in stderr.splitlines() if ln.strip()]
        if not lines:
            return Result(BAD_MESSAGE, "exit 2 with nothing on stderr", args)
        if not any(n in ln for ln in lines for n in _names(args)):
            return Result(BAD_MESSAGE, f"exit 2 naming no file or option: {lines[0][:200]}", args)
        return Result(CLEAN_ERROR, lines[0][:200], args)
    if code not in (0, 1):
        return Result(UNCAUGHT, f"exit code {code}: {stderr[-300:]}", args)
    why = _output_problems(folder, before)
    if why:
        return Result(NON_FINITE, why, args)
    if args[0] == "plan":
        out = Path(args[args.index("-o") + 1]) / "plan.json"
        if not out.is_file():
            return Result(UNCAUGHT, f"plan exited {code} without writing plan.json", args)
        why = _verifier_disagrees(out, args[1])
        if why:
            return Result(DISAGREE, why, args)
        if code == 0 and json.loads(out.read_text(encoding="utf-8")).get("feasible") is not True:
            return Result(DISAGREE, "plan exited 0 for a plan not feasible", args)
    return Result(VALID, f"exit {code}", args)


class CaseTimeout(Exception):
    """A command ran past its time (raised by the alarm of :func:`run_case`)."""


def run_case(
    case: Case, invoke: Callable[[list[str]], Any] | None = None, timeout: float | None = None
) -> Result:
    """Run a case's commands (in-process CLI) and judge each; the first failure, else the
    last outcome. ``timeout``: seconds per command, by SIGALRM (the main thread only; a
    kernel that holds the interpreter is only stopped when it returns, so the benchmark kills
    its worker processes instead)."""
    if invoke is None:
        from typer.testing import CliRunner

        from uavplan.cli import app

        runner = CliRunner()

        def invoke(args: list[str]) -> Any:
            return runner.invoke(app, args)

    last = Result(VALID)
    for k, args in enumerate(case.commands):
        before = set(case.folder.rglob("*")) if case.folder.exists() else set()
        try:
            if timeout is not None:
                signal.signal(signal.SIGALRM, _alarm)
                signal.setitimer(signal.ITIMER_REAL, timeout)
            try:
                result = invoke(args)
            finally:
                if timeout is not None:
                    signal.setitimer(signal.ITIMER_REAL, 0)
            last = judge(args, result, case.folder, before)
        except Exception as exc:  # the oracle itself broke on the output: record it
            last = Result(UNCAUGHT, f"oracle: {type(exc).__name__}: {exc}", args)
        if last.outcome in FAILURES:
            return last
        if k in case.gate and result.exit_code != 0:
            break
    pwned = case.folder / "pwned"
    if pwned.exists():
        return Result(UNCAUGHT, "a YAML tag executed code (the marker file exists)", [])
    return last
