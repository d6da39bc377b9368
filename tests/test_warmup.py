"""Ahead-of-time compilation (regopack.warmup) and the registry it packs with."""

from __future__ import annotations

import regopack.manager
from regopack.testing import make_registry
from regopack.warmup import compile_kernels


def test_compile_kernels_asks_the_default_registry_when_called(monkeypatch):
    """The registry is looked up in regopack.manager at call time (tests and tools patch it):
    without plugins no variant resolves, so nothing is packed."""
    asked: list[dict[str, object]] = []

    def empty(**kwargs: object) -> regopack.manager.Registry:
        asked.append(kwargs)
        return make_registry(builtins=())

    monkeypatch.setattr(regopack.manager, "default_registry", empty)
    steps: list[str] = []
    total = compile_kernels(lambda step, seconds: steps.append(step))
    assert asked and steps == [] and total.functions == 0
