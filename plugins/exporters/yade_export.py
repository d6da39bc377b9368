"""YADE export: a script that builds every placed particle as a YADE body, and its bodies.

YADE (``yade -n -x packing.py``) runs Python scripts that build a scene and
run it. A 3D packing is written as two files:

- ``<stem>.bodies``: one line a body, ``index mineral n radius x1 y1 z1 …
  xn yn zn`` — the particle's draw index, its mineral index, and either a
  sphere (``n = 1``, its centre, ``radius > 0``) or a polyhedron (its ``n``
  vertices in the packing's frame, ``radius = 0``);
- ``<stem>.py``: the script. Its first lines set the parameters (one
  material per mineral: density and friction; Young's modulus, Poisson's
  ratio, damping, gravity, the time step's safety factor), each also
  changeable on the command line (``--gravity 9.81``). It creates every
  sphere as a ``Sphere`` and every polyhedron as a ``Polyhedra`` from its
  exact vertices, the six walls of a walled box (axis-aligned ``Wall``
  bodies) or YADE's periodic cell, and the engines the bodies need (and no
  other): spheres meet through ``ScGeom``/``FrictPhys`` (linear springs with
  Coulomb friction), polyhedra through YADE's volumetric law (a normal force
  proportional to the volume of overlap). It runs nothing unless asked:
  ``--run STEPS`` runs that many steps and then writes the bodies' final
  state, ``<stem>.final.txt``; ``RUN_STEPS`` at the top does the same for a
  user who runs it with ``exec`` from a script of their own, where
  :func:`save_state` also writes the state at any time.

Lengths are the packing's times ``length_scale``, by default converted to
metres (YADE works in whatever consistent units it is given; the defaults
here are SI: kg/m³, Pa, m/s²). The volumetric law's stiffness is a force per
volume of overlap: the script gives the polyhedra ``young /
volumetric_length``, ``volumetric_length`` being the packing's smallest
equivalent diameter by default, so that a contact between the smallest
grains is about as stiff as one between spheres of that size. The time step
is ``dt_fraction`` of the shortest characteristic time a body can have on its
stiffest contact: YADE's P-wave time step of the spheres, and
``√(m / (k D²))`` of each polyhedron (mass ``m``, circumscribed diameter
``D``, ``k`` the volumetric stiffness).

The final state gives, for every body in draw order, its centroid, the
displacement of its centroid and the rotation (a 3 × 3 matrix, row by row)
from the packing to the end of the run, in the script's lengths;
:meth:`YadeExporter.read_state` (``regopack settled``) turns it back into a
packing. 2D packings are refused in one line.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Annotated

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from regopack.base.errors import ConfigError, ExportError
from regopack.base.units import conversion, length_unit
from regopack.geometry.domain import Box, Cylinder
from regopack.packing.core import Packing
from regopack.plugins.exporters.export_common import Analyses, _num, _write_text, scene_label
from regopack.plugins.exporters.granular_common import mineral_densities, mineral_values
from regopack.plugins.exporters.solid_export_common import (
    PlacedSolid,
    mass_properties,
    placed_solids,
)
from regopack.registry.interfaces import Exporter

__all__ = [
    "STATE_FORMAT",
    "YadeConfig",
    "YadeExporter",
    "bodies_path",
    "read_yade_state",
    "state_path",
]

VERLET_FRACTION = 0.05
"""Margin of YADE's collider (``verletDist``) as a fraction of the smallest equivalent diameter."""

FACET_GAP = 0.01
"""A walled cylinder's side wall is made of flat facets whose planes touch the circle at their
middles (the polygon circumscribes it): its corners stand farther out, by at most this
fraction of the smallest equivalent diameter (it sets the number of facets)."""

MIN_SEGMENTS = 16
"""Fewest facets (around) of a cylinder's side wall."""

STATE_FORMAT = "regopack-yade-state 1"
"""First line of the final state that the script writes."""


def bodies_path(path: Path) -> Path:
    """Return the bodies file written beside the script ``path``: ``<stem>.bodies``.

    Examples
    --------
    >>> bodies_path(Path("runs/dem3d/packing.py")).as_posix()
    'runs/dem3d/packing.bodies'
    """
    return Path(path).with_suffix(".bodies")


