"""What the exporters of granular spheres share: units, densities, the spheres, the time step.

A 3D packing whose particles are all spheres is written by the ``lammps``
exporter (``atom_style sphere``) and the ``liggghts`` exporter (``atom_style
granular``) as the same granular spheres: one atom per sphere with its
diameter, its mineral's density and its centre, in lengths converted to the
length unit of the unit style (:func:`default_length_scale`). Both scripts
take their time step as :data:`RAYLEIGH_FRACTION` of the Rayleigh time of the
sphere whose Rayleigh time is shortest (:func:`rayleigh_step_lines`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from regopack.base.errors import ConfigError, ExportError
from regopack.base.units import conversion, length_unit
from regopack.geometry.domain import Box
from regopack.packing.core import Packing
from regopack.plugins.exporters.export_common import _num, scene_label
from regopack.plugins.exporters.solid_export_common import placed_solids

__all__ = [
    "RAYLEIGH_FRACTION",
    "UNIT_STYLE_LENGTH",
    "Densities",
    "GranularSpheres",
    "check_atoms",
    "check_finite",
    "default_length_scale",
    "density_note",
    "granular_spheres",
    "material_variable_lines",
    "mineral_densities",
    "mineral_values",
    "rayleigh_step_lines",
    "read_dump",
    "read_sphere_dump",
    "sphere_data",
]

FloatArray = NDArray[np.float64]

RAYLEIGH_FRACTION = 0.2
"""Time step of granular spheres as a fraction of the Rayleigh time of the smallest sphere."""

UNIT_STYLE_LENGTH: dict[str, str | None] = {
    "micro": "µm",
    "si": "m",
    "cgs": "cm",
    "nano": "nm",
    "lj": None,
}
"""Length unit of each LAMMPS unit style (``lj``: none, lengths written as they are)."""


class Densities(Protocol):
    """The density fields of an exporter's configuration."""

    @property
    def density(self) -> float:
        """Density of the grains of every mineral not in ``mineral_density``."""
        ...

    @property
    def mineral_density(self) -> dict[str, float]:
        """Density of the grains of a mineral, by mineral name."""
        ...


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


def mineral_densities(packing: Any, config: Densities, exporter: str = "lammps") -> FloatArray:
    """Density of the grains of each mineral: ``density`` or its entry of ``mineral_density``.

    Raises
    ------
    ConfigError
        One line, when ``mineral_density`` names a mineral the packing does not have.
    """
    return mineral_values(
        packing, config.density, config.mineral_density, "mineral_density", exporter
    )


def mineral_values(
    packing: Any, default: float, by_name: dict[str, float], field: str, exporter: str
) -> FloatArray:
    """Return a value per mineral index: its ``by_name`` entry (field ``field``), else ``default``.

    Raises
    ------
    ConfigError
        One line, when ``by_name`` names a mineral the packing does not have.
    """
    names = [str(n) for n in packing.mineral_names]
    unknown = sorted(set(by_name) - set(names))
    if unknown:
        raise ConfigError(
            f"exporter {exporter!r}: {field} names {unknown[0]!r}, not a mineral of this "
            f"packing (its minerals: {', '.join(names)})"
        )
    n = max(1, len(names), int(packing.mineral.max(initial=-1)) + 1)
    out = np.full(n, default, dtype=np.float64)
    for k, name in enumerate(names):
        out[k] = by_name.get(name, default)
    return out


def check_finite(given: str, checks: list[tuple[str, FloatArray]]) -> None:
    """Refuse masses and moments that are not positive finite numbers (subnormal ones too)."""
    tiny = np.finfo(np.float64).tiny  # subnormal numbers lose their precision
    for what, values in checks:
        if values.size and not (np.isfinite(values).all() and (values >= tiny).all()):
            raise ExportError(
                f"{given}: a body's {what} is not a positive finite number; give values nearer 1"
            )


def density_note(cfg: Densities) -> str:
    """Name the density in a comment of the data file: one number, or one per mineral."""
    if not cfg.mineral_density:
        return _num(cfg.density)
    listed = ", ".join(f"{k} {_num(v)}" for k, v in sorted(cfg.mineral_density.items()))
    return f"density ({listed}; others {_num(cfg.density)})"


@dataclass(frozen=True)
class GranularSpheres:
    """The spheres of a packing of spheres as granular atoms (LAMMPS, LIGGGHTS) read them.

    ``index`` is the draw index of each sphere's particle; ``radius``,
    ``position`` (its centre, wrapped into a periodic box), ``lo``, ``hi`` and
    ``d_min`` are in the script's lengths (``scale`` × the packing's),
    ``density`` is each sphere's mineral's and ``r_rho`` the least ``radius ×
    √density``, which sets the Rayleigh time step.
    """

    index: NDArray[np.int64]
    radius: FloatArray
    position: FloatArray
    density: FloatArray
    scale: float
    lo: FloatArray
    hi: FloatArray
    periodic: bool

    @property
    def d_min(self) -> float:
        """Smallest diameter."""
        return float(2.0 * self.radius.min()) if self.radius.size else 1.0

    @property
    def r_rho(self) -> float:
        """Least ``radius × √density``: the sphere of shortest Rayleigh time."""
        return float(np.min(self.radius * np.sqrt(self.density))) if self.radius.size else 1.0


