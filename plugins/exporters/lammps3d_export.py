"""LAMMPS export of 3D packings: rounded-polyhedron bodies and an input script that runs them.

Every placed polyhedron becomes one body of LAMMPS' ``atom_style body
rounded/polyhedron``: a convex core (vertices, edges and faces) and a rounding
radius ``r``, the body being every point within ``r`` of the core. LAMMPS
computes contacts between these rounded surfaces, so a body needs ``r > 0``.
The core is the particle eroded by ``r`` (every face plane moved inward by
``r``, :func:`~regopack.plugins.exporters.rounded_polyhedra.erode_polyhedron`), so the
body fills the particle but for its rounded edges and corners and never
reaches past it: neighbours that touch in the packing touch, without
overlap, in LAMMPS.

``r`` is ``rounding_fraction`` × the particle's equivalent radius (5 % by
default), or ``rounding_radius``; a particle whose core would vanish or
break up gets ``r`` halved (up to 8 times). The body carries the mass,
centre of mass and inertia of the particle itself (the sharp polyhedron):
the rounding shapes the contacts, not the grain. A sphere is one vertex
rounded by its own radius (``N E F = 1 0 0``: LAMMPS reads no edges or faces
for it, and a face count above 0 would make it copy values past the body's
storage).

Beside ``<stem>.data`` the exporter writes ``<stem>.in``, which reads it with
the pair style ``body/rounded/polyhedron``, walls ``wall/body/polyhedron`` on
the six sides of a walled box (or periodic boundaries), gravity along -z and
a time step from the lightest body's mass and the stiffness, its parameters
as LAMMPS ``index`` variables.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.base.errors import ExportError
from regopack.base.units import length_unit
from regopack.geometry.domain import Box
from regopack.packing.core import Packing
from regopack.plugins.exporters.export_common import _num, _write_text
from regopack.plugins.exporters.lammps_export import default_length_scale
from regopack.plugins.exporters.rounded_polyhedra import Core, erode_polyhedron
from regopack.plugins.exporters.solid_export_common import mass_properties, placed_solids
from regopack.registry.interfaces import Analyzer, SolidExporter

__all__ = [
    "Lammps3dBodies",
    "Lammps3dConfig",
    "Lammps3dExporter",
    "body_faces",
    "lammps3d_bodies",
    "script3d_path",
]

FloatArray = NDArray[np.float64]

STEPS_PER_COLLISION = 50
"""Time steps per duration of a collision of the two lightest bodies (sets the time step)."""

ROUNDING_TRIES = 8
"""Times the rounding radius of one body is halved when its eroded core vanishes."""

LINE_CHARS = 200
"""Longest line of a body's values: LAMMPS reads a body's values over as many
lines as it likes, but a long line is cut (and its numbers with it) and a body
may span at most 32 lines, so the values are packed into lines of this length."""

MAX_BODY_LINES = 32
"""Lines LAMMPS' read_data accepts for one body."""


class Lammps3dConfig(BaseModel):
    """Parameters of the ``lammps3d`` exporter.

    Lengths of the packing are multiplied by ``length_scale`` and written in
    the length unit of ``units``; by default ``length_scale`` converts the
    scene's ``length_unit`` to that unit (1 for micrometres and ``units =
    "micro"``). With the default ``units = "micro"``, masses are in
    picograms, times in microseconds and forces in nanonewtons.
    """

    model_config = ConfigDict(extra="forbid", strict=True)

    units: Literal["micro", "si", "cgs", "nano", "lj"] = Field(
        "micro", description="LAMMPS unit style named in the input script."
    )
    length_scale: float | None = Field(
        None,
        gt=0,
        allow_inf_nan=False,
        description=(
            "Factor from the packing's length unit to the length unit of `units`; default: "
            "from the scene's length_unit (1 for 'µm' and units 'micro'; 1 for units 'lj')."
        ),
    )
    density: float = Field(
        3.1,
        gt=0,
        allow_inf_nan=False,
        description="Mass per unit volume of the grains (3.1 g/cm³ = 3.1 pg/µm³ in units micro).",
    )
    rounding_fraction: float = Field(
        0.05,
        gt=0,
        le=0.5,
        description="Rounding radius of a body as a fraction of the particle's equivalent radius.",
    )
    rounding_radius: float = Field(
        0.0,
        ge=0,
        allow_inf_nan=False,
        description=(
            "One rounding radius for every body, in the packing's length unit; "
            "0 uses `rounding_fraction`."
        ),
    )
    stiffness: float = Field(
        1.0e4,
        gt=0,
        allow_inf_nan=False,
        description="Normal contact stiffness k_n of the pair style and walls (force/length).",
    )
    restitution: float = Field(
        0.5,
        gt=0,
        le=1,
        description=(
            "Normal coefficient of restitution of a collision of the two lightest bodies; "
            "sets the damping c_n."
        ),
    )
    friction: float = Field(0.5, ge=0, allow_inf_nan=False, description="Friction coefficient mu.")
    gravity: float = Field(
        0.0,
        ge=0,
        allow_inf_nan=False,
        description="Acceleration of gravity along -z in the input script (0: none).",
    )
    steps: int = Field(10000, ge=0, description="Time steps the input script runs.")


