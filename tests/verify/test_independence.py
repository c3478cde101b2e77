"""The verifier is written apart from the planner: this is everything of uavplan it imports
(the import-linter contracts in pyproject.toml also forbid planning code, even indirectly)."""

from __future__ import annotations

import ast
from pathlib import Path

import uavplan.verify

#: What the verifier may import: the plan file reader (typed trajectories), the scenario as
#: data (its classes; the terrain's grid, not its clearance kernels; the airframes' limits and
#: calibration wind), the tolerances, the
#: obstacle index (its broad phase only: which segments are near which obstacle; the exact
#: tests are its own), itself.
ALLOWED = {
    "uavplan.io.plan_file",
    "uavplan.world.airframes",
    "uavplan.world.obstacle_index",
    "uavplan.world.obstacles",
    "uavplan.world.scenario",
    "uavplan.world.terrain",
    "uavplan.world.tolerances",
    "uavplan.verify",
}


def imports_of(package_dir: Path) -> set[str]:
    out: set[str] = set()
    for f in package_dir.glob("*.py"):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                out.add(node.module)
            elif isinstance(node, ast.Import):
                out.update(a.name for a in node.names)
    return {m for m in out if m.startswith("uavplan")}


def test_the_verifier_imports_only_data_and_itself() -> None:
    used = imports_of(Path(uavplan.verify.__file__).parent)
    outside = {m for m in used if not any(m == a or m.startswith(a + ".") for a in ALLOWED)}
    assert not outside, f"the verifier imports {sorted(outside)}"
    assert "uavplan.io.plan_file" in used  # it reads plans through the plan file module


def test_it_calls_no_terrain_kernel() -> None:
    """Terrain is imported as data: the verifier never calls the planner's clearance methods."""
    text = "\n".join(f.read_text() for f in Path(uavplan.verify.__file__).parent.glob("*.py"))
    for method in (".clears(", ".min_clearance(", ".max_clearance(", ".stays_within("):
        assert method not in text, method
