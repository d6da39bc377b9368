"""``regopack plugins`` in a pipe and in a narrow terminal: quiet exit, names never cut."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from regopack.registry.manager import default_registry
from regopack.scenes.schema import describe_plugins

REGOPACK = Path(sys.executable).parent / "regopack"


@pytest.mark.parametrize("command", [["plugins"], ["scenes"], ["schema"]])
def test_a_reader_that_goes_away_ends_the_command_quietly(command):
    """As in ``regopack plugins | head -1``: exit status 0, nothing on stderr."""
    env = {**os.environ, "COLUMNS": "2000"}  # padded lines: far more than a pipe buffer
    with subprocess.Popen(
        [str(REGOPACK), *command],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
    ) as proc:
        assert proc.stdout is not None and proc.stderr is not None
        assert proc.stdout.readline()
        proc.stdout.close()
        err = proc.stderr.read()
        assert proc.wait(timeout=120) == 0
    assert err == b""


def test_a_broken_pipe_in_process_returns_0(monkeypatch):
    from regopack.cli import main

    class Closed:
        def write(self, text: str) -> int:
            raise BrokenPipeError

        def flush(self) -> None:
            raise BrokenPipeError

        def isatty(self) -> bool:
            return False

    monkeypatch.setattr(sys, "stdout", Closed())
    assert main(["plugins"]) == 0


@pytest.mark.parametrize("columns", [80, 60])
def test_names_are_never_cut_in_a_narrow_terminal(columns):
    env = {**os.environ, "COLUMNS": str(columns)}
    done = subprocess.run(
        [str(REGOPACK), "plugins"], env=env, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert max(len(line) for line in lines) <= columns
    words = set(re.findall(r"[\w.\-]+", done.stdout))
    for entry in describe_plugins(default_registry(), None):
        assert entry["name"] in words, entry["name"]
        for field in entry["fields"]:
            assert field["name"] in words, (entry["name"], field["name"])
    # text is wrapped or folded, never cut with an ellipsis (lists say "… (n values)")
    cut = [line for line in lines if re.search(r"…(?! \(\d+)", line)]
    assert not cut, cut[:3]
