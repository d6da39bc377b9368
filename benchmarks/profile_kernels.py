"""Name the compiled kernels for ``perf``: a `dem` run that leaves a perf map behind.

``perf`` sees numba's compiled code as anonymous memory. This script keeps
the object code of every library numba compiles or loads from its cache,
runs the scene, and then writes ``/tmp/perf-<pid>.map`` with each function's
address, size and a short name (``module.function#hash``, the hash telling
specialisations apart; numba's reference-count helpers as ``NRT_*``). It
prints the insertion's window on the monotonic clock, so that the report can
leave out the imports and the set-up. Run from the repository root:

    perf record -k CLOCK_MONOTONIC -F 1999 -o kernels.data \\
        python benchmarks/profile_kernels.py --size 3200
    perf report -i kernels.data --time <window> --sort pid,sym --stdio

(The first run after a change compiles the kernels inside the window: run
it twice.) It reads numba's private code-library attributes (checked with
numba 0.68); a version that moves them names fewer functions.
"""

from __future__ import annotations

import argparse
import os
import struct
import sys
import time
import zlib
from typing import Any

_OBJECTS: dict[int, tuple[Any, bytes]] = {}


def keep_object_code() -> None:
    """Record each code library's object code as numba compiles or loads it."""
    from numba.core import codegen

    cls: Any = codegen.JITCodeLibrary
    loaded = cls._set_compiled_object
    compiled = cls._object_compiled_hook.__func__

    def on_load(self: Any, value: bytes) -> None:
        _OBJECTS[id(self)] = (self, value)
        loaded(self, value)

    def on_compile(owner: Any, ll_module: Any, buf: bytes) -> None:
        library = getattr(ll_module, "_CPUCodeLibrary__library", None)
        if library is not None:
            _OBJECTS[id(library)] = (library, buf)
        compiled(owner, ll_module, buf)

    cls._set_compiled_object = on_load
    cls._object_compiled_hook = classmethod(on_compile)


def _functions(obj: bytes) -> list[tuple[str, int, int, int, int]]:
    """``(name, section, offset, size, binding)`` of the functions of an ELF64 object."""
    shoff = struct.unpack_from("<Q", obj, 0x28)[0]
    entsize, count = struct.unpack_from("<HH", obj, 0x3A)
    sections = [struct.unpack_from("<IIQQQQIIQQ", obj, shoff + j * entsize) for j in range(count)]
    out = []
    for _, kind, _, _, offset, size, link, _, _, symsize in sections:
        if kind != 2:  # a symbol table
            continue
        strings = sections[link][4]
        for e in range(size // symsize):
            name, info, _, shndx, value, length = struct.unpack_from(
                "<IBBHQQ", obj, offset + e * symsize
            )
            if info & 0xF == 2:  # a function
                start = strings + name
                text = obj[start : obj.index(b"\0", start)].decode()
                out.append((text, shndx, value, length, info >> 4))
    return out


def short_name(mangled: str) -> str:
    """``module.function#hash`` of a numba symbol (``cpython.``/``cfunc.`` for wrappers)."""
    prefix = ""
    rest = mangled
    if rest.startswith("cfunc."):
        prefix, rest = "cfunc.", rest[6:]
    rest = rest.removeprefix("_ZN")
    if rest.startswith("7cpython"):
        prefix, rest = prefix + "cpython.", rest[8:]
    parts = []
    while rest[:1].isdigit():
        digits = len(rest) - len(rest.lstrip("0123456789"))
        n = int(rest[:digits])
        parts.append(rest[digits : digits + n])
        rest = rest[digits + n :]
    base = ".".join(parts[-2:]) if parts else mangled[:40]
    return f"{prefix}{base}#{zlib.crc32(mangled.encode()) % 10000}"


def write_map() -> int:
    """Write ``/tmp/perf-<pid>.map`` for the kept object code; return the entries written."""
    lines = []
    for library, obj in _OBJECTS.values():
        functions = _functions(obj)
        try:
            engine = library._codegen._engine
        except ReferenceError:  # a compiled library held by a weak proxy, since freed
            continue
        base: dict[int, int] = {}
        for name, section, value, _, binding in functions:
            if binding == 1 and section not in base:  # a global: the engine knows it
                address = engine.get_function_address(name)
                if address:
                    base[section] = address - value
        for name, section, value, size, _ in functions:
            if section in base and size:
                lines.append(f"{base[section] + value:x} {size:x} {short_name(name)}")
    from numba.core.runtime import nrt

    for name in ("NRT_incref", "NRT_decref"):  # called by every library, defined in one
        address = nrt.rtsys.library.get_pointer_to_function(name)
        if address and not any(line.startswith(f"{address:x} ") for line in lines):
            lines.append(f"{address:x} 10 {name}")
    with open(f"/tmp/perf-{os.getpid()}.map", "w") as out:
        out.write("\n".join(lines) + "\n")
    return len(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="dem")
    parser.add_argument("--size", type=float, default=1600.0)
    parser.add_argument("--set", action="append", default=[], dest="overrides")
    args = parser.parse_args()
    keep_object_code()
    import regopack
    from regopack.plugins.inserters import available_arc

    settings: dict[str, Any] = {
        "insertion.closing": "tail",
        "insertion.strip": 800.0,
        "domain.width": args.size,
        "domain.height": args.size,
    }
    from regopack.base.errors import RegopackError
    from regopack.registry.manager import default_registry
    from regopack.scenes.model import _parse_override, load_scene, resolve_scene

    fixed = ['insertion.closing="tail"', "insertion.strip=800"]
    sized = [f"domain.width={args.size}", f"domain.height={args.size}"]
    try:  # regopack's own reading of --set, and its one line on a mistake
        scene = load_scene(args.scene, [*fixed, *args.overrides, *sized])
        resolve_scene(scene, default_registry())
    except RegopackError as exc:
        parser.error(str(exc))
    settings.update(_parse_override(item) for item in args.overrides)
    run = available_arc._run_sweep
    windows: list[tuple[float, float]] = []

    def timed(*a: Any, **k: Any) -> int:
        start = time.clock_gettime(time.CLOCK_MONOTONIC)
        placed = run(*a, **k)
        windows.append((start, time.clock_gettime(time.CLOCK_MONOTONIC)))
        return placed

    available_arc._run_sweep = timed  # type: ignore[assignment]
    packing = regopack.pack(args.scene, **settings)
    print(
        f"placed {packing.n_placed}, insertion {packing.stats['insert_time_s']:.3f} s, "
        f"analyses {packing.stats.get('candidate_analyses')}"
    )
    if windows:  # the last sweep is the packing's own (a pilot runs before it)
        print(f"window {windows[-1][0]:.6f},{windows[-1][1]:.6f}")
    print(f"perf map: {write_map()} functions in /tmp/perf-{os.getpid()}.map", file=sys.stderr)


if __name__ == "__main__":
    main()