@dataclass(frozen=True)
class Lammps3dBodies:
    """The bodies of a 3D LAMMPS export, in the packing's length unit and unit density.

    Attributes
    ----------
    index
        Draw index of the particle of each body.
    cores
        Core of each body, its vertices relative to the body's centre of mass.
    rounding
        Rounding radius of each body.
    position
        Centre of mass of each body (the particle's centroid).
    volume
        Volume of each particle.
    inertia
        ``(n, 3, 3)`` inertia tensor of each particle about its centre of mass
        (unit density).
    reduced
        Number of bodies whose rounding radius was halved to keep a core.
    """

    index: NDArray[np.int64]
    cores: list[Core]
    rounding: FloatArray
    position: FloatArray
    volume: FloatArray
    inertia: FloatArray
    reduced: int


def lammps3d_bodies(packing: Packing[Box], config: Lammps3dConfig | None = None) -> Lammps3dBodies:
    """Cores, rounding radii, centres of mass and inertia of the placed polyhedra.

    Raises
    ------
    ExportError
        One line, for a particle too thin to carry a rounded body.
    """
    cfg = config or Lammps3dConfig()
    solids = placed_solids(packing, "lammps3d", spheres=True)
    fo = packing.face_offsets
    cores, rounding, position, volume, inertia = [], [], [], [], []
    reduced = 0
    for s in solids:
        j = s.index
        if s.rounding > 0:  # a sphere: one vertex rounded by its own radius
            rho = s.rounding
            v = 4.0 / 3.0 * np.pi * rho**3
            cores.append(Core(np.zeros((1, 3)), [], np.zeros((0, 2), dtype=np.int64)))
            rounding.append(rho)
            position.append(s.centre.copy())
            volume.append(v)
            inertia.append(np.eye(3) * 0.4 * v * rho * rho)
            continue
        v, c, moments = mass_properties(s.local, s.loops)
        normals = packing.normals[fo[j] : fo[j + 1]]
        support = packing.support[fo[j] : fo[j + 1]]
        r = cfg.rounding_radius or cfg.rounding_fraction * float(packing.radius[j])
        core = None
        for attempt in range(ROUNDING_TRIES):
            core = erode_polyhedron(normals, support, r)
            if core is not None:
                reduced += attempt > 0
                break
            r *= 0.5
        if core is None:
            raise ExportError(f"particle {j}: it is too thin to carry a rounded body")
        cores.append(Core(core.vertices - c, core.loops, core.edges))
        rounding.append(r)
        position.append(s.centre + c)
        volume.append(v)
        inertia.append(np.trace(moments) * np.eye(3) - moments)
    n = len(solids)
    return Lammps3dBodies(
        index=np.array([s.index for s in solids], dtype=np.int64),
        cores=cores,
        rounding=np.array(rounding, dtype=np.float64),
        position=np.array(position, dtype=np.float64).reshape(n, 3),
        volume=np.array(volume, dtype=np.float64),
        inertia=np.array(inertia, dtype=np.float64).reshape(n, 3, 3),
        reduced=reduced,
    )


def body_faces(core: Core) -> NDArray[np.int64]:
    """``(F, 4)`` faces as LAMMPS reads them: quadrilaterals, and triangles ending in -1.

    A face of more than four vertices is split into a fan of quadrilaterals
    from its first vertex (and a last triangle when its count is odd), in its
    turning sense, so every piece is planar, convex and outward. Fewer pieces
    mean fewer vertex-face tests in LAMMPS' contact search.

    Examples
    --------
    >>> core = Core(np.zeros((7, 3)), [np.array([0, 1, 2, 3, 4, 5, 6]), np.array([0, 1, 2])],
    ...             np.zeros((0, 2), dtype=np.int64))
    >>> body_faces(core).tolist()
    [[0, 1, 2, 3], [0, 3, 4, 5], [0, 5, 6, -1], [0, 1, 2, -1]]
    """
    rows: list[list[int]] = []
    for loop in core.loops:
        ids = [int(i) for i in loop]
        k = 1
        while len(ids) - k >= 3:  # a quadrilateral (v0, v_k, v_k+1, v_k+2)
            rows.append([ids[0], ids[k], ids[k + 1], ids[k + 2]])
            k += 2
        if len(ids) - k == 2:  # a last triangle (v0, v_k, v_k+1)
            rows.append([ids[0], ids[k], ids[k + 1], -1])
    return np.array(rows, dtype=np.int64).reshape(-1, 4)


