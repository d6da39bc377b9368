"""Insertion time of the working tree against a git revision, alternating in one process.

This machine's speed drifts by tens of percent between processes and within
minutes, so two builds are timed in the same process, turn about (the order
swapped every round), and the ratio of each round is reported with the
median. The revision's ``core`` and ``plugins`` are exported with
``git archive`` into ``<temp>/regopack-ab/<sha>`` as a package named
``regopack_<sha>`` (every ``regopack`` in its sources renamed), so both
builds load side by side; every module of each build is checked to come
from its own folder, and the packings to be the same (placed count and
analyses). The revision's kernels compile on its first run and are cached
with the working tree's. Run from the repository root:

    python benchmarks/ab_builds.py --rev HEAD --size 2400 --rounds 6
    NUMBA_NUM_THREADS=1 python benchmarks/ab_builds.py --rev HEAD~1 --size 1200

The scene is ``dem`` with the tail closing and strips of 800 µm unless
``--set`` changes it (``--set 'phases.0.shape={kind="disk"}'``).

Run it against ``--rev HEAD`` on a clean tree first: the same build against
itself has given medians of 1.035 (two threads) and 1.084 (one thread) on
one machine, the working tree the slower; a change's ratio means something
only against that baseline (docs/benchmarks.md).
"""

from __future__ import annotations

import argparse
import importlib
import io
import platform
import re
import statistics
import subprocess
import sys
import tarfile
import tempfile
import tomllib
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parent.parent


def export_revision(rev: str) -> tuple[str, Path]:
    """Write ``rev``'s package as ``regopack_<sha>``; return its name and the folder holding it."""
    sha = subprocess.run(
        ["git", "rev-parse", "--short", rev], cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout.strip()
    name = f"regopack_{sha}"
    into = Path(tempfile.gettempdir()) / "regopack-ab" / sha
    done = into / "exported"
    if done.exists():  # the same files, so that numba's cache of them stays valid
        return name, into
    blob = subprocess.run(
        ["git", "archive", "--format=tar", rev, "core", "plugins"],
        cwd=ROOT,
        check=True,
        capture_output=True,
    ).stdout
    pkg = into / name
    with tarfile.open(fileobj=io.BytesIO(blob)) as tar:
        for member in tar.getmembers():
            if not member.isfile():
                continue
            rel = Path(member.name)
            target = pkg / (rel.relative_to("core") if rel.parts[0] == "core" else rel)
            target.parent.mkdir(parents=True, exist_ok=True)
            data = tar.extractfile(member)
            assert data is not None
            content = data.read()
            if rel.suffix == ".py":
                content = re.sub(rb"\bregopack\b", name.encode(), content)
            target.write_bytes(content)
    done.write_text(rev)
    return name, into


def check_origin(name: str, folder: Path) -> None:
    """Stop unless every loaded module of package ``name`` lies in ``folder`` (and no other's)."""
    for mod_name, mod in list(sys.modules.items()):
        file = getattr(mod, "__file__", None)
        if file is None or mod_name.partition(".")[0] not in (name, "regopack"):
            continue
        inside = Path(file).resolve().is_relative_to(folder.resolve())
        if inside != (mod_name.partition(".")[0] == name):
            raise SystemExit(f"module {mod_name} loaded from {file}: the builds are mixed")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rev", default="HEAD")
    parser.add_argument("--scene", default="dem")
    parser.add_argument("--size", type=float, default=1600.0)
    parser.add_argument("--rounds", type=int, default=6)
    parser.add_argument("--set", action="append", default=[], dest="overrides")
    args = parser.parse_args()
    import regopack  # first: its kernel cache folder is the one both builds use

    old_name, folder = export_revision(args.rev)
    sys.path.insert(0, str(folder))
    builds: dict[str, ModuleType] = {
        args.rev: importlib.import_module(old_name),
        "tree": regopack,
    }
    print(f"tree: {Path(regopack.__file__).parent}; {args.rev}: {folder / old_name}")
    base = [
        'insertion.closing="tail"',
        "insertion.strip=800",
        *args.overrides,
    ]
    sized = [f"domain.width={args.size}", f"domain.height={args.size}"]
    times: dict[str, list[float]] = {k: [] for k in builds}
    print(f"machine: {platform.machine()}, Python {platform.python_version()}")
    print(f"{args.scene}, L = {args.size:g}, {' '.join(base)}")
    warm = min(args.size, 400.0)  # large enough to compile every kernel the runs call
    for mod in builds.values():
        mod.pack(args.scene, **_kw(base + [f"domain.width={warm}", f"domain.height={warm}"]))
    check_origin(old_name, folder / old_name)
    for r in range(args.rounds):
        seen = set()
        for key in list(builds) if r % 2 == 0 else list(builds)[::-1]:
            p = builds[key].pack(args.scene, **_kw(base + sized))
            times[key].append(p.stats["insert_time_s"])
            seen.add((p.n_placed, p.stats["candidate_analyses"]))
            print(f"round {r}  {key:>10}  placed {p.n_placed}  insert {times[key][-1]:.3f} s")
        if len(seen) != 1:
            raise SystemExit(f"the builds' packings differ: {sorted(seen)}")
    ratios = [a / b for a, b in zip(times["tree"], times[args.rev], strict=True)]
    for key, ts in times.items():
        print(f"{key:>10}: min {min(ts):.3f} s, median {statistics.median(ts):.3f} s")
    print(
        f"tree / {args.rev} per round: {' '.join(f'{x:.3f}' for x in ratios)};"
        f" median {statistics.median(ratios):.3f}"
    )


def _kw(overrides: list[str]) -> dict[str, object]:
    """``--set``-style overrides as keyword arguments of ``regopack.pack``."""
    out: dict[str, object] = {}
    for item in overrides:
        key, _, value = item.partition("=")
        out[key] = tomllib.loads(f"v = {value}")["v"]
    return out


if __name__ == "__main__":
    main()
