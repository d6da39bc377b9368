"""The documentation site builds with every warning an error (mkdocs --strict).

The build renders the API reference from the docstrings (mkdocstrings), so a
broken cross-reference, a missing page in the navigation or a docstring that
does not parse fails here.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_the_site_builds_strictly(tmp_path):
    pytest.importorskip("mkdocstrings_handlers.python")
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    page = (tmp_path / "site" / "reference" / "api" / "functions" / "index.html").read_text()
    for name in ("scene", "pack", "analyze", "verify", "export", "sweep"):
        assert f'id="regopack.api.functions.{name}"' in page
    assert ":func:" not in page  # Sphinx roles are rewritten
    shutil.rmtree(tmp_path / "site")
