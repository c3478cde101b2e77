"""docs/extending.md's worked example stays true: its planner, defined in one block of code,
registers and passes the planner contract tests."""

from __future__ import annotations

import re
import sys
import types
from collections.abc import Iterator
from pathlib import Path

import pytest

from planners import test_planners as contract
from uavplan.planners import available_planners, get_planner
from uavplan.planners.core.registry import unregister_planner

DOC = Path(__file__).resolve().parents[1] / "docs" / "extending.md"


@pytest.fixture(scope="module")
def detour() -> Iterator[str]:
    code = re.findall(r"```python\n(.*?)```", DOC.read_text(), flags=re.S)[0]
    module = types.ModuleType("extending_example")  # as if it were a file of its own
    sys.modules[module.__name__] = module
    exec(compile(code, str(DOC), "exec"), module.__dict__)
    assert "random-detour" in available_planners()
    yield "random-detour"
    unregister_planner("random-detour")
    del sys.modules[module.__name__]


@pytest.mark.parametrize("make", [contract.easy_2d, contract.easy_3d], ids=["2d", "3d"])
def test_the_example_planner_passes_the_contract(detour: str, make) -> None:  # type: ignore[no-untyped-def]
    contract.test_planner_solves_easy_scenario(detour, make)


def test_the_example_planner_behaves(detour: str) -> None:
    contract.test_planner_deterministic_per_seed(detour)
    contract.test_describe_is_generated_from_the_config(detour)
    contract.test_callback_stops_the_run(detour)
    contract.test_unknown_option_is_refused_naming_the_valid_ones(detour)
    contract.test_out_of_range_options_are_refused(detour)
    contract.test_malformed_tasks_and_budgets_are_refused(detour)
    assert get_planner(detour, samples=8).config.samples == 8


def test_the_strategy_example_runs() -> None:
    """The worked example of changing the default: a table of one's own, executed."""
    code = next(c for c in re.findall(r"```python\n(.*?)```", DOC.read_text(), flags=re.S)
                if "strategy_for(scenario, mine)" in c)  # fmt: skip
    ns: dict[str, object] = {}
    exec(compile(code, str(DOC), "exec"), ns)
    attempts = ns["attempts"]
    assert [a[:2] for a in attempts[:3]] == [("run", "rrt-star"), ("run", "rrt-star"),
                                             ("also", "spso")]  # fmt: skip
    assert attempts[0][2] == 0 and attempts[2][2] == 0 and attempts[1][2] != 0
    assert all(a[0] == "fallback" for a in attempts[3:])
    assert ns["kept"].plan.results is ns["outcome"].plan.results  # type: ignore[attr-defined]