def granular_spheres(
    packing: Packing[Box], config: Densities, scale: float = 1.0, exporter: str = "lammps"
) -> GranularSpheres | None:
    """Return the placed spheres of a 3D packing of spheres alone; ``None`` if any is no sphere.

    Raises
    ------
    ExportError
        One line, when ``scale`` and the densities give a mass that is no
        positive finite number.
    """
    solids = placed_solids(packing, exporter, spheres=True)
    if not solids or any(p.rounding <= 0 or len(p.loops) for p in solids):
        return None
    index = np.array([p.index for p in solids], dtype=np.int64)
    box = packing.domain
    lo, hi = box.bounds().reshape(3, 2).T * scale
    position = np.array([p.centre for p in solids], dtype=np.float64) * scale
    if box.periodic:
        position = lo + np.mod(position - lo, hi - lo)
    radius = np.array([p.rounding for p in solids], dtype=np.float64) * scale
    density = mineral_densities(packing, config, exporter)[packing.mineral[index]]
    with np.errstate(over="ignore", under="ignore"):  # checked below
        mass = 4.0 / 3.0 * np.pi * radius**3 * density
    check_finite(f"length_scale = {scale}, density = {density_note(config)}", [("mass", mass)])
    return GranularSpheres(index, radius, position, density, scale, lo, hi, box.periodic)


def sphere_data(
    packing: Packing[Box], g: GranularSpheres, config: Densities, program: str, style: str
) -> str:
    """Text of the data file of the spheres ``g``: ``id type diameter density x y z`` a line.

    ``program`` names the program in the first line and ``style`` the atom
    style (``LAMMPS`` and ``sphere``, ``LIGGGHTS`` and ``granular``: both read
    the same columns); atom type = mineral index + 1. A comment names the
    packing's length unit and the factor that converted it.
    """
    n = g.index.size
    n_types = max(1, len(packing.mineral_names), int(packing.mineral.max(initial=-1)) + 1)
    atoms = [
        f"{k + 1} {int(packing.mineral[j]) + 1} {_num(2.0 * g.radius[k])} "
        f"{_num(g.density[k])} " + " ".join(_num(x) for x in g.position[k])
        for k, j in enumerate(g.index.tolist())
    ]
    lines = [
        f"{program} data file from regopack {packing.version}: scene "
        f"{scene_label(packing)}, seed {packing.seed}, atom_style {style}",
        "",
        "# granular spheres: id, atom type (mineral index + 1), diameter, density, centre",
        f"# lengths = packing lengths ({length_unit(packing)}) x {_num(g.scale)}; "
        f"mass = sphere volume x {density_note(config)}",
        "",
        f"{n} atoms",
        f"{n_types} atom types",
        "",
        *(f"{_num(g.lo[i])} {_num(g.hi[i])} {a}lo {a}hi" for i, a in enumerate("xyz")),
        "",
        f"Atoms # {style}",
        "",
        *atoms,
    ]
    return "\n".join(lines) + "\n"


class Materials(Protocol):
    """The contact and run fields of a granular exporter's configuration."""

    steps: int
    youngs_modulus: float
    poisson_ratio: float
    restitution: float
    friction: float
    gravity: float


def material_variable_lines(cfg: Materials) -> list[str]:
    """Script lines that set the run's length and the contact variables, each changeable by -var."""
    return [
        f"variable steps index {cfg.steps}",
        f"variable E     index {_num(cfg.youngs_modulus)}   # Young's modulus (pressure)",
        f"variable nu    index {_num(cfg.poisson_ratio)}   # Poisson's ratio",
        f"variable e_n   index {_num(cfg.restitution)}   # coefficient of restitution",
        f"variable mu    index {_num(cfg.friction)}   # friction coefficient",
        f"variable g     index {_num(cfg.gravity)}   # gravity along -z (acceleration)",
    ]


