"""Fingerprints of packings and analyses, to check that a change leaves them bit for bit.

Packs a fixed list of scenes (the built-in ones, cut to a size that packs in
seconds, and variants that reach every domain kind, disks, η, the sweep and
3D), analyses each, and writes one SHA-256 per array::

    python benchmarks/reference_dump.py --out /tmp/before.json
    # ... change the code ...
    python benchmarks/reference_dump.py --out /tmp/after.json --compare /tmp/before.json

``--compare`` prints every entry that differs and exits 1 if any does.
"""

from __future__ import annotations

import argparse
import copy
import hashlib
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

import regopack

Edit = dict[str, Any]
SCENES: dict[str, tuple[str, Edit]] = {
    "table1_small": ("table1", {"domain": {"width": 200.0, "height": 200.0}}),
    "small": ("small", {}),
    "small_eta5": ("small", {"density": {"eta": 5.0}}),
    "small_seed3": ("small", {"seed": 3}),
    "small_periodic": ("small", {"domain": {"kind": "periodic"}}),
    "small_circle": (
        "small",
        {"domain": {"kind": "circle", "radius": 90.0, "width": None, "height": None}},
    ),
    "small_polygon": (
        "small",
        {
            "domain": {
                "kind": "polygon",
                "vertices": [[-90.0, -90.0], [90.0, -90.0], [100.0, 60.0], [-60.0, 90.0]],
                "width": None,
                "height": None,
                "center": None,
            }
        },
    ),
    "small_disks": ("small", {"phases": {0: {"shape": {"kind": "disk"}}}}),
    "small_exact": ("small", {"insertion": {"screening": "exact"}}),
    "dem_small": (
        "dem",
        {"domain": {"width": 300.0, "height": 300.0}, "insertion": {"strip": 300.0}},
    ),
    "dem_tail": (
        "dem",
        {
            "domain": {"width": 300.0, "height": 300.0},
            "insertion": {"strip": 300.0, "closing": "tail"},
        },
    ),
    "table1_3d_small": ("table1-3d", {"domain": {"width": 40.0, "height": 40.0, "depth": 40.0}}),
    "table1_3d_seed2": (
        "table1-3d",
        {"seed": 2, "domain": {"width": 40.0, "height": 40.0, "depth": 40.0}},
    ),
    "table1_3d_periodic": (
        "table1-3d",
        {"domain": {"kind": "periodic-box", "width": 40.0, "height": 40.0, "depth": 40.0}},
    ),
    "table1_3d_spheres": (
        "table1-3d",
        {
            "domain": {"width": 40.0, "height": 40.0, "depth": 40.0},
            "phases": {k: {"shape": {"kind": "sphere"}} for k in range(6)},
        },
    ),
}

EXPORTS_2D = ("csv", "json", "lammps", "gsd", "vtk", "svg")
"""Exporters whose files are fingerprinted for every 2D scene (3D: :data:`EXPORTS_3D`)."""

EXPORTS_3D = {"gsd3d": "gsd", "lammps3d": "lammps", "slice": "slice", "stl": "stl", "vtk3d": "vtk"}
"""Exporters of 3D packings, by the key their files are filed under (the 3D names
that ``vtk``, ``gsd`` and ``lammps`` had when the earlier dumps were made)."""


def _edit(data: Any, edit: Any) -> Any:
    """``data`` with ``edit`` merged in.

    ``None`` removes a key, int keys index lists, and a ``shape`` replaces
    the shape (another plugin has other parameters).
    """
    if not isinstance(edit, dict):
        return edit
    for key, value in edit.items():
        if value is None:
            data.pop(key, None)
        elif isinstance(value, dict) and isinstance(key, int):
            data[key] = _edit(data[key], value)
        elif key == "shape":
            data[key] = value  # another plugin: its own parameters
        elif isinstance(value, dict) and isinstance(data.get(key), dict | list):
            data[key] = _edit(data[key], value)
        else:
            data[key] = value
    return data


def _digest(value: Any) -> str:
    h = hashlib.sha256()
    if isinstance(value, np.ndarray):
        a = np.ascontiguousarray(value)
        h.update(str(a.dtype).encode())
        h.update(str(a.shape).encode())
        if a.dtype.kind == "O":
            h.update(repr(a.tolist()).encode())
        else:
            h.update(a.tobytes())
    else:
        h.update(json.dumps(value, sort_keys=True, default=repr).encode())
    return h.hexdigest()[:16]


