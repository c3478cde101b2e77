"""Plans, results and scenarios show themselves in IPython: the HTML formatter gives the summary
table and the inline figure."""

from __future__ import annotations

import pytest

from uavplan import notebook_display
from uavplan.planners import get_planner
from uavplan.planners.fleet.fleet_plan import plan_all
from uavplan.scenarios import resolve


def test_a_plan_and_a_scenario_render_in_ipython() -> None:
    pytest.importorskip("IPython")
    from IPython.core.interactiveshell import InteractiveShell

    shell = InteractiveShell.instance()
    try:
        assert notebook_display(shell)
        sc = resolve("ppswarm1@3")
        plan = plan_all(sc, get_planner("ppswarm", n_restart=1, pop_size=20), 3, 0)
        shown, _ = shell.display_formatter.format(plan)
        page = shown["text/html"]
        assert "<table>" in page and 'src="data:image/png;base64,' in page
        assert all(f"<td>{r.uav_id}</td>" in page for r in plan.results)
        assert ("the plan flies" in page) == plan.feasible
        one, _ = shell.display_formatter.format(plan.results[0])
        assert "<td>uav0</td>" in one["text/html"]
        scene, _ = shell.display_formatter.format(sc)
        assert "ppswarm1" in scene["text/html"] and "<img" in scene["text/html"]
    finally:
        InteractiveShell.clear_instance()


def test_outside_ipython_nothing_is_registered() -> None:
    assert notebook_display() is False
