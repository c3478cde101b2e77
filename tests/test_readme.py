"""The README's Python example runs, and its second part reproduces ``uavplan demo --seed 0``."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from uavplan.cli import app

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_python_example_reproduces_the_demo(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = re.search(r"```python\n(.*?)```", README.read_text(), re.S)
    assert code is not None
    exec(compile(code.group(1), "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert "[('run', 'spso', True)]" in out  # the strategy's one attempt, and it flies
    printed = out.split()
    r = CliRunner().invoke(app, ["demo", "--seed", "0", "--out", str(tmp_path)])
    assert r.exit_code in (0, 1), r.output
    demo_cost = json.loads((tmp_path / "plan.json").read_text())["uavs"][0]["cost"]
    assert float(printed[-1]) == pytest.approx(float(demo_cost), rel=1e-12)
