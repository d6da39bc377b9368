"""Helpers shared by the command-line tests."""

from __future__ import annotations

import pytest


def one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    """Return the single ``regopack: error: ...`` line the command printed to stderr."""
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("regopack: error: ")
    return lines[0]