def state_path(path: Path) -> Path:
    """Return the final state the script writes after ``--run``: ``<stem>.final.txt``.

    Examples
    --------
    >>> state_path(Path("runs/dem3d/packing.py")).as_posix()
    'runs/dem3d/packing.final.txt'
    """
    return Path(path).with_suffix(".final.txt")


class YadeConfig(BaseModel):
    """Parameters of the YADE exporter (3D packings of polyhedra and spheres).

    Every value is written at the top of the script, where it can be edited;
    the command line of the script changes the run's (``--run``,
    ``--gravity``, ``--young``, ``--damping``, ``--dt-fraction``). Lengths of
    the packing are multiplied by ``length_scale``; by default it converts
    the scene's ``length_unit`` to metres, and the other defaults are SI.
    """

    model_config = ConfigDict(extra="forbid", strict=True)

    length_scale: float | None = Field(
        None,
        gt=0,
        allow_inf_nan=False,
        description=(
            "Factor from the packing's length unit to the script's length unit; default: "
            "the scene's length_unit in metres (1e-6 for 'µm')."
        ),
    )
    density: float = Field(
        3100.0,
        gt=0,
        allow_inf_nan=False,
        description="Mass per unit volume of the grains (kg/m³ with the SI defaults).",
    )
    mineral_density: dict[str, Annotated[float, Field(gt=0, allow_inf_nan=False)]] = Field(
        default_factory=dict,
        description="Density of the grains of a mineral, by name; others get `density`.",
    )
    friction: float = Field(
        0.5,
        ge=0,
        allow_inf_nan=False,
        description="Coulomb friction coefficient of the grains and walls (no unit).",
    )
    mineral_friction: dict[str, Annotated[float, Field(ge=0, allow_inf_nan=False)]] = Field(
        default_factory=dict,
        description="Friction coefficient of the grains of a mineral, by name; others get "
        "`friction`.",
    )
    youngs_modulus: float = Field(
        1.0e8,
        gt=0,
        allow_inf_nan=False,
        description=(
            "Young's modulus E of the grains and walls (Pa with the SI defaults: 1e8 is a "
            "softened grain, basalt has 7e10)."
        ),
    )
    poisson_ratio: float = Field(
        0.25, gt=0, lt=0.5, description="Poisson's ratio of the grains and walls (no unit)."
    )
    volumetric_length: float | None = Field(
        None,
        gt=0,
        allow_inf_nan=False,
        description=(
            "Polyhedra: their contact stiffness per volume of overlap is E / volumetric_length "
            "(in the script's lengths); default: the smallest equivalent diameter."
        ),
    )
    damping: float = Field(
        0.2,
        ge=0,
        lt=1,
        description="Local (non-viscous) damping of YADE's NewtonIntegrator (no unit).",
    )
    gravity: float = Field(
        0.0,
        ge=0,
        allow_inf_nan=False,
        description="Acceleration of gravity along -z (m/s² with the SI defaults); 0: none.",
    )
    steps: int = Field(
        0,
        ge=0,
        description="Steps the script runs after building the scene (0: it only builds it).",
    )
    dt_fraction: float = Field(
        0.3,
        gt=0,
        le=1,
        description=(
            "Time step as a fraction of the shortest characteristic time of a body on its "
            "stiffest contact (safety factor; no unit)."
        ),
    )


