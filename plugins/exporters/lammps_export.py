"""LAMMPS export: a data file of rounded bodies and an input script that runs it.

Every placed particle becomes one body of LAMMPS' ``atom_style body
rounded/polygon`` (2D packings) or ``rounded/polyhedron`` (3D): a convex core
and a rounding radius ``r``, the body being the points within ``r`` of the
core. LAMMPS computes contacts between these rounded surfaces. The core is
the particle eroded by ``r``, so the body fills the particle but for its
rounded corners (and edges) and never reaches past it: neighbours that touch
in the packing touch, without overlap, in LAMMPS.

- *Polygons*: the outline, cleaned of repeated and collinear vertices
  (:func:`~regopack.plugins.exporters.rounded_bodies.clean_outline`), is
  eroded by ``r`` (:func:`~regopack.plugins.exporters.rounded_bodies.erode_convex`).
  A disk is one vertex with its own radius; a rounded polygon keeps its core
  and radius. The body's mass and moments are those of the rounded body.
- *Polyhedra*: every face plane moves inward by ``r``
  (:func:`~regopack.plugins.exporters.rounded_polyhedra.erode_polyhedron`).
  The body carries the mass, centre of mass and inertia of the particle itself
  (the sharp polyhedron): the rounding shapes the contacts, not the grain. A
  sphere is one vertex rounded by its own radius (``N E F = 1 0 0``: LAMMPS
  reads no edges or faces for it, and a face count above 0 would make it
  copy values past the body's storage).

``r`` is ``rounding_fraction`` × the particle's equivalent radius (5 % by
default), or ``rounding_radius``; a particle whose core would vanish (or, in
3D, break up) gets ``r`` halved (up to 8 times).

Beside ``<stem>.data`` the exporter writes ``<stem>.in``, an input script that
reads it with the pair style ``body/rounded/polygon`` (``polyhedron``), walls
(``wall/body/polygon``, ``wall/body/polyhedron``) or periodic boundaries from
the domain (in a walled cylinder: ``zplane`` walls for the floor and lid and a
ring of fixed plate bodies for the side wall, see
:mod:`~regopack.plugins.exporters.lammps_side_wall`), gravity along -y (-z in
3D), a time step from the lightest body's
mass and the stiffness (t_c / 50 of a collision of the two lightest bodies
in 2D, t_c / 20 in 3D: see :data:`STEPS_PER_COLLISION`), and its parameters
as LAMMPS ``index`` variables (``lmp -in packing.in -var k_n 1e5`` changes
one).

**Packings of spheres** (3D packings whose particles are all spheres) are
written, by default, as LAMMPS *granular* spheres rather than bodies:
``atom_style sphere`` (each atom's diameter and density), ``pair_style
granular`` with Hertz contacts from Young's modulus and Poisson's ratio
(``hertz/material``), a restitution coefficient (``damping
coeff_restitution``), Mindlin friction (``tangential mindlin``),
``fix nve/sphere``, ``fix wall/gran`` walls of the same contact model on the
six faces of a walled box (periodic boundaries for a periodic box), and a
time step of :data:`RAYLEIGH_FRACTION` of the Rayleigh time of the sphere
whose Rayleigh time is shortest. LAMMPS' granular pair styles are made for
spheres, with Hertz-Mindlin contacts and history; a one-vertex body has the
linear spring and dashpot of the body pair style only. ``spheres = "bodies"``
writes them as one-vertex bodies, as before; a packing that mixes spheres
and polyhedra is always written as bodies.

**Densities.** Every grain has ``density``, or the density of its mineral in
``mineral_density`` (by mineral name); in the bodies it sets the mass and
the inertia, for granular spheres the atoms' density column.

**The final state.** After its run, the script writes
``<stem>.final.dump`` (:func:`dump_path`): each body's displacement and its
orientation at the start and at the end, or each granular sphere's centre;
:meth:`LammpsExporter.read_state` (``regopack settled``) reads it back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack._compat import renamed_names
from regopack.base.errors import ConfigError, ExportError
from regopack.base.units import length_scale, length_unit
from regopack.geometry.domain import Box, Cylinder, PeriodicRectangle, Rectangle
from regopack.packing.core import Packing
from regopack.plugins.exporters.body_dump import read_body_dump
from regopack.plugins.exporters.export_common import (
    Analyses,
    AnyPacking,
    _num,
    _write_text,
    scene_label,
)
from regopack.plugins.exporters.granular_common import RAYLEIGH_FRACTION as RAYLEIGH_FRACTION
from regopack.plugins.exporters.granular_common import UNIT_STYLE_LENGTH as UNIT_STYLE_LENGTH
from regopack.plugins.exporters.granular_common import GranularSpheres as GranularSpheres
from regopack.plugins.exporters.granular_common import check_finite as _check_finite
from regopack.plugins.exporters.granular_common import default_length_scale as default_length_scale
from regopack.plugins.exporters.granular_common import density_note as _density_note
from regopack.plugins.exporters.granular_common import granular_spheres as granular_spheres
from regopack.plugins.exporters.granular_common import (
    material_variable_lines,
    rayleigh_step_lines,
    read_sphere_dump,
    sphere_data,
)
from regopack.plugins.exporters.granular_common import mineral_densities as mineral_densities
from regopack.plugins.exporters.lammps_side_wall import CORNER_GAP, SideWall, side_wall
from regopack.plugins.exporters.rounded_bodies import (
    CLEAN_TOLERANCE,
    clean_outline,
    erode_convex,
    rounded_moments,
)
from regopack.plugins.exporters.rounded_bodies_kernel import rounded_bodies
from regopack.plugins.exporters.rounded_polyhedra import Core, erode_polyhedron
from regopack.plugins.exporters.solid_export_common import mass_properties, placed_solids
from regopack.registry.interfaces import Exporter
from regopack.registry.plugin_types import misplaced_field

__all__ = [
    "GranularSpheres",
    "LammpsBodies",
    "LammpsConfig",
    "LammpsExporter",
    "PolyhedronBodies",
    "body_faces",
    "dump_path",
    "granular_spheres",
    "lammps_bodies",
    "mineral_densities",
    "polyhedron_bodies",
    "reference_body",
    "script_path",
]

FloatArray = NDArray[np.float64]

STEPS_PER_COLLISION = {2: 50, 3: 20}
"""Time steps per duration of a collision of the two lightest bodies (sets the time step), by
dimension. Settling polyhedra lost a body at 2.5 steps a collision and held at 5 (measured),
so 20 keeps a margin of 4 to 8; a step of a polyhedron costs hundreds of times one of a
polygon, whose scripts keep 50."""

MAX_BODY_LINES = 32
"""Lines LAMMPS' read_data accepts for one body (its MAXBODY); long cores share lines."""

