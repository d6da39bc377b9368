"""The core (``core/``, installed as ``regopack``) never imports a plugin.

Arrows run one way: plugins import the core; the core reaches plugins only
through the registry (hooks) and, for the kernel cache key, through the
distribution's metadata (:mod:`regopack.base.jit`).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

CORE = Path(__file__).resolve().parents[1] / "core"
PLUGINS = "regopack.plugins"


def _modules() -> list[Path]:
    return sorted(CORE.rglob("*.py"))


def plugin_imports(source: str, package: str = "regopack") -> list[str]:
    """Every import of ``regopack.plugins`` (or below) in ``source``, as ``line: module``.

    ``package`` is the package the module lies in, for relative imports.
    """
    found: list[str] = []
    parts = package.split(".")
    for node in ast.walk(ast.parse(source)):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = ".".join(parts[: len(parts) - node.level + 1]) if node.level else ""
            module = ".".join(p for p in (base, node.module or "") if p)
            names = [module, *(f"{module}.{alias.name}" for alias in node.names)]
        hits = [n for n in names if n == PLUGINS or n.startswith(PLUGINS + ".")]
        if hits:
            found.append(f"{node.lineno}: {hits[0]}")
    return found


def test_there_are_core_modules() -> None:
    assert len(_modules()) > 20


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(CORE)))
def test_a_core_module_imports_no_plugin(path: Path) -> None:
    package = ".".join(["regopack", *path.parent.relative_to(CORE).parts])
    assert plugin_imports(path.read_text(encoding="utf-8"), package) == []


def test_the_scan_finds_every_form_of_import() -> None:
    source = (
        "import regopack.plugins\n"
        "import regopack.plugins.shapes.octagon as o\n"
        "from regopack.plugins.analyzers import figures\n"
        "from regopack import plugins\n"
        "def f():\n"
        "    from . import plugins\n"
        "    from .plugins import exporters\n"
        "import regopack.packing.core\n"
        "from regopack import packing\n"
        "from .. import plugins\n"
    )
    lines = [hit.split(":")[0] for hit in plugin_imports(source)]
    assert lines == ["1", "2", "3", "4", "6", "7"]
    assert [h.split(":")[0] for h in plugin_imports(source, "regopack.scenes")] == [
        "1",
        "2",
        "3",
        "4",
        "10",
    ]


def test_importing_every_core_module_loads_no_plugin() -> None:
    """The same at run time: what the source scan cannot see (importlib, __import__)."""
    import subprocess
    import sys

    modules = sorted(
        ".".join(["regopack", *p.relative_to(CORE).with_suffix("").parts]).removesuffix(".__init__")
        for p in _modules()
        if p.stem != "__main__"
    )
    assert "regopack.run.pipeline" in modules
    code = (
        "import importlib, sys\n"
        f"for name in {modules!r}:\n"
        "    importlib.import_module(name)\n"
        "print([m for m in sys.modules if m.startswith('regopack.plugins')])\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
