"""The notebook under ``examples/`` runs top to bottom in a Jupyter kernel (nbclient), and the plan
and the scenario it shows render as HTML: their tables and figures."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_the_example_notebook_runs_and_a_plan_renders() -> None:
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    nb = nbformat.read(ROOT / "examples" / "fleet_notebook.ipynb", as_version=4)
    nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(ROOT)}}).execute()  # fmt: skip
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    pages = [o["data"]["text/html"] for o in outputs if "text/html" in o.get("data", {})]
    assert len(pages) == 2, [o.get("output_type") for o in outputs]
    plan, scenario = pages
    assert "<table>" in plan and "<td>uav5</td>" in plan and "data:image/png;base64," in plan
    assert "ppswarm1" in scenario and "<img" in scenario