LINE_CHARS = 200
"""Longest line of a polyhedron body's values: LAMMPS reads a body's values over
as many lines as it likes, but a long line is cut (and its numbers with it) and
a body may span at most :data:`MAX_BODY_LINES` lines, so the values are packed
into lines of this length."""

ROUNDING_TRIES = 8
"""Times the rounding radius of one body is halved when its eroded core vanishes."""


class LammpsConfig(BaseModel):
    """Parameters of the LAMMPS exporter (``thickness`` is for 2D packings only).

    Lengths of the packing are multiplied by ``length_scale`` and written in
    the length unit of ``units``; every other quantity is in that unit system.
    By default ``length_scale`` converts the scene's ``length_unit`` to the
    length unit of ``units`` (1 for micrometres and ``units = "micro"``).
    With the default ``units = "micro"``, masses are in picograms, times in
    microseconds and forces in nanonewtons, and a ``density`` of 3.1 pg/µm³
    is 3.1 g/cm³.
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
    thickness: float | None = Field(
        None,
        gt=0,
        allow_inf_nan=False,
        json_schema_extra={"dimensions": [2]},
        description=(
            "2D packings only: out-of-plane thickness of every body in the packing's length "
            "unit; a body's mass is its area × thickness × density. Default: d_min / 2 "
            "(1 at the built-in scenes' d_min = 2)."
        ),
    )
    rounding_fraction: float = Field(
        0.05,
        gt=0,
        le=0.5,
        description=(
            "Rounding radius of a body as a fraction of the particle's equivalent "
            "radius (disks, rounded polygons and spheres keep their own)."
        ),
    )
    rounding_radius: float = Field(
        0.0,
        ge=0,
        allow_inf_nan=False,
        description=(
            "One rounding radius for every body but disks, rounded polygons and spheres, "
            "in the packing's length unit; 0 uses `rounding_fraction`."
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
        description=(
            "Acceleration of gravity along -y (2D) or -z (3D) in the input script (0: none)."
        ),
    )
    steps: int = Field(10000, ge=0, description="Time steps the input script runs.")
    mineral_density: dict[str, Annotated[float, Field(gt=0, allow_inf_nan=False)]] = Field(
        default_factory=dict,
        description=(
            "Density of the grains of a mineral, by mineral name; minerals not listed get "
            "`density`."
        ),
    )
    spheres: Literal["granular", "bodies"] = Field(
        "granular",
        json_schema_extra={"dimensions": [3]},
        description=(
            "3D packings of spheres only: 'granular' writes granular spheres (atom_style "
            "sphere, pair_style granular, Hertz contacts); 'bodies' writes one-vertex "
            "rounded/polyhedron bodies, as for polyhedra."
        ),
    )
    youngs_modulus: float = Field(
        1.0e5,
        gt=0,
        allow_inf_nan=False,
        json_schema_extra={"dimensions": [3]},
        description=(
            "Granular spheres only: Young's modulus E of the Hertz contacts (pressure; 1e5 = "
            "0.1 GPa in units micro, a softened grain: 7e7 is basalt's 70 GPa)."
        ),
    )
    poisson_ratio: float = Field(
        0.25,
        gt=0,
        lt=0.5,
        json_schema_extra={"dimensions": [3]},
        description="Granular spheres only: Poisson's ratio of the grains.",
    )


@dataclass(frozen=True)
class LammpsBodies:
    """The bodies of a LAMMPS export, before they are written.

    Attributes
    ----------
    index
        Draw index of the particle of each body.
    core
        Core vertices of each body relative to its centre of mass, in the
        packing's length unit.
    rounding
        Rounding radius of each body.
    position
        Centre of mass of each body.
    area, ixx, iyy, ixy
        Area and second moments (``∫y²``, ``∫x²``, ``∫xy`` per unit area
        density) of each rounded body about its centre of mass.
    reduced
        Number of bodies whose rounding radius was halved to keep a core.
    """

    index: NDArray[np.int64]
    core: list[FloatArray]
    rounding: FloatArray
    position: FloatArray
    area: FloatArray
    ixx: FloatArray
    iyy: FloatArray
    ixy: FloatArray
    reduced: int


def _body_core(local: FloatArray, rho: float, r: float) -> tuple[FloatArray, float, bool]:
    """Core and rounding radius of one particle (``rho`` its own rounding, ``r`` the target)."""
    if rho > 0:  # a disk or a rounded polygon: its own core and radius
        return (local[:1] if local.shape[0] == 1 else clean_outline(local)), rho, False
    outline = clean_outline(local)
    if outline.shape[0] < 3:
        raise ExportError("its outline has fewer than 3 distinct vertices")
    for attempt in range(ROUNDING_TRIES):
        core = erode_convex(outline, r)
        if core.shape[0] >= 3:
            return core, r, attempt > 0
        r *= 0.5
    raise ExportError("it is too thin to carry a rounded body")


def lammps_bodies(packing: Packing, config: LammpsConfig | None = None) -> LammpsBodies:
    """Cores, rounding radii, centres of mass and moments of the placed particles.

    The compiled :func:`~regopack.plugins.exporters.rounded_bodies_kernel.rounded_bodies`
    does the work, with the rules of :func:`reference_body`.

    Raises
    ------
    ExportError
        One line, if a particle has no proper outline.
    """
    cfg = config or LammpsConfig()
    idx = np.flatnonzero(packing.placed).astype(np.int64)
    own = packing.rounding_radius[idx]
    target = (
        np.full(idx.size, cfg.rounding_radius)
        if cfg.rounding_radius
        else cfg.rounding_fraction * packing.radius[idx]
    )
    flat, counts, radius, raw, status = rounded_bodies(
        packing.vertices, packing.offsets, idx, own, target, CLEAN_TOLERANCE, ROUNDING_TRIES
    )
    bad = np.flatnonzero(status > 0)
    if bad.size:
        j = int(idx[bad[0]])
        why = {1: "its outline has fewer than 3 distinct vertices"}.get(
            int(status[bad[0]]), "it is too thin to carry a rounded body"
        )
        raise ExportError(f"particle {j}: {why}")
    area = raw[:, 0]
    c = raw[:, 1:3] / area[:, None]
    ixx = raw[:, 4] - area * c[:, 1] ** 2
    iyy = raw[:, 3] - area * c[:, 0] ** 2
    ixy = raw[:, 5] - area * c[:, 0] * c[:, 1]
    starts = np.concatenate([[0], np.cumsum(counts)])
    cores = [flat[starts[k] : starts[k + 1]] - c[k] for k in range(idx.size)]
    position = packing.centre[idx] + c
    return LammpsBodies(idx, cores, radius, position, area, ixx, iyy, ixy, int(np.sum(status < 0)))


def reference_body(
    local: FloatArray, own: float, target: float
) -> tuple[FloatArray, float, FloatArray, float, float, float, float]:
    """One particle's body, computed in plain Python (the reference of the compiled batch).

    Parameters
    ----------
    local
        The particle's outline relative to its centre.
    own
        Its own rounding radius (``> 0`` for a disk or a rounded polygon).
    target
        The rounding radius wanted for a sharp polygon.

    Returns
    -------
    tuple
        ``(core, r, centroid, area, ixx, iyy, ixy)``, the core relative to the
        particle's centre.
    """
    core, r, _ = _body_core(local, own, target)
    area, c, ixx, iyy, ixy = rounded_moments(core, r)
    return core, r, c, area, ixx, iyy, ixy


@dataclass(frozen=True)
class PolyhedronBodies:
    """The bodies of the polyhedra (and spheres) of a 3D packing, in its length unit, unit density.

    ``index``, ``rounding``, ``position`` (here the particle's centroid) and
    ``reduced`` are those of :class:`LammpsBodies`; ``cores`` holds each
    body's core, its vertices relative to the body's centre of mass,
    ``volume`` each particle's volume and ``inertia`` its ``(n, 3, 3)``
    inertia tensor about its centre of mass.
    """

    index: NDArray[np.int64]
    cores: list[Core]
    rounding: FloatArray
    position: FloatArray
    volume: FloatArray
    inertia: FloatArray
    reduced: int


def polyhedron_bodies(
    packing: Packing[Box], config: LammpsConfig | None = None
) -> PolyhedronBodies:
    """Cores, rounding radii, centres of mass and inertia of the placed polyhedra.

    Raises
    ------
    ExportError
        One line, for a particle too thin to carry a rounded body.
    """
    cfg = config or LammpsConfig()
    solids = placed_solids(packing, "lammps", spheres=True)
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
    return PolyhedronBodies(
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


def dump_path(path: Path) -> Path:
    """Return the dump of a 3D packing's final state that the script writes: ``<stem>.final.dump``.

    Examples
    --------
    >>> dump_path(Path("runs/box3d/packing.data")).as_posix()
    'runs/box3d/packing.final.dump'
    """
    return Path(path).with_suffix(".final.dump")


def script_path(path: Path) -> Path:
    """Return the input script written beside the data file ``path``: ``<stem>.in``.

    Examples
    --------
    >>> script_path(Path("runs/small/packing.data")).as_posix()
    'runs/small/packing.in'
    """
    return Path(path).with_suffix(".in")


@dataclass(frozen=True)
class _Style:
    """What the data file and the input script say differently in each dimension."""

    dimension: int
    body: str
    eroded: str
    down: str
    gravity: str


_STYLES = {
    2: _Style(2, "polygon", "outline", "y", "0 -1 0"),
    3: _Style(3, "polyhedron", "particle", "z", "0 0 -1"),
}


@dataclass(frozen=True)
class _Plates:
    """The side wall of a walled cylinder as fixed plate bodies, laid out as LAMMPS reads them.

    ``wall`` is the layout in the packing's lengths; ``mass`` (of each plate),
    ``position``, ``lo`` and ``hi`` (the box, which holds the rounded plates)
    are in LAMMPS units; ``blocks`` continues the ``Bodies`` section after the
    grains and ``note`` describes the domain.
    """

    wall: SideWall
    mass: FloatArray
    position: FloatArray
    blocks: list[str]
    lo: FloatArray
    hi: FloatArray
    note: str

    @property
    def n_min(self) -> int:
        """Vertices of a plate's core."""
        return int(self.wall.core.vertices.shape[0])

    @property
    def n_max(self) -> int:
        """Largest of the counts of vertices, edges and faces of a plate's core."""
        core = self.wall.core
        return int(max(core.vertices.shape[0], core.edges.shape[0], body_faces(core).shape[0]))


@dataclass(frozen=True)
class _Layout:
    """The bodies of a packing laid out as LAMMPS reads them, in LAMMPS units.

    ``lo`` and ``hi`` are the box's bounds (in 2D, z spans the room that
    LAMMPS' bins need), ``walls`` the wall lines of the input script,
    ``notes`` the ends of the data file's fourth and fifth lines (comments),
    ``domain`` a line of the script's header (2D) and ``blocks`` the
    ``Bodies`` section.
    """

    style: _Style
    bodies: LammpsBodies | PolyhedronBodies
    scale: float
    lo: FloatArray
    hi: FloatArray
    boundary: str
    walls: list[str]
    mass: FloatArray
    position: FloatArray
    blocks: list[str]
    n_min: int
    n_max: int
    d_min: float
    notes: tuple[str, str]
    domain: list[str]
    plates: _Plates | None = None

    @property
    def rounding(self) -> FloatArray:
        """Rounding radius of each body, in LAMMPS lengths."""
        out: FloatArray = self.bodies.rounding * self.scale
        return out


def _walls_2d(packing: Packing, s: float) -> tuple[str, list[str], str]:
    """Boundary, wall lines and note of a 2D domain (in LAMMPS lengths)."""
    d = packing.domain
    xmin, xmax, ymin, ymax = (float(v) * s for v in d.bounds())
    if isinstance(d, PeriodicRectangle):
        return "p p p", [], "periodic in x and y"
    walls = [f"xplane {_num(xmin)} {_num(xmax)}", f"yplane {_num(ymin)} {_num(ymax)}"]
    lines = [
        f"fix wall{i} all wall/body/polygon ${{k_n}} ${{c_n}} ${{c_t}} {w}"
        for i, w in enumerate(walls, start=1)
    ]
    if isinstance(d, Rectangle):
        return "f f p", lines, "walls on all sides"
    return "f f p", lines, f"walls on the bounding box; the {d.kind}'s own walls are not modelled"


def _polygon_layout(packing: Packing, cfg: LammpsConfig, s: float) -> _Layout:
    """Lay out the bodies of a 2D packing: rounded polygons, laminae of ``thickness``."""
    bodies = lammps_bodies(packing, cfg)
    thickness = length_scale(packing) if cfg.thickness is None else cfg.thickness
    boundary, walls, note = _walls_2d(packing, s)
    density = mineral_densities(packing, cfg)[packing.mineral[bodies.index]]
    lamina = density * thickness * s  # mass per unit area (LAMMPS lengths)
    with np.errstate(over="ignore", under="ignore"):  # checked below
        mass = bodies.area * (np.float64(s) ** 2 * lamina)
        per_area = lamina * np.float64(s) ** 4
        inertia = np.stack([bodies.ixx, bodies.iyy, bodies.ixy], axis=1) * per_area[:, None]
    given = f"length_scale = {s}, thickness = {thickness}, density = {_density_note(cfg)}"
    _check_finite(given, [("mass", mass), ("moment of inertia", inertia[:, :2])])
    n = bodies.index.size
    counts = [c.shape[0] for c in bodies.core]
    n_min, n_max = (min(counts), max(counts)) if counts else (1, 1)
    lo, hi = np.asarray(packing.domain.bounds(), dtype=np.float64).reshape(2, 2).T * s
    pos = np.zeros((n, 3))
    pos[:, :2] = bodies.position * s
    if isinstance(packing.domain, PeriodicRectangle):
        pos[:, :2] = lo + np.mod(pos[:, :2] - lo, hi - lo)
    reach = np.array([np.hypot(*c.T).max() for c in bodies.core]) + bodies.rounding
    # bins need room in z; at least d_min / 4 (0.5 at the built-in scenes' d_min = 2)
    half_z = max(0.5 * length_scale(packing) * s, 2.0 * float(reach.max(initial=0.0)) * s)
    per_line = max(1, math.ceil(n_max / (MAX_BODY_LINES - 4)))  # + count, inertia, rounding
    blocks: list[str] = []
    for k in range(n):
        ixx, iyy, ixy = inertia[k]  # area moments x s^4 x mass per area
        core = bodies.core[k] * s
        blocks.append(f"{k + 1} 1 {6 + 3 * core.shape[0] + 1}")
        blocks.append(str(core.shape[0]))
        blocks.append(" ".join(_num(v) for v in (ixx, iyy, ixx + iyy, -ixy, 0.0, 0.0)))
        xyz = [f"{_num(x)} {_num(y)} 0.0" for x, y in core.tolist()]
        blocks += [" ".join(xyz[i : i + per_line]) for i in range(0, len(xyz), per_line)]
        blocks.append(_num(2.0 * bodies.rounding[k] * s))
    fill = float(np.min(bodies.area / packing.area()[bodies.index])) if n else 1.0
    return _Layout(
        style=_STYLES[2],
        bodies=bodies,
        scale=s,
        lo=np.array([lo[0], lo[1], -half_z]),
        hi=np.array([hi[0], hi[1], half_z]),
        boundary=boundary,
        walls=walls,
        mass=mass,
        position=pos,
        blocks=blocks,
        n_min=n_min,
        n_max=n_max,
        d_min=float(2.0 * math.sqrt(bodies.area.min() / math.pi) * s) if n else 1.0,
        notes=(
            f"; the smallest body fills {_num(round(fill, 4))} of its particle",
            f"area x {_num(thickness * s)} x {_density_note(cfg)}; {note}",
        ),
        domain=[f"# Domain: {note}."],
    )


def _polyhedron_block(
    ident: int, core: Core, vertices: FloatArray, inertia: FloatArray, diameter: float
) -> list[str]:
    """Lines of one polyhedron body of the ``Bodies`` section (LAMMPS units given)."""
    faces = body_faces(core)
    t = inertia
    values = [_num(v) for v in (t[0, 0], t[1, 1], t[2, 2], t[0, 1], t[0, 2], t[1, 2])]
    values += [_num(x) for x in vertices.ravel()]
    values += [str(int(i)) for i in core.edges.ravel()]
    values += [str(int(i)) for i in faces.ravel()]
    values.append(_num(diameter))
    return [
        f"{ident} 3 {len(values)}",
        f"{core.vertices.shape[0]} {core.edges.shape[0]} {faces.shape[0]}",
        *_lines(values),
    ]


def _side_plates(
    packing: Packing[Cylinder],
    cylinder: Cylinder,
    bodies: PolyhedronBodies,
    cfg: LammpsConfig,
    s: float,
) -> _Plates:
    """Lay out the plates of a cylinder's side wall (see :mod:`.lammps_side_wall`).

    Their rounding radius is that of the smallest grain's (``rounding_radius``,
    or ``rounding_fraction`` × the smallest equivalent radius), their density
    ``density``; their ids follow the grains'.
    """
    radius = packing.radius[bodies.index]
    d_min, d_max = (
        (2.0 * float(radius.min()), 2.0 * float(radius.max())) if radius.size else (1.0, 1.0)
    )
    rounding = cfg.rounding_radius or cfg.rounding_fraction * 0.5 * d_min
    wall = side_wall(cylinder, rounding, d_min, d_max)
    first = bodies.index.size + 1
    vertices = wall.core.vertices
    blocks: list[str] = []
    with np.errstate(over="ignore", under="ignore"):  # checked below
        mass = np.full(wall.count, wall.volume * np.float64(s) ** 3 * cfg.density)
        per_density = np.float64(s) ** 5 * cfg.density
        for k in range(wall.count):
            inertia = np.eye(3) * (wall.moment * per_density)
            vertices = wall.vertices(k) * s
            blocks += _polyhedron_block(first + k, wall.core, vertices, inertia, 2.0 * rounding * s)
    _check_finite(
        f"length_scale = {s}, density = {cfg.density}",
        [("mass", mass), ("moment of inertia", np.array([wall.moment * per_density]))],
    )
    reach = wall.reach
    c = cylinder
    end = wall.overhang + rounding
    lo = np.array([c.cx - reach, c.cy - reach, c.zmin - end]) * s
    hi = np.array([c.cx + reach, c.cy + reach, c.zmax + end]) * s
    note = (
        f"a walled cylinder: floor and lid are walls (zplane), the side wall {wall.segments} "
        f"x {wall.layers} fixed plates (around x up; atom type {_atom_types(packing) + 1}, "
        f"group plates) whose corners stand at most {CORNER_GAP} x d_min outside the circle"
    )
    return _Plates(wall, mass, wall.centre * s, blocks, lo, hi, note)


def _atom_types(packing: AnyPacking) -> int:
    """Atom types of the grains: one per mineral."""
    return max(1, len(packing.mineral_names), int(packing.mineral.max(initial=-1)) + 1)


def _polyhedron_layout(packing: Packing[Box], cfg: LammpsConfig, s: float) -> _Layout:
    """Lay out the bodies of a 3D packing: rounded polyhedra (and spheres), grains' inertia."""
    misplaced = misplaced_field(cfg, 3)  # thickness: regopack.export refuses it first
    if misplaced is not None:
        raise ConfigError(f"exporter 'lammps': {misplaced[1]}")
    bodies = polyhedron_bodies(packing, cfg)
    density = mineral_densities(packing, cfg)[packing.mineral[bodies.index]]
    with np.errstate(over="ignore", under="ignore"):  # checked below
        mass = bodies.volume * (np.float64(s) ** 3 * density)
        inertia = bodies.inertia * (np.float64(s) ** 5 * density)[:, None, None]
    diagonal = inertia[:, [0, 1, 2], [0, 1, 2]]
    _check_finite(
        f"length_scale = {s}, density = {_density_note(cfg)}",
        [("mass", mass), ("moment of inertia", diagonal)],
    )
    # LAMMPS sizes every body's storage from Nmax as if it had Nmax vertices,
    # edges and faces: Nmax is the largest of the three counts of any body
    counts = [c.vertices.shape[0] for c in bodies.cores]
    sizes = [
        max(c.vertices.shape[0], c.edges.shape[0], body_faces(c).shape[0]) for c in bodies.cores
    ]
    n_min, n_max = (min(counts), max(sizes)) if counts else (1, 1)
    box = packing.domain
    lo, hi = box.bounds().reshape(3, 2).T * s
    plates = None
    if isinstance(box, Cylinder):
        plates = _side_plates(packing, box, bodies, cfg, s)
        n_min, n_max = min(n_min, plates.n_min), max(n_max, plates.n_max)
        lo, hi = plates.lo, plates.hi
    pos = bodies.position * s
    if box.periodic:
        pos = lo + np.mod(pos - lo, hi - lo)
    blocks: list[str] = []
    for k in range(bodies.index.size):
        core = bodies.cores[k]
        blocks += _polyhedron_block(
            k + 1, core, core.vertices * s, inertia[k], 2.0 * bodies.rounding[k] * s
        )
    walls = [
        f"fix          wall{i + 1} all wall/body/polyhedron ${{k_n}} ${{c_n}} ${{c_t}} "
        f"{axis}plane {_num(lo[i])} {_num(hi[i])}"
        for i, axis in enumerate("xyz")
    ]
    where = "periodic in x, y and z" if box.periodic else "walls on all six sides"
    if plates is not None:
        walls = [
            "fix          wall1 grains wall/body/polyhedron ${k_n} ${c_n} ${c_t} "
            f"zplane {_num(box.zmin * s)} {_num(box.zmax * s)}"
        ]
        where = plates.note
    n = bodies.index.size
    return _Layout(
        style=_STYLES[3],
        bodies=bodies,
        scale=s,
        lo=lo,
        hi=hi,
        boundary="p p p" if box.periodic else "f f f",
        walls=[] if box.periodic else walls,
        mass=mass,
        position=pos,
        blocks=blocks,
        n_min=n_min,
        n_max=n_max,
        d_min=float(2.0 * packing.radius[bodies.index].min() * s) if n else 1.0,
        notes=("", f"particle volume x {_density_note(cfg)}; {where}"),
        domain=[] if plates is None else [f"# Domain: {where}."],
        plates=plates,
    )


class LammpsExporter(Exporter[AnyPacking]):
    """LAMMPS data file (``atom_style body rounded/polygon`` or ``rounded/polyhedron``) and script.

    One body per placed particle, in draw order: atom type = mineral index + 1,
    position = its centre of mass. See the module documentation for how the
    cores are made. In a walled cylinder the plates of the side wall follow
    the grains, with one more atom type (:func:`_side_plates`). In the
    ``Bodies`` section each body lists

    - 2D: its vertex count, the six components of its inertia tensor in the
      box frame (``ixx iyy izz ixy ixz iyz`` of a uniform lamina), its core
      vertices relative to the centre of mass (z = 0) and its rounding
      *diameter*; mass = area of the rounded body × ``thickness`` × ``density``;
    - 3D: ``N E F``, the six components of its inertia tensor in the box
      frame, its core vertices relative to the centre of mass, its edges, its
      faces (four indices, -1 ending a triangle) and its rounding *diameter*;
      mass = volume of the particle × ``density``.
    """

    suffix = ".data"

    def __init__(self, config: LammpsConfig | None = None) -> None:
        self.config = config or LammpsConfig()

    def companions(self, path: Path) -> tuple[Path, ...]:
        """Return the input script written beside the data file."""
        return (script_path(path),)

    def read_state(self, packing: AnyPacking, path: Path) -> AnyPacking:
        """Return ``packing`` as the run whose final dump (``<stem>.final.dump``) is ``path``.

        Granular spheres take the dump's centres; bodies (2D and 3D) move by
        their displacement and turn about their centre of mass by the turn
        from their first orientation to their last. The lengths are divided
        by this exporter's length scale (so give the parameters of the export).
        """
        cfg = self.config
        s = (
            default_length_scale(packing, cfg.units)
            if cfg.length_scale is None
            else cfg.length_scale
        )
        if packing.dimension == 3 and cfg.spheres == "granular":
            if granular_spheres(packing, cfg, s) is not None:
                return read_sphere_dump(packing, path, cfg, s, "LAMMPS")
        if packing.dimension == 3:
            bodies: PolyhedronBodies | LammpsBodies = polyhedron_bodies(packing, cfg)
        else:
            bodies = lammps_bodies(packing, cfg)
        pivot = bodies.position - packing.centre[bodies.index]
        settled: AnyPacking = read_body_dump(
            packing, path, bodies.index, pivot, s, start=bodies.position
        )
        return settled

    def export(self, packing: AnyPacking, path: Path, *, analyses: Analyses = None) -> Path:
        """Write the data file and the input script; return the data file's path.

        Raises
        ------
        ConfigError
            One line, when ``thickness`` is set for a 3D packing.
        """
        cfg = self.config
        path = Path(path)
        s = (
            default_length_scale(packing, cfg.units)
            if cfg.length_scale is None
            else cfg.length_scale
        )
        if packing.dimension == 3 and cfg.spheres == "granular":
            spheres = granular_spheres(packing, cfg, s)
            if spheres is not None:
                _write_text(path, sphere_data(packing, spheres, cfg, "LAMMPS", "sphere"))
                _write_text(script_path(path), self._sphere_script(packing, path, spheres))
                return path
        if packing.dimension == 3:
            layout = _polyhedron_layout(packing, cfg, s)
        else:
            layout = _polygon_layout(packing, cfg, s)
        _write_text(path, self._data(packing, layout, s))
        _write_text(script_path(path), self._script(packing, path, layout))
        return path

    def _data(self, packing: AnyPacking, layout: _Layout, s: float) -> str:
        cfg = self.config
        style = layout.style
        n = layout.bodies.index.size
        n_types = _atom_types(packing)
        atoms = [
            f"{k + 1} {int(packing.mineral[j]) + 1} 1 {_num(layout.mass[k])} "
            + " ".join(_num(x) for x in layout.position[k])
            for k, j in enumerate(layout.bodies.index.tolist())
        ]
        plates = layout.plates
        n_all, types, wall_note, blocks = n, n_types, [], layout.blocks
        if plates is not None:
            n_all, types = n + plates.wall.count, n_types + 1
            atoms += [
                f"{n + k + 1} {types} 1 {_num(plates.mass[k])} "
                + " ".join(_num(x) for x in plates.position[k])
                for k in range(plates.wall.count)
            ]
            wall = plates.wall
            wall_note = [
                f"# atoms {n + 1} to {n_all} (type {types}): the cylinder's side wall, "
                f"{wall.segments} x {wall.layers} fixed plates of rounding radius "
                f"{_num(wall.rounding)} (x {_num(s)}) circumscribing the circle"
            ]
            blocks = [*blocks, *plates.blocks]
        rounding_note = (
            f"rounding radius {_num(cfg.rounding_radius)}"
            if cfg.rounding_radius
            else f"rounding radius {cfg.rounding_fraction} x equivalent radius"
        )
        r_all = layout.rounding
        lo, hi = layout.lo, layout.hi
        lines = [
            f"LAMMPS data file from regopack {packing.version}: scene "
            f"{scene_label(packing)}, seed {packing.seed}, "
            f"atom_style body rounded/{style.body} {layout.n_min} {layout.n_max}",
            "",
            f"# {style.body} bodies: {style.eroded} eroded by the {rounding_note}; the Bodies "
            "section ends each body with its rounding diameter",
            f"# rounding radii from {_num(r_all.min() if n else 0.0)} to "
            f"{_num(r_all.max() if n else 0.0)}; {layout.bodies.reduced} bodies with a "
            f"halved radius{layout.notes[0]}",
            f"# lengths = packing lengths ({length_unit(packing)}) x {_num(s)}; "
            f"mass = {layout.notes[1]}",
            *wall_note,
            "",
            f"{n_all} atoms",
            f"{n_all} bodies",
            f"{types} atom types",
            "",
            *(f"{_num(lo[i])} {_num(hi[i])} {a}lo {a}hi" for i, a in enumerate("xyz")),
            "",
            "Atoms # body",
            "",
            *atoms,
            "",
            "Bodies",
            "",
            *blocks,
        ]
        return "\n".join(lines) + "\n"

    def _sphere_script(self, packing: AnyPacking, path: Path, g: GranularSpheres) -> str:
        cfg = self.config
        model = (
            "hertz/material ${E} ${e_n} ${nu} tangential mindlin NULL 1.0 ${mu} "
            "damping coeff_restitution"
        )
        domain = packing.domain
        if isinstance(domain, Cylinder):
            cx, cy, radius = (v * g.scale for v in (domain.cx, domain.cy, domain.radius))
            walls = [
                f"region       container cylinder z {_num(cx)} {_num(cy)} {_num(radius)} "
                f"{_num(g.lo[2])} {_num(g.hi[2])} side in units box",
                f"fix          wall1 all wall/gran/region granular {model} region container",
            ]
            where = "a walled cylinder (side wall, floor and lid)."
        else:
            walls = [
                f"fix          wall{i + 1} all wall/gran granular {model} "
                f"{axis}plane {_num(g.lo[i])} {_num(g.hi[i])}"
                for i, axis in enumerate("xyz")
            ]
            where = "periodic in x, y and z." if g.periodic else "walls on all six sides."
        return "\n".join(
            [
                f"# LAMMPS input for {path.name}, written by regopack {packing.version} "
                f"(scene {scene_label(packing)}, seed {packing.seed}).",
                f"# Run it in this folder: lmp -in {script_path(path).name}",
                "# Change a parameter with -var, e.g. -var E 7e7 -var steps 50000.",
                f"# Domain: {where}",
                "",
                *material_variable_lines(cfg),
                *rayleigh_step_lines(g.r_rho),
                f"variable skin  equal {_num(0.1 * g.d_min)}",
                "",
                f"units        {cfg.units}",
                "dimension    3",
                f"boundary     {'p p p' if g.periodic else 'f f f'}",
                "atom_style   sphere",
                "atom_modify  map array",
                f"read_data    {path.name}",
                "",
                "pair_style   granular",
                f"pair_coeff   * * {model}",
                "comm_modify  vel yes",
                "neighbor     ${skin} bin",
                "neigh_modify every 1 delay 0 check yes",
                "timestep     ${dt}",
                "",
                "fix          integrate all nve/sphere",
                *([] if g.periodic else walls),
                "fix          weight all gravity ${g} vector 0 0 -1",
                "compute      disp all displace/atom",
                "",
                "thermo_style custom step atoms ke pe",
                "thermo       1000",
                "run          ${steps}",
                f"write_dump   all custom {dump_path(path).name} id type x y z radius mass "
                'c_disp[1] c_disp[2] c_disp[3] c_disp[4] modify sort id format line "%d %d'
                + " %.17g" * 9
                + '"',
                "",
            ]
        )

    def _script(self, packing: AnyPacking, path: Path, layout: _Layout) -> str:
        cfg = self.config
        style = layout.style
        m_min = float(layout.mass.min()) if layout.mass.size else 1.0
        d_min = layout.d_min
        r_min = float(layout.rounding.min()) if layout.rounding.size else 0.05 * d_min
        grains, groups, exclude = "all", [], []
        thermo = ["thermo_style custom step atoms ke pe"]
        if layout.plates is not None:  # the side wall's plates: never integrated or counted
            grains, plates = "grains", _atom_types(packing) + 1
            groups = [
                f"group        plates type {plates}",
                "group        grains subtract all plates",
            ]
            exclude = [f"neigh_modify exclude type {plates} {plates}"]
            thermo = [
                "variable     grains equal count(grains)",
                "compute      t_grains grains temp",
                "thermo_style custom step v_grains ke pe",
                "thermo_modify temp t_grains norm no",
            ]
        return "\n".join(
            [
                f"# LAMMPS input for {path.name}, written by regopack {packing.version} "
                f"(scene {scene_label(packing)}, seed {packing.seed}).",
                f"# Run it in this folder: lmp -in {script_path(path).name}",
                "# Change a parameter with -var, e.g. -var k_n 1e5 -var steps 50000.",
                *layout.domain,
                "",
                f"variable steps index {cfg.steps}",
                f"variable k_n   index {_num(cfg.stiffness)}   # normal stiffness (force/length)",
                f"variable e_n   index {_num(cfg.restitution)}   "
                f"# restitution of two {'smallest' if style.dimension == 2 else 'lightest'} "
                "bodies",
                f"variable mu    index {_num(cfg.friction)}   # friction coefficient",
                f"variable g     index {_num(cfg.gravity)}   "
                f"# gravity along -{style.down} (acceleration)",
                f"variable m_min equal {_num(m_min)}   # mass of the lightest body",
                "variable zeta  equal -ln(v_e_n)/sqrt(PI^2+ln(v_e_n)^2)",
                "variable c_n   equal 2*v_zeta*sqrt(0.5*v_m_min*v_k_n)   # normal damping",
                "variable c_t   equal 0.5*v_c_n   # tangential damping",
                "variable dt    equal PI*sqrt(0.5*v_m_min/v_k_n)/"
                f"{STEPS_PER_COLLISION[style.dimension]}",
                f"variable skin  equal {_num(0.1 * d_min)}",
                f"variable cut   equal {_num(0.5 * r_min)}",
                "",
                f"units        {cfg.units}",
                f"dimension    {style.dimension}",
                f"boundary     {layout.boundary}",
                "newton       on",
                f"atom_style   body rounded/{style.body} {layout.n_min} {layout.n_max}",
                "atom_modify  map array",
                f"read_data    {path.name}",
                *groups,
                "",
                f"pair_style   body/rounded/{style.body} ${{c_n}} ${{c_t}} ${{mu}} 1.0 ${{cut}}",
                "pair_coeff   * * ${k_n} 0.0",
                "comm_modify  vel yes",
                "neighbor     ${skin} bin",
                "neigh_modify every 1 delay 0 check yes",
                *exclude,
                "timestep     ${dt}",
                "",
                f"fix          integrate {grains} nve/body",
                *layout.walls,
                f"fix          weight {grains} gravity ${{g}} vector {style.gravity}",
                *(["fix          plane all enforce2d"] if style.dimension == 2 else []),
                *self._final_state(path, grains),
                "",
                *thermo,
                "thermo       1000",
                "run          ${steps}",
                *self._final_dump(path, grains),
                "",
            ]
        )

    @staticmethod
    def _final_state(path: Path, group: str = "all") -> list[str]:
        """Script lines that keep each body's start: its displacement and first orientation."""
        return [
            f"compute      disp {group} displace/atom",
            f"compute      q {group} property/atom quatw quati quatj quatk",
            f"fix          q0 {group} store/state 0 c_q[1] c_q[2] c_q[3] c_q[4]",
        ]

    @staticmethod
    def _final_dump(path: Path, group: str = "all") -> list[str]:
        """Script lines that write each body's final position, displacement and orientations."""
        return [
            f"write_dump   {group} custom {dump_path(path).name} id type x y z c_disp[1] "
            "c_disp[2] "
            "c_disp[3] c_q[1] c_q[2] c_q[3] c_q[4] f_q0[1] f_q0[2] f_q0[3] f_q0[4] "
            'modify sort id format line "%d %d' + " %.17g" * 14 + '"',
        ]


__getattr__ = renamed_names(
    __name__,
    {
        "Lammps3dBodies": "PolyhedronBodies",
        "Lammps3dConfig": "LammpsConfig",
        "Lammps3dExporter": "LammpsExporter",
        "lammps3d_bodies": "polyhedron_bodies",
        "script3d_path": "script_path",
    },
)
"""The names of the 3D exporter this module's exporter took over, for one release."""
