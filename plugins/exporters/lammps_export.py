"""LAMMPS export: a data file of rounded-polygon bodies and an input script that runs it.

Every placed particle becomes one body of LAMMPS' ``atom_style body
rounded/polygon``: a convex core and a rounding radius ``r``, the body being
the points within ``r`` of the core. A sharp polygon's core is its outline
eroded by ``r`` (:func:`~regopack.plugins.exporters.rounded_bodies.erode_convex`), so
the body fills the particle but for its rounded corners and never reaches past
it: neighbours that touch in the packing touch, without overlap, in LAMMPS. A
disk is one vertex with its own radius; a rounded polygon keeps its core and
radius. Repeated and collinear vertices are removed first
(:func:`~regopack.plugins.exporters.rounded_bodies.clean_outline`).

Beside ``<stem>.data`` the exporter writes ``<stem>.in``, an input script that
reads it with the pair style ``body/rounded/polygon``, walls or periodic
boundaries from the domain, a time step from the smallest body's mass and the
stiffness, and its parameters as LAMMPS ``index`` variables (``lmp -in
packing.in -var k_n 1e5`` changes one).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.base.errors import ExportError
from regopack.base.units import conversion, length_scale, length_unit
from regopack.geometry.domain import PeriodicRectangle, Rectangle
from regopack.packing.core import Packing, _atomic_file
from regopack.plugins.exporters.rounded_bodies import (
    CLEAN_TOLERANCE,
    clean_outline,
    erode_convex,
    rounded_moments,
)
from regopack.plugins.exporters.rounded_bodies_kernel import rounded_bodies
from regopack.registry.interfaces import Analyzer, Exporter

__all__ = [
    "LammpsBodies",
    "LammpsConfig",
    "LammpsExporter",
    "lammps_bodies",
    "reference_body",
    "script_path",
]

FloatArray = NDArray[np.float64]

STEPS_PER_COLLISION = 50
"""Time steps per duration of a collision of the two smallest bodies (sets the time step)."""

MAX_BODY_LINES = 32
"""Lines LAMMPS' read_data accepts for one body (its MAXBODY); long cores share lines."""

ROUNDING_TRIES = 8
"""Times the rounding radius of one body is halved when its eroded core vanishes."""


UNIT_STYLE_LENGTH: dict[str, str | None] = {
    "micro": "µm",
    "si": "m",
    "cgs": "cm",
    "nano": "nm",
    "lj": None,
}
"""Length unit of each LAMMPS unit style (``lj``: none, lengths written as they are)."""


def default_length_scale(packing: Any, units: str) -> float:
    """Return the factor from the packing's ``length_unit`` to the length unit of ``units``.

    1 for ``lj`` (reduced units: lengths as they are) and for a scene in
    micrometres written with ``units = "micro"``.

    Examples
    --------
    >>> default_length_scale({"length_unit": "mm"}, "micro"), default_length_scale({}, "si")
    (1000.0, 1e-06)
    """
    target = UNIT_STYLE_LENGTH[units]
    return 1.0 if target is None else conversion(length_unit(packing), target)


