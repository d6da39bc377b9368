"""Runs: a scene in, a packing, its summary, analyses and exports out (one folder)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from regopack._exports import lazy_exports

if TYPE_CHECKING:
    from regopack.run.pipeline import BYTES_PER_PARTICLE as BYTES_PER_PARTICLE
    from regopack.run.pipeline import PARTICLE_BYTES as PARTICLE_BYTES
    from regopack.run.pipeline import RUN_FOLDER as RUN_FOLDER
    from regopack.run.pipeline import RunOutcome as RunOutcome
    from regopack.run.pipeline import check_runnable as check_runnable
    from regopack.run.pipeline import check_scene as check_scene
    from regopack.run.pipeline import default_out_dir as default_out_dir
    from regopack.run.pipeline import draw_population as draw_population
    from regopack.run.pipeline import memory_limit as memory_limit
    from regopack.run.pipeline import particle_bytes as particle_bytes
    from regopack.run.pipeline import particle_count as particle_count
    from regopack.run.pipeline import phi_in_window as phi_in_window
    from regopack.run.pipeline import run_scene as run_scene

__all__ = [
    "BYTES_PER_PARTICLE",
    "PARTICLE_BYTES",
    "RUN_FOLDER",
    "RunOutcome",
    "check_runnable",
    "check_scene",
    "default_out_dir",
    "draw_population",
    "memory_limit",
    "particle_bytes",
    "particle_count",
    "phi_in_window",
    "run_scene",
]

__getattr__, __dir__ = lazy_exports(globals(), "regopack.run.pipeline")