def script3d_path(path: Path) -> Path:
    """Return the input script written beside the data file ``path``: ``<stem>.in``."""
    return Path(path).with_suffix(".in")


def _lines(values: list[str]) -> list[str]:
    """Pack ``values`` into lines of at most :data:`LINE_CHARS` characters."""
    lines: list[str] = []
    line = ""
    for v in values:
        if line and len(line) + 1 + len(v) > LINE_CHARS:
            lines.append(line)
            line = v
        else:
            line = f"{line} {v}" if line else v
    if line:
        lines.append(line)
    return lines


class Lammps3dExporter(SolidExporter):
    """LAMMPS data file (``atom_style body rounded/polyhedron``) and its input script.

    One body per placed particle, in draw order: atom type = mineral index + 1,
    mass = volume × ``density``, position = its centre of mass. In the
    ``Bodies`` section each body lists ``N E F``, the six components of its
    inertia tensor in the box frame (``ixx iyy izz ixy ixz iyz``), its core
    vertices relative to the centre of mass, its edges, its faces (four
    indices, -1 ending a triangle) and its rounding *diameter*.
    """

    suffix = ".data"

    def __init__(self, config: Lammps3dConfig | None = None) -> None:
        self.config = config or Lammps3dConfig()

    def companions(self, path: Path) -> tuple[Path, ...]:
        """Return the input script written beside the data file."""
        return (script3d_path(path),)

    def export(
        self, packing: Packing[Box], path: Path, *, analyses: Mapping[str, Analyzer] | None = None
    ) -> Path:
        """Write the data file and the input script; return the data file's path."""
        cfg = self.config
        path = Path(path)
        bodies = lammps3d_bodies(packing, cfg)
        s = (
            default_length_scale(packing, cfg.units)
            if cfg.length_scale is None
            else cfg.length_scale
        )
        with np.errstate(over="ignore", under="ignore"):  # checked below
            mass = bodies.volume * (np.float64(s) ** 3 * cfg.density)
            inertia = bodies.inertia * (np.float64(s) ** 5 * cfg.density)
        n = bodies.index.size
        tiny = np.finfo(np.float64).tiny
        diagonal = inertia[:, [0, 1, 2], [0, 1, 2]]
        for what, checked in (("mass", mass), ("moment of inertia", diagonal)):
            if n and not (np.isfinite(checked).all() and (checked >= tiny).all()):
                raise ExportError(
                    f"length_scale = {s}, density = {cfg.density}: a body's {what} is not a "
                    "positive finite number; give values nearer 1"
                )
        # LAMMPS sizes every body's storage from Nmax as if it had Nmax vertices,
        # edges and faces: Nmax is the largest of the three counts of any body
        counts = [c.vertices.shape[0] for c in bodies.cores]
        sizes = [
            max(c.vertices.shape[0], c.edges.shape[0], body_faces(c).shape[0]) for c in bodies.cores
        ]
        n_min, n_max = (min(counts), max(sizes)) if counts else (1, 1)
        n_types = max(1, len(packing.mineral_names), int(packing.mineral.max(initial=-1)) + 1)
        box = packing.domain
        lo, hi = box.bounds().reshape(3, 2).T * s
        pos = bodies.position * s
        if box.periodic:
            pos = lo + np.mod(pos - lo, hi - lo)
        atoms: list[str] = []
        blocks: list[str] = []
        for k in range(n):
            j = int(bodies.index[k])
            core = bodies.cores[k]
            faces = body_faces(core)
            nv, ne, nf = core.vertices.shape[0], core.edges.shape[0], faces.shape[0]
            atoms.append(
                f"{k + 1} {int(packing.mineral[j]) + 1} 1 {_num(mass[k])} "
                + " ".join(_num(x) for x in pos[k])
            )
            t = inertia[k]
            values = [_num(v) for v in (t[0, 0], t[1, 1], t[2, 2], t[0, 1], t[0, 2], t[1, 2])]
            values += [_num(x) for x in (core.vertices * s).ravel()]
            values += [str(int(i)) for i in core.edges.ravel()]
            values += [str(int(i)) for i in faces.ravel()]
            values.append(_num(2.0 * bodies.rounding[k] * s))
            blocks.append(f"{k + 1} 3 {len(values)}")
            blocks.append(f"{nv} {ne} {nf}")
            blocks += _lines(values)
        rounding_note = (
            f"rounding radius {_num(cfg.rounding_radius)}"
            if cfg.rounding_radius
            else f"rounding radius {cfg.rounding_fraction} x equivalent radius"
        )
        r_all = bodies.rounding * s
        walls = "periodic in x, y and z" if box.periodic else "walls on all six sides"
        lines = [
            f"LAMMPS data file from regopack {packing.version}: scene "
            f"{packing.scene.get('name', '?')}, seed {packing.seed}, "
            f"atom_style body rounded/polyhedron {n_min} {n_max}",
            "",
            f"# polyhedron bodies: particle eroded by the {rounding_note}; the Bodies section "
            "ends each body with its rounding diameter",
            f"# rounding radii from {_num(r_all.min() if n else 0.0)} to "
            f"{_num(r_all.max() if n else 0.0)}; {bodies.reduced} bodies with a halved radius",
            f"# lengths = packing lengths ({length_unit(packing)}) x {_num(s)}; "
            "mass = particle volume x "
            f"{_num(cfg.density)}; {walls}",
            "",
            f"{n} atoms",
            f"{n} bodies",
            f"{n_types} atom types",
            "",
            f"{_num(lo[0])} {_num(hi[0])} xlo xhi",
            f"{_num(lo[1])} {_num(hi[1])} ylo yhi",
            f"{_num(lo[2])} {_num(hi[2])} zlo zhi",
            "",
            "Atoms # body",
            "",
            *atoms,
            "",
            "Bodies",
            "",
            *blocks,
        ]
        m_min = float(mass.min()) if n else 1.0
        d_min = float(2.0 * packing.radius[bodies.index].min() * s) if n else 1.0
        r_min = float(r_all.min()) if n else 0.05 * d_min
        script = self._script(packing, path, lo, hi, n_min, n_max, m_min, d_min, r_min)
        _write_text(path, "\n".join(lines) + "\n")
        _write_text(script3d_path(path), script)
        return path

    def _script(
        self,
        packing: Packing[Box],
        path: Path,
        lo: FloatArray,
        hi: FloatArray,
        n_min: int,
        n_max: int,
        m_min: float,
        d_min: float,
        r_min: float,
    ) -> str:
        cfg = self.config
        periodic = packing.domain.periodic
        walls = (
            []
            if periodic
            else [
                f"fix          wall{i + 1} all wall/body/polyhedron ${{k_n}} ${{c_n}} ${{c_t}} "
                f"{axis}plane {_num(lo[i])} {_num(hi[i])}"
                for i, axis in enumerate("xyz")
            ]
        )
        return "\n".join(
            [
                f"# LAMMPS input for {path.name}, written by regopack {packing.version} "
                f"(scene {packing.scene.get('name', '?')}, seed {packing.seed}).",
                f"# Run it in this folder: lmp -in {script3d_path(path).name}",
                "# Change a parameter with -var, e.g. -var k_n 1e5 -var steps 50000.",
                "",
                f"variable steps index {cfg.steps}",
                f"variable k_n   index {_num(cfg.stiffness)}   # normal stiffness (force/length)",
                f"variable e_n   index {_num(cfg.restitution)}   "
                "# restitution of two lightest bodies",
                f"variable mu    index {_num(cfg.friction)}   # friction coefficient",
                f"variable g     index {_num(cfg.gravity)}   # gravity along -z (acceleration)",
                f"variable m_min equal {_num(m_min)}   # mass of the lightest body",
                "variable zeta  equal -ln(v_e_n)/sqrt(PI^2+ln(v_e_n)^2)",
                "variable c_n   equal 2*v_zeta*sqrt(0.5*v_m_min*v_k_n)   # normal damping",
                "variable c_t   equal 0.5*v_c_n   # tangential damping",
                f"variable dt    equal PI*sqrt(0.5*v_m_min/v_k_n)/{STEPS_PER_COLLISION}",
                f"variable skin  equal {_num(0.1 * d_min)}",
                f"variable cut   equal {_num(0.5 * r_min)}",
                "",
                f"units        {cfg.units}",
                "dimension    3",
                f"boundary     {'p p p' if periodic else 'f f f'}",
                "newton       on",
                f"atom_style   body rounded/polyhedron {n_min} {n_max}",
                "atom_modify  map array",
                f"read_data    {path.name}",
                "",
                "pair_style   body/rounded/polyhedron ${c_n} ${c_t} ${mu} 1.0 ${cut}",
                "pair_coeff   * * ${k_n} 0.0",
                "comm_modify  vel yes",
                "neighbor     ${skin} bin",
                "neigh_modify every 1 delay 0 check yes",
                "timestep     ${dt}",
                "",
                "fix          integrate all nve/body",
                *walls,
                "fix          weight all gravity ${g} vector 0 0 -1",
                "",
                "thermo_style custom step atoms ke pe",
                "thermo       1000",
                "run          ${steps}",
                "",
            ]
        )