class YadeExporter(Exporter[Packing[Box]]):
    """YADE script (``<stem>.py``) and bodies file (``<stem>.bodies``) of a 3D packing.

    See the module documentation for the files and the model.
    """

    suffix = ".py"

    def __init__(self, config: YadeConfig | None = None) -> None:
        self.config = config or YadeConfig()

    def companions(self, path: Path) -> tuple[Path, ...]:
        """Return the bodies file written beside the script."""
        return (bodies_path(path),)

    def read_state(self, packing: Packing[Box], path: Path) -> Packing[Box]:
        """Return ``packing`` as the run whose final state (``<stem>.final.txt``) is ``path``.

        See :func:`read_yade_state`; the lengths are divided by this
        exporter's ``length_scale`` (so give the parameters of the export).
        """
        if packing.dimension != 3:
            raise ConfigError("exporter 'yade': reads the states of 3D packings only")
        return read_yade_state(packing, path, self._scale(packing))

    def _scale(self, packing: Packing[Box]) -> float:
        """Return the factor from the packing's lengths to the script's."""
        if self.config.length_scale is not None:
            return self.config.length_scale
        return conversion(length_unit(packing), "m")

    def export(self, packing: Packing[Box], path: Path, *, analyses: Analyses = None) -> Path:
        """Write the script and the bodies file; return the script's path.

        Raises
        ------
        ExportError
            One line, when the packing is 2D, or has rounded polyhedra, or a
            parameter gives a body no positive finite mass.
        ConfigError
            One line, when ``mineral_density`` or ``mineral_friction`` names a
            mineral the packing does not have.
        """
        cfg = self.config
        path = Path(path)
        if packing.dimension != 3:
            raise ExportError(
                "exporter 'yade' writes 3D packings (polyhedra and spheres); 2D packings: csv, "
                "gsd, image, json, lammps, svg, vtk"
            )
        scale = self._scale(packing)
        solids = placed_solids(packing, "yade", spheres=True)
        names = [str(n) for n in packing.mineral_names]
        density = mineral_densities(packing, cfg, "yade")
        friction = _mineral_friction(packing, cfg)
        index = np.array([p.index for p in solids], dtype=np.int64)
        volume = packing.solids.volume[index]  # every face at once
        d_min = float((6.0 / math.pi * volume.min()) ** (1.0 / 3.0)) if index.size else 1.0
        kappa_length = cfg.volumetric_length or d_min * scale
        with np.errstate(over="ignore", under="ignore"):  # checked below
            mass = volume * np.float64(scale) ** 3 * density[packing.mineral[index]]
        if mass.size and not (np.isfinite(mass).all() and mass.min() >= np.finfo(float).tiny):
            raise ExportError(
                f"exporter 'yade': length_scale = {scale} and the densities give a body no "
                "positive finite mass; give values nearer 1"
            )
        if packing.domain.periodic:
            _check_cell(packing, solids, d_min)
        _check_reach(packing, solids, scale)
        _write_text(bodies_path(path), _bodies_text(packing, solids, scale))
        text = _script(
            packing,
            path,
            cfg,
            scale=scale,
            names=names or ["grain"],
            density=density,
            friction=friction,
            kappa_length=kappa_length,
            verlet=VERLET_FRACTION * d_min * scale,
            spheres=any(not p.loops for p in solids),
            polyhedra=any(p.loops for p in solids),
            d_min=d_min,
        )
        _write_text(path, text)
        return path


