"""``uavplan --help`` and each command's help read as sentences: a paragraph is one line (the
help box wraps it), and the command list gives each command's first sentence."""

from __future__ import annotations

import pytest
import typer
from typer.testing import CliRunner

from uavplan.cli import app


def _commands(t: typer.Typer) -> list[typer.models.CommandInfo]:
    out = list(t.registered_commands)
    for g in t.registered_groups:
        if g.typer_instance is not None:
            out += _commands(g.typer_instance)
    return out


def test_every_command_help_is_sentences() -> None:
    infos = _commands(app)
    assert len(infos) > 15
    for info in infos:
        assert info.help, info.name
        for para in info.help.split("\n\n"):
            assert "\n" not in para and "  " not in para, (info.name, para)
        assert info.short_help and info.help.startswith(info.short_help.rstrip(".")), info.name


def test_the_command_list_shows_whole_sentences() -> None:
    r = CliRunner().invoke(app, ["--help"], env={"COLUMNS": "200"})
    assert r.exit_code == 0
    line = next(x for x in r.output.splitlines() if "│ plan " in x)
    assert "OUT/plan.html." in line and "single UAV" not in r.output


def test_running_out_of_memory_is_one_line_not_a_traceback(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import uavplan.cli as cli

    def boom() -> None:
        raise MemoryError("Allocation failed (probably too large).")

    monkeypatch.setattr(cli, "app", boom)
    with pytest.raises(SystemExit) as exc:
        cli.main()
    assert exc.value.code == 1
    text = capsys.readouterr().err
    assert "out of memory" in text and "Traceback" not in text
