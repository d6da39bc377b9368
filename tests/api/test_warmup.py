"""Ahead-of-time compilation (regopack.api.warmup) and the registry it packs with."""

from __future__ import annotations

import regopack.registry.manager
from regopack.api.warmup import compile_kernels
from regopack.testing import make_registry


def test_compile_kernels_asks_the_default_registry_when_called(monkeypatch):
    """The registry is looked up in the manager module at call time (tests and tools patch it):
    without plugins no variant resolves, so nothing is packed."""
    asked: list[dict[str, object]] = []

    def empty(**kwargs: object) -> regopack.registry.manager.Registry:
        asked.append(kwargs)
        return make_registry(builtins=())

    monkeypatch.setattr(regopack.registry.manager, "default_registry", empty)
    steps: list[str] = []
    total = compile_kernels(lambda step, seconds: steps.append(step))
    assert asked and steps == [] and total.functions == 0