class LammpsConfig(BaseModel):
    """Parameters of the LAMMPS exporter.

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
        description=(
            "Out-of-plane thickness of every body in the packing's length unit; "
            "a body's mass is its area × thickness × density. Default: d_min / 2 "
            "(1 at the built-in scenes' d_min = 2)."
        ),
    )
    rounding_fraction: float = Field(
        0.05,
        gt=0,
        le=0.5,
        description=(
            "Rounding radius of a polygon body as a fraction of the particle's "
            "equivalent radius (disks and rounded polygons keep their own)."
        ),
    )
    rounding_radius: float = Field(
        0.0,
        ge=0,
        allow_inf_nan=False,
        description=(
            "One rounding radius for every polygon body, in the packing's length unit; "
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
            "Normal coefficient of restitution of a collision of the two smallest bodies; "
            "sets the damping c_n."
        ),
    )
    friction: float = Field(0.5, ge=0, allow_inf_nan=False, description="Friction coefficient mu.")
    gravity: float = Field(
        0.0,
        ge=0,
        allow_inf_nan=False,
        description="Acceleration of gravity along -y in the input script (0: none).",
    )
    steps: int = Field(10000, ge=0, description="Time steps the input script runs.")


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


def script_path(path: Path) -> Path:
    """Return the input script written beside the data file ``path``: ``<stem>.in``.

    Examples
    --------
    >>> script_path(Path("runs/small/packing.data")).as_posix()
    'runs/small/packing.in'
    """
    return Path(path).with_suffix(".in")


def _num(value: float) -> str:
    return repr(float(value))


def _write(path: Path, text: str) -> None:
    try:
        with _atomic_file(path) as fh:
            fh.write(text.encode("utf-8"))
    except OSError as err:
        raise ExportError(f"cannot write {path}: {err.strerror or type(err).__name__}") from err


@dataclass(frozen=True)
class _Frame:
    """Box, boundary and walls of the LAMMPS simulation, in LAMMPS lengths."""

    box: tuple[float, float, float, float]
    boundary: str
    walls: list[str]
    note: str


def _frame(packing: Packing, scale: float) -> _Frame:
    d = packing.domain
    xmin, xmax, ymin, ymax = (float(v) * scale for v in d.bounds())
    if isinstance(d, PeriodicRectangle):
        return _Frame((xmin, xmax, ymin, ymax), "p p p", [], "periodic in x and y")
    if isinstance(d, Rectangle):
        walls = [f"xplane {_num(xmin)} {_num(xmax)}", f"yplane {_num(ymin)} {_num(ymax)}"]
        return _Frame((xmin, xmax, ymin, ymax), "f f p", walls, "walls on all sides")
    walls = [f"xplane {_num(xmin)} {_num(xmax)}", f"yplane {_num(ymin)} {_num(ymax)}"]
    return _Frame(
        (xmin, xmax, ymin, ymax),
        "f f p",
        walls,
        f"walls on the bounding box; the {d.kind}'s own walls are not modelled",
    )


class LammpsExporter(Exporter):
    """LAMMPS data file (``atom_style body rounded/polygon``, 2d) and its input script.

    One body per placed particle, in draw order: atom type = mineral index + 1,
    mass = area of the rounded body × ``thickness`` × ``density``, position =
    its centre of mass. In the ``Bodies`` section each body lists its vertex
    count, the six components of its inertia tensor in the box frame
    (``ixx iyy izz ixy ixz iyz`` of a uniform lamina), its core vertices
    relative to the centre of mass (z = 0) and its rounding *diameter*. See
    the module documentation for how the cores are made.
    """

    suffix = ".data"

    def __init__(self, config: LammpsConfig | None = None) -> None:
        self.config = config or LammpsConfig()

    def companions(self, path: Path) -> tuple[Path, ...]:
        """Return the input script written beside the data file."""
        return (script_path(path),)

    def export(
        self, packing: Packing, path: Path, *, analyses: Mapping[str, Analyzer] | None = None
    ) -> Path:
        """Write the data file and the input script; return the data file's path."""
        cfg = self.config
        path = Path(path)
        bodies = lammps_bodies(packing, cfg)
        s = (
            default_length_scale(packing, cfg.units)
            if cfg.length_scale is None
            else cfg.length_scale
        )
        thickness = length_scale(packing) if cfg.thickness is None else cfg.thickness
        frame = _frame(packing, s)
        lamina = cfg.density * thickness * s  # mass per unit area (LAMMPS lengths)
        with np.errstate(over="ignore", under="ignore"):  # checked below
            mass = bodies.area * (np.float64(s) ** 2 * lamina)
            per_area = np.float64(lamina) * np.float64(s) ** 4
            inertia = np.stack([bodies.ixx, bodies.iyy, bodies.ixy], axis=1) * per_area
        n = bodies.index.size
        counts = [c.shape[0] for c in bodies.core]
        n_min, n_max = (min(counts), max(counts)) if counts else (1, 1)
        n_types = max(1, len(packing.mineral_names), int(packing.mineral.max(initial=-1)) + 1)
        pos = bodies.position * s
        if isinstance(packing.domain, PeriodicRectangle):
            lo = np.array([frame.box[0], frame.box[2]])
            width = np.array([frame.box[1] - frame.box[0], frame.box[3] - frame.box[2]])
            pos = lo + np.mod(pos - lo, width)
        for what, values in (("mass", mass), ("moment of inertia", inertia[:, :2])):
            tiny = np.finfo(np.float64).tiny  # subnormal numbers lose their precision
            if n and not (np.isfinite(values).all() and (values >= tiny).all()):
                raise ExportError(
                    f"length_scale = {s}, thickness = {thickness}, density = {cfg.density}: "
                    f"a body's {what} is not a positive finite number; give values nearer 1"
                )
        reach = np.array([np.hypot(*c.T).max() for c in bodies.core]) + bodies.rounding
        # bins need room in z; at least d_min / 4 (0.5 at the built-in scenes' d_min = 2)
        half_z = max(0.5 * length_scale(packing) * s, 2.0 * float(reach.max(initial=0.0)) * s)
        per_line = max(1, math.ceil(n_max / (MAX_BODY_LINES - 4)))  # + count, inertia, rounding
        atoms: list[str] = []
        blocks: list[str] = []
        for k in range(n):
            j = int(bodies.index[k])
            atoms.append(
                f"{k + 1} {int(packing.mineral[j]) + 1} 1 {_num(mass[k])} "
                f"{_num(pos[k, 0])} {_num(pos[k, 1])} 0.0"
            )
            ixx, iyy, ixy = inertia[k]  # area moments x s^4 x mass per area
            core = bodies.core[k] * s
            blocks.append(f"{k + 1} 1 {6 + 3 * core.shape[0] + 1}")
            blocks.append(str(core.shape[0]))
            blocks.append(" ".join(_num(v) for v in (ixx, iyy, ixx + iyy, -ixy, 0.0, 0.0)))
            xyz = [f"{_num(x)} {_num(y)} 0.0" for x, y in core.tolist()]
            blocks += [" ".join(xyz[i : i + per_line]) for i in range(0, len(xyz), per_line)]
            blocks.append(_num(2.0 * bodies.rounding[k] * s))
        rounding_note = (
            f"rounding radius {_num(cfg.rounding_radius)}"
            if cfg.rounding_radius
            else f"rounding radius {cfg.rounding_fraction} x equivalent radius"
        )
        r_all = bodies.rounding * s
        fill = float(np.min(bodies.area / packing.area()[bodies.index])) if n else 1.0
        xlo, xhi, ylo, yhi = frame.box
        lines = [
            f"LAMMPS data file from regopack {packing.version}: scene "
            f"{packing.scene.get('name', '?')}, seed {packing.seed}, "
            f"atom_style body rounded/polygon {n_min} {n_max}",
            "",
            f"# polygon bodies: outline eroded by the {rounding_note}; the Bodies section "
            "ends each body with its rounding diameter",
            f"# rounding radii from {_num(r_all.min() if n else 0.0)} to "
            f"{_num(r_all.max() if n else 0.0)}; {bodies.reduced} bodies with a halved radius; "
            f"the smallest body fills {_num(round(fill, 4))} of its particle",
            f"# lengths = packing lengths ({length_unit(packing)}) x {_num(s)}; "
            f"mass = area x {_num(thickness * s)} "
            f"x {_num(cfg.density)}; {frame.note}",
            "",
            f"{n} atoms",
            f"{n} bodies",
            f"{n_types} atom types",
            "",
            f"{_num(xlo)} {_num(xhi)} xlo xhi",
            f"{_num(ylo)} {_num(yhi)} ylo yhi",
            f"{_num(-half_z)} {_num(half_z)} zlo zhi",
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
        d_min = float(2.0 * math.sqrt(bodies.area.min() / math.pi) * s) if n else 1.0
        script = self._script(packing, path, frame, n_min, n_max, m_min, d_min, r_all)
        _write(path, "\n".join(lines) + "\n")
        _write(script_path(path), script)
        return path

    def _script(
        self,
        packing: Packing,
        path: Path,
        frame: _Frame,
        n_min: int,
        n_max: int,
        m_min: float,
        d_min: float,
        rounding: FloatArray,
    ) -> str:
        cfg = self.config
        r_min = float(rounding.min()) if rounding.size else 0.05 * d_min
        walls = [
            f"fix wall{i} all wall/body/polygon ${{k_n}} ${{c_n}} ${{c_t}} {w}"
            for i, w in enumerate(frame.walls, start=1)
        ]
        return "\n".join(
            [
                f"# LAMMPS input for {path.name}, written by regopack {packing.version} "
                f"(scene {packing.scene.get('name', '?')}, seed {packing.seed}).",
                f"# Run it in this folder: lmp -in {script_path(path).name}",
                "# Change a parameter with -var, e.g. -var k_n 1e5 -var steps 50000.",
                f"# Domain: {frame.note}.",
                "",
                f"variable steps index {cfg.steps}",
                f"variable k_n   index {_num(cfg.stiffness)}   # normal stiffness (force/length)",
                f"variable e_n   index {_num(cfg.restitution)}   "
                "# restitution of two smallest bodies",
                f"variable mu    index {_num(cfg.friction)}   # friction coefficient",
                f"variable g     index {_num(cfg.gravity)}   # gravity along -y (acceleration)",
                f"variable m_min equal {_num(m_min)}   # mass of the lightest body",
                "variable zeta  equal -ln(v_e_n)/sqrt(PI^2+ln(v_e_n)^2)",
                "variable c_n   equal 2*v_zeta*sqrt(0.5*v_m_min*v_k_n)   # normal damping",
                "variable c_t   equal 0.5*v_c_n   # tangential damping",
                f"variable dt    equal PI*sqrt(0.5*v_m_min/v_k_n)/{STEPS_PER_COLLISION}",
                f"variable skin  equal {_num(0.1 * d_min)}",
                f"variable cut   equal {_num(0.5 * r_min)}",
                "",
                f"units        {cfg.units}",
                "dimension    2",
                f"boundary     {frame.boundary}",
                "newton       on",
                f"atom_style   body rounded/polygon {n_min} {n_max}",
                "atom_modify  map array",
                f"read_data    {path.name}",
                "",
                "pair_style   body/rounded/polygon ${c_n} ${c_t} ${mu} 1.0 ${cut}",
                "pair_coeff   * * ${k_n} 0.0",
                "comm_modify  vel yes",
                "neighbor     ${skin} bin",
                "neigh_modify every 1 delay 0 check yes",
                "timestep     ${dt}",
                "",
                "fix          integrate all nve/body",
                *walls,
                "fix          weight all gravity ${g} vector 0 -1 0",
                "fix          plane all enforce2d",
                "",
                "thermo_style custom step atoms ke pe",
                "thermo       1000",
                "run          ${steps}",
                "",
            ]
        )