def read_yade_state(packing: Packing[Box], path: Path, scale: float) -> Packing[Box]:
    """Return ``packing`` as the YADE run whose final state is ``path`` left it.

    ``scale`` is the export's ``length_scale``: the state's lengths are
    divided by it. Each body's centroid moves by its displacement and the body
    turns about it by its rotation; the steps and the time of the run go into
    the packing's ``stats`` (``settled_steps``, ``settled_time``).

    Raises
    ------
    PackingFileError
        One line naming ``path``, when it is no state of this packing's bodies.
    """
    from regopack.base.errors import PackingError, PackingFileError
    from regopack.packing.motion import moved

    try:
        lines = Path(path).read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as err:
        raise PackingFileError(f"{path}: cannot read a YADE state: {err}") from err
    if not lines or lines[0].strip() != STATE_FORMAT:
        raise PackingFileError(
            f"{path}: not a YADE state written by regopack's script (its first line is not "
            f"{STATE_FORMAT!r})"
        )
    rows = [line.split() for line in lines[1:] if line.strip() and not line.startswith("#")]
    solids = placed_solids(packing, "yade", spheres=True)
    if len(rows) != len(solids) or any(len(r) != 16 for r in rows):
        raise PackingFileError(
            f"{path}: {len(rows)} bodies of 16 columns expected for the packing's "
            f"{len(solids)} placed particles; is it the state of another packing?"
        )
    try:
        table = np.array(rows, dtype=np.float64)
    except ValueError as err:
        raise PackingFileError(f"{path}: a value is not a number ({err})") from err
    if not np.isfinite(table).all():
        raise PackingFileError(f"{path}: a body's state is not finite (the run blew up)")
    index = np.array([p.index for p in solids], dtype=np.int64)
    if not np.array_equal(table[:, 0], index):
        raise PackingFileError(
            f"{path}: its draw indices are not the packing's placed particles in draw order"
        )
    pivot = np.array(
        [mass_properties(p.local, p.loops)[1] if p.loops else np.zeros(3) for p in solids]
    ).reshape(-1, 3)
    head = dict(
        re.findall(r"(steps|time|length scale) ([^,\s]+)", lines[1] if len(lines) > 1 else "")
    )
    try:
        numbers = {k: float(v) for k, v in head.items()}
    except ValueError as err:
        raise PackingFileError(f"{path}: its header holds a value that is not a number") from err
    if not all(math.isfinite(v) for v in numbers.values()):
        raise PackingFileError(f"{path}: its header holds a value that is not finite")
    written = numbers.pop("length scale", None)
    if written is not None and not math.isclose(written, scale, rel_tol=1e-12):
        raise PackingFileError(
            f"{path}: written with length scale {written!r}, read with {scale!r}; give the "
            "export's length_scale"
        )
    stats = {f"settled_{k}": v for k, v in numbers.items()}
    try:
        return moved(
            packing,
            index,
            table[:, 4:7] / scale,
            table[:, 7:16].reshape(-1, 3, 3),
            pivot,
            stats,
        )
    except PackingError as err:
        raise PackingFileError(f"{path}: {str(err).removeprefix('moved: ')}") from err


MAX_COORDINATE = 1.0e4
"""Largest coordinate of a polyhedron's vertex in the script's lengths: YADE 2023.02a built
polyhedra up to 10⁴ and crashed or kept no vertex at 10⁵ and beyond."""


def _check_reach(packing: Packing[Box], solids: list[PlacedSolid], scale: float) -> None:
    """Refuse polyhedra whose vertices lie farther than MAX_COORDINATE from the origin."""
    box = packing.domain
    origin = box.bounds().reshape(3, 2)[:, 0] if box.periodic else np.zeros(3)
    reach = max((float(np.abs(p.world - origin).max()) for p in solids if p.loops), default=0.0)
    if reach * scale > MAX_COORDINATE:
        raise ExportError(
            f"exporter 'yade': a polyhedron's vertex lies at {reach * scale:.3g} in the script's "
            f"lengths (length_scale = {scale!r}); YADE builds polyhedra only up to "
            f"{MAX_COORDINATE:g}: give a smaller length_scale"
        )


def _check_cell(packing: Packing[Box], solids: list[PlacedSolid], d_min: float) -> None:
    """Refuse a periodic box in which a body is half a side across (YADE's cell refuses it)."""
    side = np.diff(packing.domain.bounds().reshape(3, 2), axis=1)[:, 0]
    for p in solids:
        points = p.world if p.loops else p.centre[None, :]
        extent = points.max(axis=0) - points.min(axis=0) + 2.0 * p.rounding
        extent += 2.0 * VERLET_FRACTION * d_min
        if np.any(extent >= 0.5 * side):
            axis = int(np.argmax(extent / side))
            raise ExportError(
                f"exporter 'yade': particle {p.index} is {extent[axis]:.6g} across along "
                f"{'xyz'[axis]} with the collider's margin, not under half the periodic box's "
                f"side ({side[axis]:.6g}), as YADE's periodic cell needs; use a larger box"
            )


def _mineral_friction(packing: Packing[Box], cfg: YadeConfig) -> list[float]:
    """Friction coefficient of each mineral (the mineral index's entry)."""
    values = mineral_values(packing, cfg.friction, cfg.mineral_friction, "mineral_friction", "yade")
    return [float(v) for v in values]


