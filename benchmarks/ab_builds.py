"""Insertion time of two builds, alternating in one process.

This machine's speed drifts by tens of percent between processes and within
minutes, so two builds are timed in the same process, turn about (the order
swapped every round), and the ratio of each round is reported with the
median. Both builds are exported into ``<temp>/regopack-ab/<id>`` as
packages named ``regopack_<id>`` (every ``regopack`` in their sources
renamed): ``--rev`` from git with ``git archive``, ``--new`` likewise, or,
by default, the working tree's ``core`` and ``plugins`` as they are on disk
(``<id>`` is then a hash of their contents). Neither build is the installed
package, so both load the same way; every module is checked to come from
its own folder, and the packings to be the same (placed count and
analyses). Each build's kernels compile on its first run and are cached.
Run from the repository root:

    python benchmarks/ab_builds.py --rev HEAD --size 1600 --rounds 8
    NUMBA_NUM_THREADS=1 python benchmarks/ab_builds.py --rev HEAD~1 --new HEAD --size 800

The scene is ``dem`` with the tail closing and strips of 800 µm unless
``--set`` changes it (``--set 'phases.0.shape={kind="disk"}'``).

The build whose package is loaded first runs faster, by 5-8 % on one
machine, whichever build it is; so the script runs ``--passes`` processes
(two by default), loading the base first in one and the new build first in
the next, and reports each order's median ratio and their geometric mean,
in which that factor cancels. The same kernels against themselves give
1.006-1.008 that way (docs/benchmarks.md).
"""

from __future__ import annotations

import argparse
import hashlib
import importlib
import io
import platform
import re
import statistics
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parent.parent


