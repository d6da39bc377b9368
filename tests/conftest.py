from __future__ import annotations

import importlib.metadata

import pytest


def _version(dist: str) -> str:
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return "not installed"


def pytest_report_header(config: pytest.Config) -> str:
    names = ("regopack", "numpy", "scipy", "shapely", "numba", "pydantic", "pluggy")
    return "versions: " + ", ".join(f"{n} {_version(n)}" for n in names)


@pytest.fixture
def registry():
    from fakes import fake_registry

    return fake_registry()