def _bodies_text(packing: Packing[Box], solids: list[PlacedSolid], scale: float) -> str:
    """Text of the bodies file: ``index mineral n radius`` and the coordinates, a line a body.

    The coordinates are the packing's times ``scale``, less the box's lower
    corner in a periodic box (YADE's cell starts at the origin).
    """
    box = packing.domain
    origin = box.bounds().reshape(3, 2)[:, 0] if box.periodic else np.zeros(3)
    lines = [
        f"# bodies of {scene_label(packing)} (seed {packing.seed}), regopack "
        f"{packing.version}: draw index, mineral index, vertices, radius, coordinates",
        f"# coordinates = (packing lengths ({length_unit(packing)}) - origin) x {_num(scale)}, "
        f"origin {' '.join(_num(x) for x in origin)}",
    ]
    for p in solids:
        points = (p.centre[None, :] if not p.loops else p.world) - origin
        coords = " ".join(_num(x) for x in (points * scale).ravel())
        radius = p.rounding * scale if not p.loops else 0.0
        lines.append(
            f"{p.index} {int(packing.mineral[p.index])} {len(points)} {_num(radius)} {coords}"
        )
    return "\n".join(lines) + "\n"


def _dict_text(names: list[str], values: list[float] | np.ndarray) -> str:
    """Return a Python dict literal of values by mineral name."""
    return "{" + ", ".join(f"{n!r}: {_num(v)}" for n, v in zip(names, values, strict=False)) + "}"


def _script(
    packing: Packing[Box],
    path: Path,
    cfg: YadeConfig,
    *,
    scale: float,
    names: list[str],
    density: np.ndarray,
    friction: list[float],
    kappa_length: float,
    verlet: float,
    spheres: bool,
    polyhedra: bool,
    d_min: float,
) -> str:
    """Text of the YADE script (see the module documentation)."""
    box = packing.domain
    cylinder = _side_wall(box, d_min, scale)
    lo, hi = box.bounds().reshape(3, 2).T
    size = (hi - lo) * scale
    lower = np.zeros(3) if box.periodic else lo * scale
    upper = size if box.periodic else hi * scale
    bounds = ", ".join(_num(x) for x in lower), ", ".join(_num(x) for x in upper)
    unit = length_unit(packing)
    engines = _engines(spheres, polyhedra, facets=cylinder is not None)
    head = [
        f"# YADE scene of {bodies_path(path).name}, written by regopack {packing.version} "
        f"(scene {scene_label(packing)}, seed {packing.seed}).",
        f"# Build the scene and exit:    yade -n -x {path.name}",
        f"# Build it and run 5000 steps: yade -n -x {path.name} --run 5000 [--gravity 9.81]",
        f"#   (then {state_path(path).name}: every body's centroid, displacement and rotation)",
        f"# From a YADE script of yours: exec(open({path.name!r}).read()), then O.run(...) and",
        "#   save_state('state.txt'); it builds the scene and runs RUN_STEPS steps (0: none).",
        f"# Lengths: packing lengths ({unit}) x {_num(scale)}"
        + (
            f", less the lower corner ({', '.join(_num(x) for x in lo)}) in the periodic box."
            if box.periodic
            else "."
        ),
        "",
        "import argparse",
        "import math",
        "import os",
        "import sys",
        "",
        "from yade import *  # noqa: F403 (O, the bodies, engines and materials)",
        "from yade import geom, polyhedra_utils, utils",
        "",
        f"RUN_STEPS = {cfg.steps}  # steps run after building (--run)",
        f"GRAVITY = {_num(cfg.gravity)}  # acceleration along -z (--gravity)",
        f"YOUNG = {_num(cfg.youngs_modulus)}  # Young's modulus of grains and walls (--young)",
        f"POISSON = {_num(cfg.poisson_ratio)}  # Poisson's ratio",
        f"DAMPING = {_num(cfg.damping)}  # NewtonIntegrator's local damping (--damping)",
        f"DT_FRACTION = {_num(cfg.dt_fraction)}  # of the shortest contact time (--dt-fraction)",
        f"VOLUMETRIC_LENGTH = {_num(kappa_length)}  # polyhedra: stiffness per overlap volume "
        "YOUNG / VOLUMETRIC_LENGTH",
        f"DENSITY = {_dict_text(names, density)}  # by mineral",
        f"FRICTION = {_dict_text(names, friction)}  # Coulomb coefficient, by mineral",
        f"WALL_FRICTION = {_num(cfg.friction)}",
        f"VERLET = {_num(verlet)}  # the collider's margin: 5 % of the smallest diameter",
        f"PERIODIC = {box.periodic}",
        f"SPHERES = {spheres}  # bodies of each kind present",
        f"POLYHEDRA = {polyhedra}",
        f"LOWER = ({bounds[0]})  # box corners" + (" (of the cylinder's box)" if cylinder else ""),
        f"UPPER = ({bounds[1]})",
        *(
            [
                f"CYLINDER = ({', '.join(_num(v) for v in cylinder[:3])}, {int(cylinder[3])})  "
                "# axis x, y, radius and facets of the side wall",
            ]
            if cylinder
            else ["CYLINDER = None  # no side wall: a box"]
        ),
        f"BODIES = {bodies_path(path).name!r}",
        f"STATE = {state_path(path).name!r}",
        f"STATE_FORMAT = {STATE_FORMAT!r}",
        f"LENGTH_SCALE = {_num(scale)}",
        "",
    ]
    return "\n".join(head) + _SCRIPT_BODY.replace("@ENGINES@", engines)


