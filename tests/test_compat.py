"""Old module names: the new module object under the old name, a warning, and no use left."""

from __future__ import annotations

import re
import sys
import warnings
from pathlib import Path

import pytest

import regopack.geometry.domain
from regopack._compat import FINDER, MOVED_MODULES, AliasFinder, install

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture
def fresh_domain3d():  # type: ignore[no-untyped-def]
    """Forget an earlier import of ``regopack.domain3d``, so that importing it runs again."""
    sys.modules.pop("regopack.domain3d", None)
    yield
    sys.modules.pop("regopack.domain3d", None)


def test_the_finder_is_installed_once() -> None:
    install()
    assert sum(f is FINDER for f in sys.meta_path) == 1


def test_an_old_module_name_is_the_new_module_and_warns_once(
    fresh_domain3d: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    with pytest.warns(
        DeprecationWarning, match=r"regopack\.domain3d is deprecated.*regopack\.geometry\.domain"
    ) as caught:
        import regopack.domain3d as old
    assert [w.filename for w in caught] == [__file__]  # blames the importing line
    assert old is regopack.geometry.domain
    assert old.Box is regopack.geometry.domain.Box
    assert regopack.geometry.domain.__spec__.name == "regopack.geometry.domain"
    monkeypatch.setattr(old, "DOMAIN_KINDS", {})
    assert regopack.geometry.domain.DOMAIN_KINDS == {}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        from regopack.domain3d import Box  # imported already: no second warning
    assert Box is regopack.geometry.domain.Box


def test_the_old_3d_names_read_boxes_and_warn(fresh_domain3d: None) -> None:
    with pytest.warns(DeprecationWarning):
        from regopack.domain3d import DOMAIN3D_KINDS, domain3d_from_dict
    assert DOMAIN3D_KINDS == {
        "box": regopack.geometry.domain.Box,
        "periodic-box": regopack.geometry.domain.PeriodicBox,
        "cylinder": regopack.geometry.domain.Cylinder,
    }
    box = domain3d_from_dict({"kind": "periodic-box", "bounds": [0, 1, 0, 2, 0, 3]})
    assert box == regopack.geometry.domain.PeriodicBox(0.0, 1.0, 0.0, 2.0, 0.0, 3.0)
    with pytest.raises(ValueError):
        domain3d_from_dict({"kind": "rectangle", "bounds": [0, 1, 0, 1]})


def test_a_submodule_of_a_moved_package_moves_with_it() -> None:
    finder = AliasFinder({"pkg.old": "pkg.new"})
    assert finder.target("pkg.old") == "pkg.new"
    assert finder.target("pkg.old.sub") == "pkg.new.sub"
    assert finder.target("pkg.older") is None
    assert finder.target("pkg.new") is None


def _imports_of(old: str) -> re.Pattern[str]:
    """``import old``, ``from old import ...`` and ``from parent import child``."""
    parent, _, child = old.rpartition(".")
    name = re.escape(old)
    return re.compile(
        rf"\b(?:import|from)\s+{name}\b"
        rf"|\bfrom\s+{re.escape(parent)}\s+import\s+(?:\([^)]*|[^\n]*)\b{child}\b"
    )


def test_nothing_in_the_project_imports_an_old_module_name() -> None:
    """Only this test imports a moved module by its old name."""
    # every match holds the old name's last part: a file without it is passed over
    patterns = [(old.rpartition(".")[2], _imports_of(old)) for old in MOVED_MODULES]
    found = []
    for folder in ("core", "plugins", "tests", "docs", "benchmarks"):
        for path in sorted((REPO / folder).rglob("*")):
            if path.suffix not in {".py", ".md"} or path.resolve() == Path(__file__).resolve():
                continue
            text = path.read_text(encoding="utf-8")
            for child, pattern in patterns:
                if child not in text:
                    continue
                found += [f"{path.relative_to(REPO)}: {m.group()}" for m in pattern.finditer(text)]
    assert found == []
