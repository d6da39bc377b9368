"""The lazy names of the sub-packages (regopack._exports)."""

from __future__ import annotations

import importlib
import sys
from types import ModuleType
from typing import Any

import pytest

from regopack._exports import lazy_exports


def _package(name: str, names: list[str], sources: Any) -> ModuleType:
    module = ModuleType(name)
    module.__all__ = names  # type: ignore[attr-defined]
    module.__getattr__, module.__dir__ = lazy_exports(vars(module), sources)  # type: ignore[method-assign]
    return module


def test_a_name_is_loaded_from_its_module_on_first_use_and_kept() -> None:
    package = _package("pkg", ["dumps", "sqrt"], {"dumps": "json", "sqrt": "math"})
    assert "dumps" not in vars(package)
    assert package.dumps is importlib.import_module("json").dumps
    assert package.sqrt is importlib.import_module("math").sqrt
    assert "dumps" in vars(package)


def test_one_module_name_serves_every_name_of_all() -> None:
    package = _package("pkg", ["dumps", "loads"], "json")
    assert package.loads is importlib.import_module("json").loads
    assert dir(package) == ["dumps", "loads"]


def test_a_name_not_offered_is_an_attribute_error() -> None:
    package = _package("pkg", ["dumps"], {"dumps": "json"})
    with pytest.raises(AttributeError, match="'pkg' has no attribute 'loads'"):
        package.loads  # noqa: B018
    package = _package("pkg", ["dumps"], "json")
    for name in ("nothing_such", "_default_decoder"):  # neither in the module nor public
        with pytest.raises(AttributeError, match=f"'pkg' has no attribute '{name}'"):
            getattr(package, name)


def test_a_package_in_place_of_a_module_offers_its_other_public_names() -> None:
    # as the module did before it moved: regopack.run was one module
    import regopack.analysis
    import regopack.run
    from regopack.analysis.pipeline import FigureWarning
    from regopack.run.pipeline import summary_rows

    assert regopack.run.summary_rows is summary_rows
    assert regopack.analysis.FigureWarning is FigureWarning
    package = _package("pkg", ["dumps"], "json")
    assert package.loads is importlib.import_module("json").loads
    assert dir(package) == ["dumps"]


def test_a_submodule_is_not_taken_for_a_name_of_the_module(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    pkg = tmp_path / "lazypkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text(
        "from regopack._exports import lazy_exports\n"
        "__all__ = ['x']\n"
        "__getattr__, __dir__ = lazy_exports(globals(), 'lazypkg.core')\n"
    )
    (pkg / "core.py").write_text("x = 1\nsibling = 'a name of core'\n")
    (pkg / "sibling.py").write_text("")
    monkeypatch.syspath_prepend(str(tmp_path))
    from lazypkg import sibling, x  # type: ignore[import-not-found]

    assert x == 1
    assert isinstance(sibling, ModuleType) and sibling.__name__ == "lazypkg.sibling"
    for name in ("lazypkg", "lazypkg.core", "lazypkg.sibling"):
        monkeypatch.delitem(sys.modules, name, raising=False)


@pytest.mark.parametrize("name", ["regopack.run", "regopack.analysis", "regopack.plugins.shapes"])
def test_the_sub_packages_list_and_load_their_names(name: str) -> None:
    package = sys.modules.get(name) or importlib.import_module(name)
    assert dir(package) == sorted(package.__all__)
    for each in package.__all__:
        assert getattr(package, each) is not None