def _side_wall(domain: object, d_min: float, scale: float) -> tuple[float, ...] | None:
    """Return ``(cx, cy, R, N)`` of a cylinder's side wall in the script's lengths, or ``None``.

    ``N`` flat facets circumscribe the circle of radius ``R``: their corners
    stand ``R (1 / cos(π / N) - 1)`` outside it, at most :data:`FACET_GAP` ×
    ``d_min`` (and at least :data:`MIN_SEGMENTS` facets).
    """
    if not isinstance(domain, Cylinder):
        return None
    radius = domain.radius
    gap = FACET_GAP * d_min
    segments = max(MIN_SEGMENTS, math.ceil(math.pi / math.acos(radius / (radius + gap))))
    return (domain.cx * scale, domain.cy * scale, radius * scale, float(segments))


def _engines(spheres: bool, polyhedra: bool, facets: bool = False) -> str:
    """Return the script's engines: the functors the bodies present need, and no other."""
    bounds = []
    geoms = []
    physics = []
    laws = []
    if spheres:
        bounds.append("Bo1_Sphere_Aabb()")
        geoms += ["Ig2_Sphere_Sphere_ScGeom()", "Ig2_Wall_Sphere_ScGeom()"]
        geoms += ["Ig2_Facet_Sphere_ScGeom()"] if facets else []
        physics.append("Ip2_FrictMat_FrictMat_FrictPhys()")
        laws.append("Law2_ScGeom_FrictPhys_CundallStrack()")
    if polyhedra:
        bounds.append("Bo1_Polyhedra_Aabb()")
        geoms += [
            "Ig2_Polyhedra_Polyhedra_PolyhedraGeom()",
            "Ig2_Wall_Polyhedra_PolyhedraGeom()",
        ]
        geoms += ["Ig2_Facet_Polyhedra_PolyhedraGeom()"] if facets else []
        physics.append("Ip2_PolyhedraMat_PolyhedraMat_PolyhedraPhys()")
        laws.append("Law2_PolyhedraGeom_PolyhedraPhys_Volumetric()")
    if spheres and polyhedra:
        geoms.append("Ig2_Sphere_Polyhedra_ScGeom()")
        physics.append("Ip2_FrictMat_PolyhedraMat_FrictPhys()")
    bounds.append("Bo1_Wall_Aabb()")
    if facets:
        bounds.append("Bo1_Facet_Aabb()")

    def listed(items: list[str]) -> str:
        return "[" + ", ".join(items) + "]"

    return "\n".join(
        [
            "        ForceResetter(),",
            f"        InsertionSortCollider({listed(bounds)}, verletDist=verlet),",
            "        InteractionLoop(",
            f"            {listed(geoms)},",
            f"            {listed(physics)},",
            f"            {listed(laws)},",
            "        ),",
            "        NewtonIntegrator(damping=DAMPING, gravity=(0, 0, -GRAVITY)),",
        ]
    )