def rayleigh_step_lines(r_rho: float, fraction: float = RAYLEIGH_FRACTION) -> list[str]:
    """Script lines that set the variable ``dt``: ``fraction`` × the shortest Rayleigh time.

    The Rayleigh time of a sphere of radius r and density ρ is
    π r √(ρ / G) / (0.1631 ν + 0.8766), G = E / (2 (1 + ν)) the shear
    modulus; the lines read E and ν from the variables ``E`` and ``nu``, so
    the step follows them when they are changed with ``-var``. ``r_rho`` is
    the least r √ρ (:attr:`GranularSpheres.r_rho`).

    Examples
    --------
    >>> print(rayleigh_step_lines(2.0)[-1])
    variable dt    equal 0.2*PI*v_r_rho/sqrt(v_G)/(0.1631*v_nu+0.8766)   # of its Rayleigh time
    """
    return [
        f"variable r_rho equal {_num(r_rho)}   "
        "# radius x sqrt(density) of the sphere of shortest Rayleigh time",
        "variable G     equal v_E/(2*(1+v_nu))   # shear modulus",
        f"variable dt    equal {_num(fraction)}*PI*v_r_rho/sqrt(v_G)"
        "/(0.1631*v_nu+0.8766)   # of its Rayleigh time",
    ]


def read_sphere_dump(
    packing: Packing[Box], path: Path, config: Densities, scale: float, program: str
) -> Packing[Box]:
    """Return ``packing`` as the run whose final dump of granular spheres is ``path`` left it.

    The dump (``write_dump ... custom ... id type x y z radius ...`` of the
    scripts of :func:`sphere_data`'s atoms, sorted by id) gives every sphere's
    centre; atom ``k`` is the ``k``-th placed sphere in draw order. Lengths
    are divided by ``scale``; the dump's time step goes into the packing's
    ``stats`` as ``settled_steps``.

    Raises
    ------
    PackingFileError
        One line naming ``path``, when it is no dump of this packing's spheres.
    """
    from regopack.base.errors import PackingError, PackingFileError
    from regopack.packing.motion import moved

    step, columns, table = read_dump(path, program)
    if columns[:6] != ["id", "type", "x", "y", "z", "radius"]:
        raise PackingFileError(
            f"{path}: its atoms' columns start with {' '.join(columns[:6])!r}, not "
            f"'id type x y z radius' as the script's final dump"
        )
    spheres = granular_spheres(packing, config, scale, exporter=program.lower())
    if spheres is None:
        raise PackingFileError(f"{path}: the packing is not one of spheres alone")
    check_atoms(path, table, spheres.index.size, "placed spheres", table[:, :6])
    if not np.allclose(table[:, 5], spheres.radius, rtol=1e-9, atol=0.0):
        raise PackingFileError(
            f"{path}: its radii are not those of the packing's spheres times {scale!r}; "
            "give the export's units and length_scale"
        )
    shift = table[:, 2:5] / scale - packing.centre[spheres.index]
    try:
        return moved(packing, spheres.index, shift, stats={"settled_steps": step})
    except PackingError as err:
        raise PackingFileError(f"{path}: {str(err).removeprefix('moved: ')}") from err


def read_dump(path: Path, program: str) -> tuple[float, list[str], FloatArray]:
    """Read a dump of one time step: its step, its atoms' columns and their values.

    Raises
    ------
    PackingFileError
        One line naming ``path``, when it is unreadable, holds no single time
        step, or a value is not a number or a row has another length.
    """
    from regopack.base.errors import PackingFileError

    try:
        lines = Path(path).read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as err:
        raise PackingFileError(f"{path}: cannot read a {program} dump: {err}") from err
    heads = [k for k, line in enumerate(lines) if line.startswith("ITEM: ATOMS")]
    if len(heads) != 1 or len(lines) < 2 or not lines[0].startswith("ITEM: TIMESTEP"):
        raise PackingFileError(f"{path}: not a {program} dump of one time step")
    columns = lines[heads[0]].split()[2:]
    rows = [line.split() for line in lines[heads[0] + 1 :] if line.strip()]
    if any(len(row) != len(columns) for row in rows):
        raise PackingFileError(f"{path}: a row does not have the {len(columns)} columns")
    try:
        table = np.array(rows, dtype=np.float64).reshape(-1, len(columns))
        step = float(lines[1])
    except ValueError as err:
        raise PackingFileError(f"{path}: a value is not a number ({err})") from err
    if not (math.isfinite(step) and step >= 0 and step == int(step)):
        raise PackingFileError(f"{path}: its time step {lines[1].strip()!r} is no step count")
    return step, columns, table


def check_atoms(path: Path, table: FloatArray, n: int, what: str, state: FloatArray) -> None:
    """Refuse a dump whose rows are not ``n`` atoms with ids 1 to ``n`` and a finite ``state``."""
    from regopack.base.errors import PackingFileError

    if table.shape[0] != n:
        raise PackingFileError(
            f"{path}: {table.shape[0]} atoms, but the packing has {n} {what}; is it the dump "
            "of another packing?"
        )
    if not np.isfinite(state).all():
        raise PackingFileError(f"{path}: an atom's state is not finite (the run blew up)")
    if not np.array_equal(table[:, 0], np.arange(1, n + 1)):
        raise PackingFileError(f"{path}: its atom ids are not 1 to {n} in order")
