"""LIGGGHTS export: a data file of granular spheres and an input script that runs it.

LIGGGHTS, the discrete-element code built on LAMMPS, models grains as
spheres: ``atom_style granular`` gives every atom a diameter and a density.
A 3D packing whose particles are all spheres is written as such atoms, the
way the ``lammps`` exporter writes its granular spheres
(:mod:`~regopack.plugins.exporters.granular_common`): ``<stem>.data`` lists
``id type diameter density x y z`` (atom type = mineral index + 1, density
= its mineral's), and ``<stem>.in`` is an input script that reads it and
runs:

- the material of every atom type as ``fix property/global``: Young's
  modulus, Poisson's ratio, and the coefficients of restitution and friction
  of every pair of types;
- ``pair_style gran model hertz tangential history``: Hertz contacts with
  their damping from the restitution coefficient and tangential history
  (Coulomb friction);
- ``fix nve/sphere``; walls of the same contact model (``fix wall/gran ...
  primitive``) on the six faces of a walled box, or ``boundary p p p`` for a
  periodic box; in a walled cylinder, its side wall (``primitive ...
  zcylinder R cx cy``) and the planes of its floor and lid (``zplane``);
- a time step of ``rayleigh_fraction`` (0.2 by default) of the Rayleigh time
  of the sphere whose Rayleigh time is shortest, computed in the script from
  the variables ``E`` and ``nu``, so it follows them when they are changed
  with ``-var``;
- gravity along -z (``g``, 0 by default: off), ``steps`` steps, and at the
  end a dump of every atom's final position and its displacement from the
  packing, ``<stem>.final.dump``.

Lengths are the packing's times ``length_scale``, converted by default to
the length unit of ``units``; the data file's comment names the packing's
unit and the factor. Polyhedra have no counterpart among LIGGGHTS' granular
atoms (its multisphere and superquadric models are other shapes), and 2D
packings none either: both are refused in one line that names the exporters
that take them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

from regopack.base.errors import ConfigError, ExportError
from regopack.base.units import length_unit
from regopack.geometry.domain import Box, Cylinder
from regopack.packing.core import Packing
from regopack.plugins.exporters.export_common import Analyses, _num, _write_text, scene_label
from regopack.plugins.exporters.granular_common import (
    RAYLEIGH_FRACTION,
    GranularSpheres,
    default_length_scale,
    granular_spheres,
    material_variable_lines,
    rayleigh_step_lines,
    read_sphere_dump,
    sphere_data,
)
from regopack.registry.interfaces import Exporter

__all__ = [
    "POLYHEDRA_EXPORTERS",
    "LiggghtsConfig",
    "LiggghtsExporter",
    "dump_path",
    "script_path",
]

POLYHEDRA_EXPORTERS = "gsd, image, lammps, slice, stl, vtk, yade"
"""The built-in exporters that write 3D packings of polyhedra, named when one is refused."""


def script_path(path: Path) -> Path:
    """Return the input script written beside the data file ``path``: ``<stem>.in``.

    Examples
    --------
    >>> script_path(Path("runs/spheres/packing.data")).as_posix()
    'runs/spheres/packing.in'
    """
    return Path(path).with_suffix(".in")


def dump_path(path: Path) -> Path:
    """Return the dump that the input script writes at the end of its run: ``<stem>.final.dump``.

    Examples
    --------
    >>> dump_path(Path("runs/spheres/packing.data")).as_posix()
    'runs/spheres/packing.final.dump'
    """
    return Path(path).with_suffix(".final.dump")


class LiggghtsConfig(BaseModel):
    """Parameters of the LIGGGHTS exporter (3D packings of spheres).

    Lengths of the packing are multiplied by ``length_scale`` and written in
    the length unit of ``units``; every other quantity is in that unit system.
    By default ``length_scale`` converts the scene's ``length_unit`` to the
    length unit of ``units`` (1 for micrometres and ``units = "micro"``).
    With the default ``units = "micro"``, masses are in picograms, times in
    microseconds, pressures in kPa (so a Young's modulus of 1e5 is 0.1 GPa)
    and a ``density`` of 3.1 pg/µm³ is 3.1 g/cm³. The defaults are those of
    the ``lammps`` exporter's granular spheres.
    """

    model_config = ConfigDict(extra="forbid", strict=True)

    units: Literal["micro", "si", "cgs", "nano"] = Field(
        "micro", description="LIGGGHTS unit style named in the input script."
    )
    length_scale: float | None = Field(
        None,
        gt=0,
        allow_inf_nan=False,
        description=(
            "Factor from the packing's length unit to the length unit of `units` (µm, m, cm, "
            "nm); default: from the scene's length_unit (1 for 'µm' and units 'micro')."
        ),
    )
    density: float = Field(
        3.1,
        gt=0,
        allow_inf_nan=False,
        description=(
            "Mass per unit volume of the grains (3.1 pg/µm³ = 3.1 g/cm³ in units micro; "
            "3100 kg/m³ in units si)."
        ),
    )
    mineral_density: dict[str, Annotated[float, Field(gt=0, allow_inf_nan=False)]] = Field(
        default_factory=dict,
        description=(
            "Density of the grains of a mineral, by mineral name; minerals not listed get "
            "`density`."
        ),
    )
    youngs_modulus: float = Field(
        1.0e5,
        gt=0,
        allow_inf_nan=False,
        description=(
            "Young's modulus E of the grains and walls (pressure; 1e5 = 0.1 GPa in units "
            "micro, a softened grain: 7e7 is basalt's 70 GPa; 1e8 Pa in units si)."
        ),
    )
    poisson_ratio: float = Field(
        0.25, gt=0, lt=0.5, description="Poisson's ratio of the grains and walls (no unit)."
    )
    restitution: float = Field(
        0.5,
        gt=0,
        le=1,
        description="Normal coefficient of restitution of every pair of grains (no unit).",
    )
    friction: float = Field(
        0.5, ge=0, allow_inf_nan=False, description="Coulomb friction coefficient mu (no unit)."
    )
    gravity: float = Field(
        0.0,
        ge=0,
        allow_inf_nan=False,
        description=(
            "Acceleration of gravity along -z (length/time²; 9.81 in units si, 9.81e-6 "
            "µm/µs² in units micro); 0: none."
        ),
    )
    steps: int = Field(10000, ge=0, description="Time steps the input script runs.")
    rayleigh_fraction: float = Field(
        RAYLEIGH_FRACTION,
        gt=0,
        le=1,
        description=(
            "Time step as a fraction of the Rayleigh time of the sphere whose Rayleigh time is "
            "shortest (safety factor; no unit)."
        ),
    )


class LiggghtsExporter(Exporter[Packing[Box]]):
    """LIGGGHTS data file (``atom_style granular``) and input script of a packing of spheres.

    One atom per placed sphere, in draw order (atom IDs 1, 2, …): atom type
    = mineral index + 1, its diameter, its mineral's density and its centre
    (wrapped into a periodic box). See the module documentation for the
    script.
    """

    suffix = ".data"

    def __init__(self, config: LiggghtsConfig | None = None) -> None:
        self.config = config or LiggghtsConfig()

    def companions(self, path: Path) -> tuple[Path, ...]:
        """Return the input script written beside the data file."""
        return (script_path(path),)

    def read_state(self, packing: Packing[Box], path: Path) -> Packing[Box]:
        """Return ``packing`` as the run whose final dump (``<stem>.final.dump``) is ``path``.

        Every sphere's centre is the dump's, divided by this exporter's length
        scale (so give the parameters of the export); see
        :func:`~regopack.plugins.exporters.granular_common.read_sphere_dump`.
        """
        cfg = self.config
        if packing.dimension != 3:
            raise ConfigError("exporter 'liggghts': reads the states of 3D packings only")
        scale = (
            default_length_scale(packing, cfg.units)
            if cfg.length_scale is None
            else cfg.length_scale
        )
        return read_sphere_dump(packing, path, cfg, scale, "LIGGGHTS")

    def export(self, packing: Packing[Box], path: Path, *, analyses: Analyses = None) -> Path:
        """Write the data file and the input script; return the data file's path.

        Raises
        ------
        ExportError
            One line, when the packing is not a 3D packing of spheres alone.
        """
        cfg = self.config
        path = Path(path)
        if packing.dimension != 3:
            raise ExportError(
                "exporter 'liggghts' writes 3D packings of spheres; 2D packings: csv, gsd, "
                "image, json, lammps, svg, vtk"
            )
        s = (
            default_length_scale(packing, cfg.units)
            if cfg.length_scale is None
            else cfg.length_scale
        )
        spheres = granular_spheres(packing, cfg, s, exporter="liggghts")
        if spheres is None:
            raise ExportError(
                "exporter 'liggghts' writes packings of spheres alone (LIGGGHTS' granular atoms "
                f"are spheres), and this packing has polyhedra; polyhedra: {POLYHEDRA_EXPORTERS}"
            )
        _write_text(path, sphere_data(packing, spheres, cfg, "LIGGGHTS", "granular"))
        _write_text(script_path(path), self._script(packing, path, spheres))
        return path

    def _script(self, packing: Packing[Box], path: Path, g: GranularSpheres) -> str:
        cfg = self.config
        model = "model hertz tangential history"
        n_types = max(1, len(packing.mineral_names), int(packing.mineral.max(initial=-1)) + 1)

        def per_type(name: str, var: str) -> str:
            return f"fix          {name} all property/global {var}"

        planes = "z" if isinstance(packing.domain, Cylinder) else "xyz"
        walls = [
            f"fix          wall_{axis}{side} all wall/gran {model} primitive type 1 "
            f"{axis}plane {_num(bound['xyz'.index(axis)])}"
            for axis in planes
            for side, bound in (("lo", g.lo), ("hi", g.hi))
        ]
        where = "periodic in x, y and z." if g.periodic else "walls on all six sides."
        if isinstance(packing.domain, Cylinder):
            d = packing.domain
            walls.insert(
                0,
                f"fix          wall_side all wall/gran {model} primitive type 1 zcylinder "
                + " ".join(_num(v * g.scale) for v in (d.radius, d.cx, d.cy)),
            )
            where = "a walled cylinder (side wall, floor and lid)."
        unit = length_unit(packing)
        return "\n".join(
            [
                f"# LIGGGHTS input for {path.name}, written by regopack {packing.version} "
                f"(scene {scene_label(packing)}, seed {packing.seed}).",
                f"# Run it in this folder: liggghts -in {script_path(path).name}",
                "# Change a parameter with -var, e.g. -var E 7e7 -var steps 50000.",
                f"# Domain: {where}",
                f"# Lengths: packing lengths ({unit}) x {_num(g.scale)}, units {cfg.units}.",
                f"# At the end: {dump_path(path).name}, id type x y z radius mass and the "
                "displacement from the packing (dx dy dz |d|).",
                "",
                *material_variable_lines(cfg),
                *rayleigh_step_lines(g.r_rho, cfg.rayleigh_fraction),
                f"variable skin  equal {_num(0.1 * g.d_min)}",
                "",
                f"units        {cfg.units}",
                "atom_style   granular",
                "atom_modify  map array",
                f"boundary     {'p p p' if g.periodic else 'f f f'}",
                "newton       off",
                "communicate  single vel yes",
                f"read_data    {path.name}",
                "",
                "neighbor     ${skin} bin",
                "neigh_modify every 1 delay 0 check yes",
                "",
                f"# the material of each of the {n_types} atom types (minerals), and of the walls",
                per_type("m1", "youngsModulus peratomtype" + " ${E}" * n_types),
                per_type("m2", "poissonsRatio peratomtype" + " ${nu}" * n_types),
                per_type(
                    "m3",
                    f"coefficientRestitution peratomtypepair {n_types}" + " ${e_n}" * n_types**2,
                ),
                per_type(
                    "m4", f"coefficientFriction peratomtypepair {n_types}" + " ${mu}" * n_types**2
                ),
                "",
                f"pair_style   gran {model}",
                "pair_coeff   * *",
                "timestep     ${dt}",
                "",
                "fix          integrate all nve/sphere",
                *([] if g.periodic else walls),
                "fix          gravi all gravity ${g} vector 0 0 -1",
                "compute      disp all displace/atom",
                "",
                "thermo_style custom step atoms ke dt",
                "thermo       1000",
                "thermo_modify lost error norm no",
                "run          ${steps}",
                f"write_dump   all custom {dump_path(path).name} id type x y z radius mass "
                'c_disp[1] c_disp[2] c_disp[3] c_disp[4] modify sort id format "%d %d'
                + " %.17g" * 9
                + '"',
                "",
            ]
        )