def revision_files(rev: str) -> tuple[str, dict[Path, bytes]]:
    """``rev``'s short sha and the files of its ``core`` and ``plugins``."""
    sha = subprocess.run(
        ["git", "rev-parse", "--short", rev], cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout.strip()
    blob = subprocess.run(
        ["git", "archive", "--format=tar", rev, "core", "plugins"],
        cwd=ROOT,
        check=True,
        capture_output=True,
    ).stdout
    files: dict[Path, bytes] = {}
    with tarfile.open(fileobj=io.BytesIO(blob)) as tar:
        for member in tar.getmembers():
            data = tar.extractfile(member) if member.isfile() else None
            if data is not None:
                files[Path(member.name)] = data.read()
    return sha, files


def tree_files() -> tuple[str, dict[Path, bytes]]:
    """A hash of the working tree's ``core`` and ``plugins`` as on disk, and their files."""
    files: dict[Path, bytes] = {}
    for top in ("core", "plugins"):
        for path in sorted((ROOT / top).rglob("*")):
            if path.is_file() and "__pycache__" not in path.parts:
                files[path.relative_to(ROOT)] = path.read_bytes()
    digest = hashlib.sha1()
    for rel, content in sorted(files.items()):
        digest.update(str(rel).encode() + b"\0" + content)
    return "t" + digest.hexdigest()[:9], files


def export(ident: str, files: dict[Path, bytes]) -> tuple[str, Path]:
    """Write ``files`` as package ``regopack_<ident>``; return its name and its folder."""
    name = f"regopack_{ident}"
    into = Path(tempfile.gettempdir()) / "regopack-ab" / ident
    done = into / "exported"
    if done.exists():  # the same files, so that numba's cache of them stays valid
        return name, into
    if not files:
        raise SystemExit(f"no exported build at {into}")
    pkg = into / name
    for rel, content in files.items():
        target = pkg / (rel.relative_to("core") if rel.parts[0] == "core" else rel)
        target.parent.mkdir(parents=True, exist_ok=True)
        if rel.suffix == ".py":
            content = re.sub(rb"\bregopack\b", name.encode(), content)
        target.write_bytes(content)
    done.write_text(ident)
    return name, into


def export_revision(rev: str) -> tuple[str, Path]:
    """Export ``rev`` with :func:`export`, reading it from git only when not yet exported."""
    sha = subprocess.run(
        ["git", "rev-parse", "--short", rev], cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout.strip()
    if (Path(tempfile.gettempdir()) / "regopack-ab" / sha / "exported").exists():
        return export(sha, {})
    return export(*revision_files(rev))


def check_origin(packages: dict[str, Path]) -> None:
    """Stop unless every loaded module of each package lies in that package's folder."""
    for mod_name, mod in list(sys.modules.items()):
        file = getattr(mod, "__file__", None)
        top = mod_name.partition(".")[0]
        if file is None or top not in packages:
            continue
        if not Path(file).resolve().is_relative_to(packages[top].resolve()):
            raise SystemExit(f"module {mod_name} loaded from {file}: the builds are mixed")


def _check_scene(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Stop with regopack's one line unless the scene builds with the fixed settings,
    ``--set`` and the size (checked with the installed package, not the builds compared)."""
    from regopack.errors import RegopackError
    from regopack.manager import default_registry
    from regopack.scene_model import load_scene, resolve_scene

    sized = [f"domain.width={args.size}", f"domain.height={args.size}"]
    try:
        resolve_scene(load_scene(args.scene, [*BASE, *args.overrides, *sized]), default_registry())
    except RegopackError as exc:
        parser.error(str(exc))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rev", default="HEAD", help="the base build (a git revision)")
    parser.add_argument("--new", default=None, help="a git revision (default: the working tree)")
    parser.add_argument("--scene", default="dem")
    parser.add_argument("--size", type=float, default=1600.0)
    parser.add_argument("--rounds", type=int, default=6, help="rounds in each process")
    parser.add_argument("--passes", type=int, default=2, help="processes, loading order swapped")
    parser.add_argument("--set", action="append", default=[], dest="overrides")
    parser.add_argument("--first", choices=("rev", "new"), help=argparse.SUPPRESS)
    parser.add_argument("--ids", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.rounds < 1 or args.passes < 1:
        parser.error("--rounds and --passes take 1 or more")
    if args.first is None:  # the passes' parent checks the scene once for them
        _check_scene(parser, args)
    new_label = args.new or "tree"
    if args.ids:  # a pass: the builds its parent exported
        exported = {args.rev: export(args.ids[0], {}), new_label: export(args.ids[1], {})}
    else:
        exported = {
            args.rev: export_revision(args.rev),
            new_label: export_revision(args.new) if args.new else export(*tree_files()),
        }
    if len({name for name, _ in exported.values()}) != 2:
        raise SystemExit("--rev and --new name the same files; export one of them as the tree")
    if args.first is None:
        ids = [name.removeprefix("regopack_") for name, _ in exported.values()]
        passes(args, new_label, ids)
        return
    if args.first == "new":
        exported = dict(reversed(exported.items()))
    ratios = time_builds(args, exported)
    print(f"{MARK} {args.first} {' '.join(f'{x:.6f}' for x in ratios)}")


MARK = "ratios-of-pass:"
BASE = ['insertion.closing="tail"', "insertion.strip=800"]
"""Settings of every timed run, before ``--set``'s."""


def passes(args: argparse.Namespace, new_label: str, ids: list[str]) -> None:
    """Run ``args.passes`` processes, loading first the base and the new build in turn.

    Each process times the builds exported here (``ids``), even if the tree or
    the revisions change meanwhile.
    """
    by_order: dict[str, list[float]] = {"rev": [], "new": []}
    argv = list(sys.argv[1:])
    for k in range(args.passes):
        first = "rev" if k % 2 == 0 else "new"
        print(f"pass {k}: {args.rev if first == 'rev' else new_label} loaded first", flush=True)
        # the pass's output (its warnings too) is shown as it comes
        with subprocess.Popen(
            [sys.executable, "-u", __file__, *argv, "--first", first, "--ids", *ids],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        ) as child:
            assert child.stdout is not None
            for line in child.stdout:
                if line.startswith(MARK):
                    by_order[first] += [float(x) for x in line.split()[2:]]
                else:
                    print("  " + line.rstrip("\n"), flush=True)
        if child.returncode != 0:
            raise SystemExit(f"pass {k} failed (exit status {child.returncode})")
    medians = {k: statistics.median(v) for k, v in by_order.items() if v}
    for k, m in medians.items():
        loaded = args.rev if k == "rev" else new_label
        print(f"{new_label} / {args.rev}, {loaded} loaded first: median {m:.3f}")
    if len(medians) == 2:
        both = (medians["rev"] * medians["new"]) ** 0.5
        print(f"{new_label} / {args.rev}: {both:.3f} (geometric mean of the two orders)")
    else:
        print("one loading order only: its median carries the first-loaded build's advantage")


def time_builds(args: argparse.Namespace, exported: dict[str, tuple[str, Path]]) -> list[float]:
    """Time the builds in ``exported``'s order, turn about; return new / base per round."""
    import regopack  # noqa: F401  first: its kernel cache folder is the one both builds use

    builds: dict[str, ModuleType] = {}
    for label, (name, folder) in exported.items():
        sys.path.insert(0, str(folder))
        builds[label] = importlib.import_module(name)
        print(f"{label}: {folder / name}")
    base = [*BASE, *args.overrides]
    sized = [f"domain.width={args.size}", f"domain.height={args.size}"]
    times: dict[str, list[float]] = {k: [] for k in builds}
    print(f"machine: {platform.machine()}, Python {platform.python_version()}")
    print(f"{args.scene}, L = {args.size:g}, {' '.join(base)}")
    warm = min(args.size, 400.0)  # large enough to compile every kernel the runs call
    for mod in builds.values():
        mod.pack(args.scene, **_kw(base + [f"domain.width={warm}", f"domain.height={warm}"]))
    check_origin({name: folder / name for name, folder in exported.values()})
    for r in range(args.rounds):
        seen = set()
        for key in list(builds) if r % 2 == 0 else list(builds)[::-1]:
            p = builds[key].pack(args.scene, **_kw(base + sized))
            times[key].append(p.stats["insert_time_s"])
            seen.add((p.n_placed, p.stats["candidate_analyses"]))
            print(f"round {r}  {key:>10}  placed {p.n_placed}  insert {times[key][-1]:.3f} s")
        if len(seen) != 1:
            raise SystemExit(f"the builds' packings differ: {sorted(seen)}")
    new_label = args.new or "tree"
    ratios = [a / b for a, b in zip(times[new_label], times[args.rev], strict=True)]
    for key, ts in times.items():
        print(f"{key:>10}: min {min(ts):.3f} s, median {statistics.median(ts):.3f} s")
    print(
        f"{new_label} / {args.rev} per round: {' '.join(f'{x:.3f}' for x in ratios)};"
        f" median {statistics.median(ratios):.3f}"
    )
    return ratios


def _kw(overrides: list[str]) -> dict[str, object]:
    """``--set``-style overrides as keyword arguments of ``regopack.pack``, read as
    ``regopack run --set`` reads them."""
    from regopack.scene_model import _parse_override

    return dict(_parse_override(item) for item in overrides)


if __name__ == "__main__":
    main()