_SCRIPT_BODY = '''
DRAW_INDEX = {}
"""The packing's draw index of each body, by YADE body id."""
FOLDER = "."
"""The folder of the bodies file read, where save_state writes the state by default."""
SPHERE_MASK, POLYHEDRA_MASK = 0b101, 0b110
"""Collision masks: spheres and polyhedra meet each other (bit 3) ..."""
SPHERE_WALL_MASK, POLYHEDRA_WALL_MASK = 0b001, 0b010
"""... and each kind the walls of its own material."""


def _options(argv):
    """Read --run, --gravity, --young, --damping and --dt-fraction (other arguments are left)."""
    parser = argparse.ArgumentParser(add_help=False)
    parser.add_argument("--run", type=int, default=None)
    parser.add_argument("--gravity", type=float, default=None)
    parser.add_argument("--young", type=float, default=None)
    parser.add_argument("--damping", type=float, default=None)
    parser.add_argument("--dt-fraction", type=float, default=None)
    return parser.parse_known_args(argv)[0]


def _bodies_file():
    """The bodies file: REGOPACK_BODIES when a script of yours set it before exec, else
    the file of that name beside the script yade runs, else in the working folder."""
    given = globals().get("REGOPACK_BODIES")
    if given:
        return given
    folder = os.path.dirname(os.path.abspath(sys.argv[0])) if sys.argv and sys.argv[0] else ""
    there = os.path.join(folder, BODIES)
    return there if folder and os.path.exists(there) else BODIES


def _material(polyhedra, friction, density, label):
    """A material of spheres (FrictMat) or of polyhedra (PolyhedraMat), appended to O.materials."""
    angle = math.atan(friction)
    if polyhedra:
        material = PolyhedraMat(young=YOUNG / VOLUMETRIC_LENGTH, poisson=POISSON,
                                frictionAngle=angle, density=density, label=label)
    else:
        material = FrictMat(young=YOUNG, poisson=POISSON, frictionAngle=angle, density=density,
                            label=label)
    O.materials.append(material)
    return material


def _materials():
    """Per mineral, a material for its spheres and one for its polyhedra (those present),
    and the walls' for each kind present."""
    kinds = {}
    for name in DENSITY:
        kinds[name] = tuple(
            _material(polyhedra, FRICTION[name], DENSITY[name], kind + " " + name)
            if present else None
            for polyhedra, kind, present in ((False, "spheres", SPHERES),
                                             (True, "polyhedra", POLYHEDRA))
        )
    walls = [(_material(polyhedra, WALL_FRICTION, 1000.0, "walls of " + kind), mask)
             for polyhedra, kind, mask, present in (
                 (False, "spheres", SPHERE_WALL_MASK, SPHERES),
                 (True, "polyhedra", POLYHEDRA_WALL_MASK, POLYHEDRA)) if present]
    return kinds, walls


def _bodies(kinds):
    """Read the bodies file: every placed particle as a YADE body, in draw order."""
    names = list(DENSITY)
    bodies = []
    global FOLDER
    source = _bodies_file()
    FOLDER = os.path.dirname(os.path.abspath(source))
    with open(source) as lines:
        for line in lines:
            if line.startswith("#") or not line.strip():
                continue
            words = line.split()
            index, mineral, n, radius = int(words[0]), int(words[1]), int(words[2]), float(words[3])
            xyz = [float(w) for w in words[4:4 + 3 * n]]
            sphere_mat, polyhedra_mat = kinds[names[mineral]]
            if radius > 0:
                body = utils.sphere(xyz[:3], radius, material=sphere_mat, mask=SPHERE_MASK)
            else:
                points = [Vector3(*xyz[3 * k:3 * k + 3]) for k in range(n)]
                body = polyhedra_utils.polyhedra(polyhedra_mat, v=points, mask=POLYHEDRA_MASK)
                if len(body.shape.v) < 4:
                    raise RuntimeError(
                        "YADE could not build polyhedron %d from its vertices (%d kept): "
                        "export with a length_scale that keeps coordinates near 1" % (
                            index, len(body.shape.v)))
            bodies.append((index, body))
    ids = O.bodies.append([body for _, body in bodies])
    for body_id, (index, body) in zip(ids, bodies):
        body.state.refPos = body.state.pos
        body.state.refOri = body.state.ori
        DRAW_INDEX[body_id] = index


def _walls(walls):
    """The six walls of a walled box (sense: towards the inside), YADE's periodic cell, or
    a walled cylinder: its floor and lid (walls) and its side wall (facets).

    Spheres and polyhedra meet walls of their own material (the masks keep the
    others apart): YADE has no functor for a sphere and a wall of polyhedra."""
    if PERIODIC:
        O.periodic = True
        O.cell.setBox(UPPER)
        return
    for material, mask in walls:
        for axis in ((2,) if CYLINDER else range(3)):
            for where, sense in ((LOWER[axis], 1), (UPPER[axis], -1)):
                O.bodies.append(utils.wall(where, axis=axis, sense=sense, material=material,
                                           mask=mask))
        if CYLINDER:
            O.bodies.append(side_wall(material, mask))


def side_wall(material, mask):
    """The cylinder's side wall: flat facets from the floor to the lid whose planes touch
    the circle of radius R at their middles, so that the polygon holds the whole cylinder
    (a particle inside the cylinder overlaps no facet)."""
    cx, cy, radius, segments = CYLINDER
    corners = radius / math.cos(math.pi / segments)
    centre = (cx, cy, 0.5 * (LOWER[2] + UPPER[2]))
    return geom.facetCylinder(centre, corners, UPPER[2] - LOWER[2], segmentsNumber=segments,
                              wallMask=4, material=material, mask=mask)


def time_step():
    """DT_FRACTION of the shortest characteristic time of a body on its stiffest contact."""
    times = []
    kappa = YOUNG / VOLUMETRIC_LENGTH
    for body in O.bodies:
        if isinstance(body.shape, Polyhedra):
            size = 2.0 * max(v.norm() for v in body.shape.v)
            times.append(math.sqrt(body.state.mass / (kappa * size * size)))
    if any(isinstance(body.shape, Sphere) for body in O.bodies):
        times.append(utils.PWaveTimeStep())
    return DT_FRACTION * min(times) if times else O.dt


def build():
    """Create the materials, the walls or the cell, the bodies, the engines and the step."""
    kinds, walls = _materials()
    _walls(walls)
    _bodies(kinds)
    verlet = VERLET
    O.engines = [
@ENGINES@
    ]
    O.dt = time_step()


def save_state(path=None):
    """Write every body's centroid, displacement and rotation since the packing, in draw order."""
    rows = []
    for body_id, index in sorted(DRAW_INDEX.items(), key=lambda item: item[1]):
        state = O.bodies[body_id].state
        turn = state.ori.toRotationMatrix() * state.refOri.toRotationMatrix().transpose()
        moved = state.pos - state.refPos
        values = list(state.pos) + list(moved) + [turn[i, j] for i in range(3) for j in range(3)]
        rows.append(str(index) + " " + " ".join(repr(float(x)) for x in values))
    target = path or os.path.join(FOLDER, STATE)
    with open(target + ".part", "w") as out:
        out.write(STATE_FORMAT + "\\n")
        out.write("# steps %d, time %r, dt %r, length scale %r, bodies %d\\n"
                  % (O.iter, O.time, O.dt, LENGTH_SCALE, len(rows)))
        out.write("# index x y z dx dy dz r11 r12 r13 r21 r22 r23 r31 r32 r33\\n")
        out.write("".join(row + "\\n" for row in rows))
    os.replace(target + ".part", target)
    return target


_given = _options(sys.argv[1:])
RUN_STEPS = _given.run if _given.run is not None else RUN_STEPS
GRAVITY = _given.gravity if _given.gravity is not None else GRAVITY
YOUNG = _given.young if _given.young is not None else YOUNG
DAMPING = _given.damping if _given.damping is not None else DAMPING
DT_FRACTION = _given.dt_fraction if _given.dt_fraction is not None else DT_FRACTION
build()
print("regopack: %d bodies, dt %r" % (len(DRAW_INDEX), O.dt))
if RUN_STEPS > 0:
    O.run(RUN_STEPS, True)
    print("regopack: %d steps run, state in %s" % (O.iter, save_state()))
'''
