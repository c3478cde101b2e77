"""What the command groups share: error exits without a traceback, ``--param`` parsing."""

from __future__ import annotations

from typing import Any

import typer
from rich.console import Console

#: messages stay one line each (no wrapping at the terminal's width), also when piped
err = Console(stderr=True, soft_wrap=True, highlight=False)
out = Console(soft_wrap=True)


def fail(lines: list[str] | str, code: int = 2) -> typer.Exit:
    """Print problem lines to stderr and return the Exit to raise (no traceback)."""
    for line in [lines] if isinstance(lines, str) else lines:
        err.print(line, markup=False, highlight=False)
    return typer.Exit(code)


def parse_params(params: list[str]) -> dict[str, Any]:
    parsed: dict[str, Any] = {}
    for item in params:
        if "=" not in item:
            raise fail(f"--param {item!r}: expected NAME=VALUE")
        k, v = item.split("=", 1)
        value: Any = v
        for conv in (int, float):
            try:
                value = conv(v)
                break
            except ValueError:
                continue
        if v.lower() in ("true", "false"):
            value = v.lower() == "true"
        parsed[k.strip()] = value
    return parsed
