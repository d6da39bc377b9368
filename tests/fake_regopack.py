"""The ``regopack`` command with the fake plugins of ``fakes.py``, for subprocess tests.

``python tests/fake_regopack.py ARGS...`` runs ``regopack ARGS...`` whose
registry holds the fakes (fast: no compiled kernels) and the built-in exporters
and analyzers.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from fakes import fake_registry

import regopack.plugins.analyzers
import regopack.plugins.exporters
import regopack.registry.manager


def registry(**kwargs: object) -> regopack.registry.manager.Registry:
    """The fakes with the built-in exporters and analyzers."""
    return fake_registry(regopack.plugins.exporters, regopack.plugins.analyzers)


if __name__ == "__main__":
    regopack.registry.manager.default_registry = registry  # type: ignore[assignment]
    from regopack.cli import main

    raise SystemExit(main())