ONE_DIMENSION = {2: ("orientation",), 3: ("face_offsets", "rotation")}
"""Arrays of the dump that only packings of one dimension have, by that dimension."""


def _packing_arrays(p: Any) -> dict[str, Any]:
    names = (
        "radius",
        "mineral",
        "vertices",
        "offsets",
        "orientation",
        "centre",
        "insertion_index",
        "rounding",
        "faces",
        "face_offsets",
        "rotation",
    )
    # one packing type holds both dimensions: the other dimension's arrays are
    # empty and left out, as when each dimension had its own type
    other = ONE_DIMENSION[5 - getattr(p, "dimension", 2)]
    out = {}
    for n in names:
        v = getattr(p, n, None)
        if isinstance(v, np.ndarray) and not (n in other and v.size == 0):
            out[n] = v
    return out


def _analysis_arrays(results: Any) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for name, result in results.items():
        for key, value in sorted(vars(result).items()):
            if isinstance(value, np.ndarray) and value.dtype.kind != "O":
                out[f"{name}.{key}"] = value
            elif isinstance(value, dict):
                out[f"{name}.{key}"] = value
            elif isinstance(value, float | int | str):
                out[f"{name}.{key}"] = value
    return out


def _export_digests(p: Any) -> dict[str, str]:
    """One SHA-256 per file that each exporter writes for ``p``."""
    out: dict[str, str] = {}
    kinds = EXPORTS_3D if getattr(p, "dimension", 2) == 3 else {k: k for k in EXPORTS_2D}
    for kind, exporter in kinds.items():
        with tempfile.TemporaryDirectory() as tmp:
            try:
                regopack.export(p, exporter, Path(tmp) / "packing")
            except Exception as exc:  # an export that fails is an entry too
                out[kind] = f"error: {type(exc).__name__}: {exc}"
                continue
            for f in sorted(Path(tmp).rglob("*")):
                if f.is_file():
                    rel = f.relative_to(tmp).as_posix()
                    out[f"{kind}/{rel}"] = _file_digest(f.read_bytes())
    return out


def _without_stats(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _without_stats(v) for k, v in value.items() if k != "stats"}
    if isinstance(value, list):
        return [_without_stats(v) for v in value]
    return value


def _file_digest(data: bytes) -> str:
    """SHA-256 of a file; JSON without the run's ``stats`` (timings differ between runs)."""
    try:
        value = json.loads(data)
    except (UnicodeDecodeError, ValueError):
        return hashlib.sha256(data).hexdigest()[:16]
    return _digest(_without_stats(value))


def dump(names: list[str]) -> dict[str, str]:
    """Fingerprint every scene of ``names`` and its analyses."""
    entries: dict[str, str] = {}
    for label in names:
        base, edit = SCENES[label]
        data = _edit(regopack.scene(base).to_dict(), copy.deepcopy(edit))
        p = regopack.pack(data)
        for key, value in _packing_arrays(p).items():
            entries[f"{label}/{key}"] = _digest(value)
        try:
            results = regopack.analyze(p)
        except Exception as exc:  # an analysis that fails is an entry too
            entries[f"{label}/analyze"] = f"error: {type(exc).__name__}: {exc}"
        else:
            for key, value in _analysis_arrays(results).items():
                entries[f"{label}/analysis/{key}"] = _digest(value)
        for key, value in _export_digests(p).items():
            entries[f"{label}/export/{key}"] = value
        print(f"{label}: {p.n_placed} placed", file=sys.stderr, flush=True)
    return entries


def main() -> int:
    """Dump the fingerprints; compare with an earlier dump if asked."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--compare", type=Path)
    parser.add_argument("--only", nargs="*", choices=sorted(SCENES), default=sorted(SCENES))
    args = parser.parse_args()
    entries = dump(args.only)
    args.out.write_text(json.dumps(entries, indent=1, sort_keys=True) + "\n")
    if args.compare is None:
        return 0
    before = json.loads(args.compare.read_text())
    keys = sorted(set(before) | set(entries))
    differ = [k for k in keys if before.get(k) != entries.get(k)]
    for k in differ:
        print(f"differs: {k}: {before.get(k)} -> {entries.get(k)}")
    same = len(keys) - len(differ)
    print(f"{same}/{len(keys)} identical")
    return 1 if differ else 0


if __name__ == "__main__":
    raise SystemExit(main())
