"""Peak resident memory of one packing run, for the memory per particle in docs/benchmarks.md.

Usage: ``python benchmarks/measure_memory.py SCENE SCALE [KEY=VALUE ...]``: packs the
built-in ``SCENE`` with its width (and a box's depth) times ``SCALE`` and
``count = "auto"``, without analyses, files or verification, and prints one JSON
line with the particle count and the peak resident memory (``ru_maxrss``). Run
it in a fresh process per size; the slope between sizes is the memory per particle.
"""

from __future__ import annotations

import json
import resource
import sys
import time

from regopack.manager import default_registry
from regopack.run import run_scene
from regopack.run3d import run_scene3d
from regopack.scene_model import load_scene, resolve_scene


def main() -> int:
    """Pack the scene and print the JSON line."""
    scene, scale_text, *sets = sys.argv[1:]
    scale = float(scale_text)
    d = load_scene(scene).domain
    over = [*sets, f"domain.width={d.width * scale}"]
    if d.dimension == 3:
        over.append(f"domain.depth={d.depth * scale}")
    resolved = resolve_scene(load_scene(scene, over), default_registry())
    start = time.perf_counter()
    run = run_scene3d if d.dimension == 3 else run_scene
    out = run(resolved, None, verify=False)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    line = {"scene": scene, "scale": scale, "sets": sets, "n": out.summary["tried"]}
    line |= {"peak_rss": peak, "seconds": round(time.perf_counter() - start, 1)}
    print(json.dumps(line), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
