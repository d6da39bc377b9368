"""Scenes: what to pack, validated in two steps.

A scene file (TOML) names one plugin of each kind and its parameters. Step one
(:class:`Scene`) checks the structure and reads each section's ``kind``; step
two (:func:`resolve_scene`) validates each section's parameters with the
``config_model`` of the plugin that ``kind`` selects. Every validation error is
turned into a one-line :class:`~regopack.base.errors.ConfigError` naming the file,
the dotted field, the offending value and what is allowed, for example::

    scene.toml: density.eta = -3: Input should be greater than or equal to 0

Phase fractions must sum to 1 within ``1e-3``; they are divided by their sum
(normalised exactly) when minerals are drawn.
"""

from __future__ import annotations

import copy
import math
import os
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, ClassVar, Generic, Literal, TypeVar

import numpy as np
from numpy.typing import NDArray
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    PrivateAttr,
    ValidationError,
    field_validator,
    model_validator,
)

from regopack.base import toml as _toml
from regopack.base.errors import ConfigError, GeometryError, PluginError
from regopack.base.messages import describe_validation_error, dotted, format_value, where
from regopack.base.outdir import MARKER, NAME_RULE, name_key, name_problem
from regopack.base.units import _ALIASES, LENGTH_UNITS, _allowed
from regopack.geometry.domain import (
    DOMAIN_KINDS,
    Box,
    Circle,
    ConvexPolygon,
    Cylinder,
    Rectangle,
)
from regopack.geometry.domain import Domain as DomainGeometry
from regopack.registry.manager import Registry
from regopack.registry.plugin_types import PluginSpec, misplaced_field, served_dimensions

__all__ = [
    "ANALYSIS_FOLDER",
    "DEFAULT_SCENE",
    "FRACTION_TOLERANCE",
    "Domain",
    "Outputs",
    "Phase",
    "PluginRef",
    "ResolvedPhase",
    "ResolvedPlugin",
    "ResolvedScene",
    "Scene",
    "apply_overrides",
    "builtin_scenes",
    "load_scene",
    "output_files",
    "resolve_scene",
]

DEFAULT_SCENE = "table1"
"""Built-in scene used when no scene is given (the paper's Table 1)."""

FRACTION_TOLERANCE = 1e-3
"""Largest allowed distance of the sum of the phase fractions from 1."""

CENTER_PRECISION = 1e-9
"""How finely 64-bit floats must resolve a domain's sides where it lies, as a share of its
smallest side: a centre farther from the origin than about ``CENTER_PRECISION / 2.2e-16``
smallest sides is refused (its particles would touch and overlap only to rounding)."""

ANALYSIS_FOLDER = "analysis"
"""Folder of the analysis files inside a run folder (when the scene lists analyses)."""

T = TypeVar("T")
FiniteFloat = Annotated[float, Field(allow_inf_nan=False)]
Point = Annotated[tuple[FiniteFloat, FiniteFloat], Field(strict=False)]
"""A point ``[x, y]``: a TOML array is taken as a tuple, its items stay strict numbers."""
Centre = Annotated[tuple[FiniteFloat, ...], Field(strict=False)]
"""A domain's centre: ``[x, y]``, or ``[x, y, z]`` for a box (checked with the kind)."""

STRICT = ConfigDict(extra="forbid", strict=True)
"""Model configuration of the scene sections: unknown keys and coerced values are errors.

Strict validation refuses a string or a boolean where a number is expected
(``width = "200"``, ``width = true``) and a number or string where a boolean is
expected; an integer is still a valid float (``width = 200``).
"""


class Domain(BaseModel):
    """The container: a walled rectangle, polygon, circle, box or cylinder, or a periodic one.

    ``kind = "rectangle"`` (the default) and ``"periodic"`` use ``width``,
    ``height`` and ``center``; ``"circle"`` uses ``radius`` and ``center``;
    ``"polygon"`` uses ``vertices``; ``"box"`` and ``"periodic-box"`` use
    ``width`` (x), ``depth`` (y), ``height`` (z, the vertical) and a
    three-number ``center``: they make the scene three-dimensional, as does
    ``"cylinder"`` (vertical axis) with ``radius``, ``height`` and a
    three-number ``center`` (the middle of its axis). A field
    that does not belong to the kind is an error.
    """

    model_config = STRICT

    kind: Literal[
        "rectangle", "periodic", "polygon", "circle", "box", "periodic-box", "cylinder"
    ] = Field(
        "rectangle",
        description=(
            "Shape of the container: 'rectangle' (walls), 'periodic' (a rectangle whose "
            "opposite sides are identified), 'polygon' (convex, walls) or 'circle' (wall); "
            "in 3D 'box' (walls), 'periodic-box' or 'cylinder' (vertical axis, walls)."
        ),
    )
    width: float = Field(
        800.0,
        gt=0,
        allow_inf_nan=False,
        description="Extent along x (micrometres); rectangle and periodic.",
    )
    height: float = Field(
        800.0,
        gt=0,
        allow_inf_nan=False,
        description=(
            "Extent along y (micrometres), the vertical; rectangle and periodic "
            "(boxes and cylinders: along z, the vertical)."
        ),
    )
    depth: float = Field(
        800.0,
        gt=0,
        allow_inf_nan=False,
        description="Extent along y (micrometres) of a box or periodic box.",
    )
    center: Centre = Field(
        (0.0, 0.0),
        description=(
            "Centre (micrometres): [x, y] of a rectangle, periodic rectangle or circle; "
            "[x, y, z] of a box, or of a cylinder's middle (default: the origin)."
        ),
    )
    radius: float | None = Field(
        None,
        gt=0,
        allow_inf_nan=False,
        description="Radius of the circle or the cylinder (micrometres).",
    )
    vertices: list[Point] | None = Field(
        None,
        min_length=3,
        description="Corners of the convex polygon in order, either orientation (micrometres).",
    )

    _FIELDS: ClassVar[dict[str, tuple[str, ...]]] = {
        "rectangle": ("width", "height", "center"),
        "periodic": ("width", "height", "center"),
        "circle": ("radius", "center"),
        "polygon": ("vertices",),
        "box": ("width", "height", "depth", "center"),
        "periodic-box": ("width", "height", "depth", "center"),
        "cylinder": ("radius", "height", "center"),
    }
    _REQUIRED: ClassVar[dict[str, tuple[str, ...]]] = {
        "circle": ("radius",),
        "cylinder": ("radius",),
        "polygon": ("vertices",),
    }

    @model_validator(mode="after")
    def _check_kind_fields(self) -> Domain:
        allowed = self._FIELDS[self.kind]
        for name in sorted(self.model_fields_set - {"kind"}):
            if name not in allowed:
                raise ValueError(
                    f"{name} does not apply to kind {self.kind!r}, which takes {', '.join(allowed)}"
                )
        for name in self._REQUIRED.get(self.kind, ()):
            if getattr(self, name) is None:
                raise ValueError(f"kind {self.kind!r} needs {name}")
        points = self.dimension
        if len(self.center) != points:
            if "center" in self.model_fields_set:
                raise ValueError(
                    f"center: kind {self.kind!r} takes {points} coordinates "
                    f"({'[x, y, z]' if points == 3 else '[x, y]'}), not {len(self.center)}"
                )
            object.__setattr__(self, "center", (0.0,) * points)
        self._check_center_precision()
        try:
            domain = self.to_domain()
        except GeometryError as err:
            if self.kind != "polygon":
                raise
            raise ValueError(f"vertices: {err}") from err
        if not math.isfinite(domain.measure):
            if self.kind == "cylinder":
                given = f"radius x height = {self.radius:g} x {self.height:g}"
            elif self.dimension == 3:
                given = (
                    f"width x depth x height = {self.width:g} x {self.depth:g} x {self.height:g}"
                )
            elif self.kind in ("rectangle", "periodic"):
                given = f"width x height = {self.width:g} x {self.height:g}"
            elif self.kind == "circle":
                given = f"radius = {self.radius:g}"
            else:
                given = "the vertices"
            measure = "volume" if self.dimension == 3 else "area"
            raise ValueError(
                f"{given} gives a {self.kind} whose {measure} overflows 64-bit floats (inf); "
                "give a smaller domain"
            )
        return self

    def _check_center_precision(self) -> None:
        """Refuse a centre so far from the origin that floats no longer resolve the sides."""
        if "center" not in self._FIELDS[self.kind]:
            return
        if self.kind == "circle":
            assert self.radius is not None
            sides = [2.0 * self.radius]
        elif self.kind == "cylinder":
            assert self.radius is not None
            sides = [2.0 * self.radius, self.height]
        else:
            sides = [self.width, self.height] + ([self.depth] if self.dimension == 3 else [])
        side = min(sides)
        # the centre's own offset: the extents are checked against the particles elsewhere
        far = max(abs(float(c)) for c in self.center)
        if not (side > 0 and math.isfinite(far)):
            return  # the fields' own bounds speak for these
        if math.ulp(far) > CENTER_PRECISION * side:
            reach = CENTER_PRECISION * side / math.ulp(1.0)
            given = "[" + ", ".join(f"{float(c):g}" for c in self.center) + "]"
            raise ValueError(
                f"center = {given} is too far from the origin for a domain whose smallest side "
                f"is {side:g}: 64-bit floats are {math.ulp(far):.2g} apart there, more than "
                f"{CENTER_PRECISION:g} of that side; put the centre within {reach:.2g} of the "
                "origin"
            )

    @property
    def dimension(self) -> int:
        """Dimension of the container: 3 for a box, periodic box or cylinder, 2 otherwise."""
        return DOMAIN_KINDS[self.kind].dimension

    def to_domain(self) -> DomainGeometry:
        """Return the container as a :class:`regopack.geometry.domain.Domain` (a box in 3D)."""
        cls = DOMAIN_KINDS[self.kind]
        if cls is Circle:
            assert self.radius is not None
            return Circle(self.center[0], self.center[1], self.radius)
        if cls is ConvexPolygon:
            assert self.vertices is not None
            return ConvexPolygon(tuple(self.vertices))
        if cls is Cylinder:
            assert self.radius is not None
            cx, cy, cz = (float(c) for c in self.center)
            return Cylinder.centred(self.radius, self.height, (cx, cy, cz))
        if issubclass(cls, Box):
            cx, cy, cz = (float(c) for c in self.center)
            return cls.centred(self.width, self.height, self.depth, (cx, cy, cz))
        assert issubclass(cls, Rectangle)
        cx, cy = (float(c) for c in self.center)
        return cls.centred(self.width, self.height, (cx, cy))

    def to_box(self) -> Box:
        """Return a 3D domain as a :class:`regopack.geometry.domain.Box`."""
        domain = self.to_domain()
        if not isinstance(domain, Box):
            raise GeometryError(f"the domain is a 2D {self.kind}, not a box")
        return domain

    def to_rectangle(self) -> Rectangle:
        """Return a rectangular domain as a :class:`regopack.geometry.domain.Rectangle`."""
        domain = self.to_domain()
        if not isinstance(domain, Rectangle):
            raise GeometryError(f"the domain is a {self.kind}, not a rectangle")
        return domain

    def resolved_dict(self) -> dict[str, Any]:
        """``kind`` and the fields of that kind, defaults filled in (plain data)."""
        data = self.model_dump(mode="json")
        return {"kind": self.kind, **{k: data[k] for k in self._FIELDS[self.kind]}}


class PluginRef(BaseModel):
    """Selects a plugin implementation by ``kind``; other keys are its parameters.

    The parameters are validated later, by the plugin's own ``config_model``
    (see :func:`resolve_scene`).
    """

    model_config = ConfigDict(extra="allow")

    kind: str = Field(min_length=1, description="Name of the plugin implementation.")

    @property
    def params(self) -> dict[str, Any]:
        """The parameters given besides ``kind``."""
        return dict(self.model_extra or {})


class Phase(BaseModel):
    """One mineral phase: its share of the particles and its shape generator."""

    model_config = STRICT

    name: str = Field(min_length=1, description="Name of the mineral phase.")
    fraction: float = Field(
        gt=0,
        allow_inf_nan=False,
        description="Share of the particles drawn from this phase (normalised to sum 1).",
    )
    shape: PluginRef = Field(description="Shape generator of this phase's particles.")


class Outputs(BaseModel):
    """Names of the files a run writes into its output directory."""

    model_config = STRICT

    packing: str = Field(
        "packing.npz",
        min_length=1,
        description="Packing file (NPZ): a plain file name inside the run folder.",
    )
    summary: str = Field(
        "summary.json",
        min_length=1,
        description="Run summary (JSON): a plain file name inside the run folder.",
    )
    analyses: list[Annotated[str, Field(min_length=1)] | PluginRef] = Field(
        default_factory=list,
        description=(
            "Analyzers to run after packing: a name (defaults), or an inline table "
            'with its parameters, e.g. {kind = "contacts", tol = 0.1}.'
        ),
    )
    exports: list[Annotated[str, Field(min_length=1)] | PluginRef] = Field(
        default_factory=list,
        description=(
            "Exporters to write after the run, beside the packing file: a name (defaults), "
            'or an inline table with its parameters, e.g. {kind = "lammps", stiffness = 1e5}.'
        ),
    )

    fabric: bool = Field(
        True,
        description=(
            "Measure the contact network for the summary's fabric block: contacts, Z and "
            "the mechanical Z_m, the share of rattlers and the fabric anisotropy with its "
            "sampling error (a contact search after packing; false leaves it out)."
        ),
    )

    @field_validator("packing", "summary")
    @classmethod
    def _check_file_name(cls, name: str) -> str:
        problem = name_problem(name)
        if problem is not None:
            raise ValueError(
                f"{problem}; an output is a plain file name inside the run folder ({NAME_RULE})"
            )
        return name


class Tiles(BaseModel):
    """One packing built in tiles over the floor (:mod:`regopack.tiling`)."""

    model_config = STRICT

    side: float | list[float] = Field(
        description=(
            "Side of the tiles (length units) along the floor: x in the plane, x and y in "
            "space; a list gives one side per floor axis ([x, y]; a side as long as the "
            "box gives one tile along that axis, strips). Each tile draws its share of the "
            "particles from its own stream and is packed against the tiles before it; the "
            "packing depends on the tiles, not on the workers that pack them. At least two "
            "largest diameters and two largest circumradii."
        ),
    )

    @field_validator("side")
    @classmethod
    def _check_side(cls, side: float | list[float]) -> float | list[float]:
        values = side if isinstance(side, list) else [side]
        if not 1 <= len(values) <= 2:
            raise ValueError(f"give one side, or one per floor axis ([x, y]), not {len(values)}")
        for v in values:
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"a side must be a positive finite length, not {v!r}")
        return side

    def sides(self, floor_axes: int) -> list[float]:
        """Return the side along each of ``floor_axes`` floor axes."""
        if isinstance(self.side, list):
            return list(self.side)
        return [float(self.side)] * floor_axes

    def label(self) -> str:
        """``tiles.side = ...`` as the scene gives it, for messages."""
        if isinstance(self.side, list):
            return "tiles.side = [" + ", ".join(f"{v:g}" for v in self.side) + "]"
        return f"tiles.side = {self.side:g}"


class Scene(BaseModel):
    """A packing scene: domain, particle population, insertion and density control.

    Examples
    --------
    >>> scene = load_scene("small")
    >>> scene.name, scene.domain.width
    ('small', 200.0)
    """

    model_config = STRICT

    name: str = Field("custom", min_length=1, description="Name of the scene (used for outputs).")
    seed: int = Field(0, ge=0, strict=True, description="Seed of the run's random generator.")
    count: Literal["auto"] | Annotated[int, Field(ge=1, strict=True)] = Field(
        "auto",
        description=(
            "Number of particles to draw; 'auto' gives round(domain area / mean particle area)."
        ),
    )
    length_unit: str = Field(
        "µm",
        description=(
            "Unit of every length of the scene, its packing and analyses: 'm', 'cm', 'mm', "
            "'µm' (or 'um') or 'nm'. It names the unit in figures, tables and exports; "
            "it does not convert anything."
        ),
        json_schema_extra={"enum": [*LENGTH_UNITS, *_ALIASES]},
    )
    domain: Domain = Field(default_factory=Domain, description="The container.")
    size: PluginRef = Field(description="Size distribution of the equivalent radii.")
    phases: list[Phase] = Field(
        min_length=1, description="Mineral phases with fractions and shape generators."
    )
    insertion: PluginRef = Field(description="Insertion strategy.")
    density: PluginRef = Field(description="Density controller used by the insertion.")
    outputs: Outputs = Field(default_factory=Outputs, description="Output file names.")
    tiles: Tiles | None = Field(
        None,
        description=(
            "Build the packing in tiles that workers pack side by side "
            "(regopack run --workers); absent: one packing in one process."
        ),
    )

    _source: str | None = PrivateAttr(default=None)
    _overridden: dict[str, str] = PrivateAttr(default_factory=dict)

    @field_validator("name")
    @classmethod
    def _check_name(cls, name: str) -> str:
        problem = name_problem(name)
        if problem is not None:
            raise ValueError(
                f"{problem}; the scene name is used in the output folder "
                f"runs/<name>-seed<seed>, so it must be a plain folder name ({NAME_RULE})"
            )
        return name

    @field_validator("length_unit", mode="before")
    @classmethod
    def _check_length_unit(cls, value: Any) -> Any:
        unit = _ALIASES.get(value, value) if isinstance(value, str) else value
        if isinstance(unit, str) and unit in LENGTH_UNITS:
            return unit
        raise ValueError(f"not a length unit; allowed: {_allowed()}")

    @field_validator("count", mode="before")
    @classmethod
    def _check_count(cls, value: Any) -> Any:
        whole = isinstance(value, int) and not isinstance(value, bool)
        if value == "auto" or (whole and value >= 1):
            return value
        raise ValueError('must be "auto" or a whole number >= 1')

    @field_validator("phases")
    @classmethod
    def _check_phases(cls, phases: list[Phase]) -> list[Phase]:
        names = [p.name for p in phases]
        duplicates = sorted({n for n in names if names.count(n) > 1})
        if duplicates:
            raise ValueError(f"phase names must be unique; repeated: {', '.join(duplicates)}")
        total = math.fsum(p.fraction for p in phases)
        if abs(total - 1.0) > FRACTION_TOLERANCE:
            raise ValueError(
                f"phase fractions sum to {total:.6g}; they must sum to 1 "
                f"(within {FRACTION_TOLERANCE:g})"
            )
        return phases

    @property
    def source(self) -> str | None:
        """File the scene was read from (for messages), if any."""
        return self._source

    def origin(self, loc: str) -> str | None:
        """Where the value of the dotted field ``loc`` came from: an option or the file."""
        return _where(loc, self._source, self._overridden)

    @property
    def fractions(self) -> NDArray[np.float64]:
        """Phase fractions divided by their sum."""
        f = np.array([p.fraction for p in self.phases], dtype=np.float64)
        out: NDArray[np.float64] = f / f.sum()
        return out


# ---------------------------------------------------------------------------
# errors


_format_value = format_value
_dotted = dotted
_where = where


# ---------------------------------------------------------------------------
# loading


def builtin_scenes() -> dict[str, str]:
    """Built-in scenes: name to one-line description (the file's first comment).

    Examples
    --------
    >>> sorted(builtin_scenes())
    ['dem', 'dem3d', 'small', 'table1', 'table1-3d']
    """
    out: dict[str, str] = {}
    for entry in sorted(resources.files("regopack.scenes").iterdir(), key=lambda e: e.name):
        if not entry.name.endswith(".toml"):
            continue
        text = entry.read_text(encoding="utf-8")
        out[entry.name.removesuffix(".toml")] = _toml.first_comment(text)
    return out


def _read_builtin(name: str) -> str:
    return resources.files("regopack.scenes").joinpath(f"{name}.toml").read_text(encoding="utf-8")


def _parse_override(text: str) -> tuple[str, Any]:
    key, sep, raw = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise ConfigError(f"--set {text!r}: expected key=value, e.g. density.eta=10")
    parts = key.split(".")
    if any(not p.strip() for p in parts):
        raise ConfigError(f"--set {text!r}: empty part in the dotted key {key!r}")
    raw = raw.strip()
    try:
        value = tomllib.loads("v = " + raw)["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    return ".".join(p.strip() for p in parts), value


def apply_overrides(data: dict[str, Any], overrides: Sequence[str]) -> list[str]:
    """Apply ``key=value`` overrides to a raw scene dictionary in place.

    Keys are dotted paths; list items are addressed by index
    (``phases.0.shape.psi=3``). Values are parsed as TOML values
    (``10``, ``0.99``, ``"text"``, ``[1, 2]``, ``{kind = "eta"}``) and taken as
    plain strings when they are not valid TOML.

    Returns
    -------
    list of str
        The dotted keys that were set.

    Examples
    --------
    >>> d = {"density": {"kind": "eta"}}
    >>> apply_overrides(d, ["density.eta=10", "insertion.first=center"])
    ['density.eta', 'insertion.first']
    >>> d
    {'density': {'kind': 'eta', 'eta': 10}, 'insertion': {'first': 'center'}}
    """
    keys: list[str] = []
    for text in overrides:
        key, value = _parse_override(text)
        set_value(data, key, value, f"--set {key}")
        keys.append(key)
    return keys


def set_value(data: dict[str, Any], key: str, value: Any, label: str) -> None:
    """Set the dotted ``key`` of a raw scene dictionary to ``value``, in place.

    Missing tables are created; list items are addressed by index. ``label``
    starts the one-line error (e.g. ``--set phases.9.name``).

    Examples
    --------
    >>> d = {"phases": [{"name": "glass"}]}
    >>> set_value(d, "phases.0.fraction", 1.0, "example")
    >>> d
    {'phases': [{'name': 'glass', 'fraction': 1.0}]}
    """
    parts = key.split(".")
    node: Any = data
    for depth, part in enumerate(parts):
        last = depth == len(parts) - 1
        where = ".".join(parts[: depth + 1])
        if isinstance(node, list):
            if not part.isdigit() or int(part) >= len(node):
                raise ConfigError(f"{label}: {where} is not an item of a list of {len(node)} items")
            index = int(part)
            if last:
                node[index] = value
            else:
                node = node[index]
        elif isinstance(node, dict):
            if last:
                node[part] = value
            else:
                node = node.setdefault(part, {})
        else:
            parent = ".".join(parts[:depth])
            raise ConfigError(f"{label}: {parent} is a value, not a table")


def read_scene_data(path_or_name: str | Path | None = None) -> tuple[dict[str, Any], str]:
    """Read a scene's raw dictionary and the name of its source, unvalidated.

    Parameters
    ----------
    path_or_name
        As for :func:`load_scene`.

    Returns
    -------
    data, source
        The parsed TOML and the file name errors should name
        (``table1.toml`` for a built-in scene).
    """
    if path_or_name is None:
        path_or_name = DEFAULT_SCENE
    name = str(path_or_name)
    builtins = builtin_scenes()
    if isinstance(path_or_name, str) and not name.endswith(".toml") and name in builtins:
        source = f"{name}.toml"
        text = _read_builtin(name)
    else:
        path = Path(path_or_name)
        source = str(path)
        known = ", ".join(sorted(builtins))
        text = _toml.read_text_file(path, "scene", f" (built-in scenes: {known})")
    return _toml.parse_toml(text, source), source


def load_scene(
    path_or_name: str | Path | None = None,
    overrides: Sequence[str] = (),
    seed: int | None = None,
) -> Scene:
    """Read a scene and apply command-line overrides (step one of validation).

    Parameters
    ----------
    path_or_name
        ``None`` for the default built-in scene (``table1``); the name of a
        built-in scene (see :func:`builtin_scenes`); or the path of a TOML file.
    overrides
        ``key=value`` strings with dotted keys, e.g. ``density.eta=10``,
        ``domain.width=200``, ``phases.0.shape.psi=3`` (see :func:`apply_overrides`).
    seed
        Replaces the scene's seed.

    Raises
    ------
    ConfigError
        One line naming the file, field, value and what is allowed.

    Examples
    --------
    >>> load_scene("table1", ["density.eta=10"], seed=7).seed
    7
    """
    data, source = read_scene_data(path_or_name)
    overridden = dict.fromkeys(apply_overrides(data, overrides), "--set")
    if seed is not None:
        data["seed"] = seed
        overridden["seed"] = "--seed"
    return scene_from_dict(data, source=source, overridden=overridden)


def scene_from_dict(
    data: Mapping[str, Any],
    *,
    source: str | None = None,
    overridden: Mapping[str, str] | None = None,
) -> Scene:
    """Validate a raw scene dictionary (step one), with one-line errors.

    Parameters
    ----------
    data
        The scene as read from TOML.
    source
        File name used in error messages.
    overridden
        Dotted keys set on the command line, mapped to the option that set them
        (``"--set"``, ``"--seed"``); errors in them name the option, not the file.
    """
    try:
        scene = Scene.model_validate(data)
    except ValidationError as err:
        raise ConfigError(
            describe_validation_error(err, source=source, overridden=overridden, model=Scene)
        ) from err
    scene._source = source
    scene._overridden = dict(overridden or {})
    return scene


# ---------------------------------------------------------------------------
# resolution


@dataclass(frozen=True)
class ResolvedPlugin(Generic[T]):
    """A plugin selection with its validated configuration.

    Attributes
    ----------
    kind
        Name of the implementation (the scene's ``kind``).
    spec
        The plugin's spec record.
    config
        The validated ``config_model`` instance (all defaults filled in).
    origin
        Plugin or distribution that provides the implementation.
    """

    kind: str
    spec: PluginSpec[T]
    config: BaseModel
    origin: str

    def build(self) -> T:
        """Build the implementation from the validated configuration."""
        return self.spec.factory(self.config)

    def to_dict(self) -> dict[str, Any]:
        """``{"kind": ..., **parameters}`` with every default filled in."""
        params = self.config.model_dump(mode="json", by_alias=True)
        return {"kind": self.kind, **{k: v for k, v in params.items() if k != "kind"}}


@dataclass(frozen=True)
class ResolvedPhase:
    """A phase with its resolved shape generator."""

    name: str
    fraction: float
    shape: ResolvedPlugin[Any]


@dataclass(frozen=True, repr=False)
class ResolvedScene:
    """A scene whose plugin parameters have been validated (step two).

    Attributes
    ----------
    scene
        The structural scene.
    size, insertion, density
        Resolved plugin selections.
    phases
        Phases in scene order.
    analyses
        Analyzers requested in ``outputs.analyses``.
    exports
        Exporters requested in ``outputs.exports``.
    registry
        Registry the plugins came from (to look up analyzers' requirements).
    """

    scene: Scene
    size: ResolvedPlugin[Any]
    phases: tuple[ResolvedPhase, ...]
    insertion: ResolvedPlugin[Any]
    density: ResolvedPlugin[Any]
    analyses: tuple[ResolvedPlugin[Any], ...]
    registry: Registry
    exports: tuple[ResolvedPlugin[Any], ...] = ()

    @property
    def name(self) -> str:
        """Name of the scene."""
        return self.scene.name

    @property
    def seed(self) -> int:
        """Seed of the run."""
        return self.scene.seed

    @property
    def domain(self) -> DomainGeometry:
        """The container."""
        return self.scene.domain.to_domain()

    @property
    def phase_names(self) -> tuple[str, ...]:
        """Phase names in scene order."""
        return tuple(p.name for p in self.phases)

    @property
    def fractions(self) -> NDArray[np.float64]:
        """Phase fractions divided by their sum."""
        return self.scene.fractions

    def to_dict(self) -> dict[str, Any]:
        """Return the fully resolved scene (every default filled in) as plain data.

        ``outputs.fabric`` is written only when it is false, so that a scene
        stored in a packing reads as it did before the field existed.

        Reading the result back with :func:`scene_from_dict` and resolving it
        gives the same scene.
        """
        s = self.scene
        return {
            "name": s.name,
            "seed": s.seed,
            "count": s.count,
            "length_unit": s.length_unit,
            "domain": s.domain.resolved_dict(),
            "size": self.size.to_dict(),
            "phases": [
                {"name": p.name, "fraction": p.fraction, "shape": p.shape.to_dict()}
                for p in self.phases
            ],
            "insertion": self.insertion.to_dict(),
            "density": self.density.to_dict(),
            "outputs": {
                "packing": s.outputs.packing,
                "summary": s.outputs.summary,
                "analyses": [
                    a.kind if isinstance(item, str) else a.to_dict()
                    for a, item in zip(self.analyses, s.outputs.analyses, strict=True)
                ],
                "exports": [
                    e.kind if isinstance(item, str) else e.to_dict()
                    for e, item in zip(self.exports, s.outputs.exports, strict=True)
                ],
                # only when off: the scenes stored in packings stay as they were
                **({} if s.outputs.fabric else {"fabric": False}),
            },
            **({} if s.tiles is None else {"tiles": {"side": s.tiles.side}}),
        }

    def to_toml(self) -> str:
        """:meth:`to_dict` as a TOML document."""
        return _toml.dumps(self.to_dict())

    def with_(
        self, *, seed: int | None = None, registry: Registry | None = None, **overrides: Any
    ) -> ResolvedScene:
        """Return this scene with some fields changed, validated again.

        Keys are dotted names as for ``--set``, written with ``__`` for the
        dots (``domain__width=400``, ``phases__0__shape__psi=3``) or passed
        as a dictionary (``**{"domain.width": 400}``). ``seed`` and
        ``registry`` are those of :func:`regopack.scene` (``None`` keeps the
        scene's own).

        Examples
        --------
        >>> import regopack
        >>> regopack.scene("small").with_(density__eta=5, seed=3).seed
        3
        """
        return make_scene(self, seed=seed, registry=registry, overrides=overrides)

    def __repr__(self) -> str:
        d = self.scene.domain
        if d.kind == "circle":
            where = f"circle of radius {d.radius:g} µm"
        elif d.kind == "cylinder":
            where = f"cylinder of radius {d.radius:g} µm and height {d.height:g} µm"
        elif d.kind == "polygon":
            where = f"polygon of {len(d.vertices or ())} vertices"
        else:
            where = f"{d.width:g} × {d.height:g} µm {d.kind}"
        count = self.scene.count
        phases = ", ".join(self.phase_names)
        return (
            f"<scene {self.name!r}: seed {self.seed}, count {count}, {where}, "
            f"{self.size.kind} sizes, phases [{phases}], {self.insertion.kind} insertion, "
            f"{self.density.kind} density>"
        )


def _resolve_ref(
    scene: Scene,
    registry: Registry,
    category: str,
    ref: PluginRef,
    loc: tuple[int | str, ...],
    kind_loc: tuple[int | str, ...] | None = None,
) -> ResolvedPlugin[Any]:
    kind_where = _dotted(kind_loc if kind_loc is not None else (*loc, "kind"))
    try:
        spec = registry.get(category, ref.kind)
        origin = registry.origin(category, ref.kind)
    except PluginError as err:
        text = f"{kind_where}: {err}"
        source = _where(kind_where, scene.source, scene._overridden)
        raise ConfigError(f"{source}: {text}" if source else text) from err
    try:
        config = spec.config_model.model_validate(ref.params)
    except ValidationError as err:
        raise ConfigError(
            describe_validation_error(
                err,
                source=scene.source,
                prefix=loc,
                overridden=scene._overridden,
                model=spec.config_model,
                also=("kind",),
            )
        ) from err
    if category in ("analysis", "export"):  # a parameter of another dimension than the scene's
        misplaced = misplaced_field(config, scene.domain.dimension)
        if misplaced is not None:
            field, line = misplaced
            text = f"{_dotted(loc)}.{line}"
            source = _where(_dotted((*loc, field)), scene.source, scene._overridden)
            raise ConfigError(f"{source}: {text}" if source else text)
    return ResolvedPlugin(kind=ref.kind, spec=spec, config=config, origin=origin)


def resolve_scene(scene: Scene, registry: Registry) -> ResolvedScene:
    """Validate every plugin's parameters with its ``config_model`` (step two).

    Raises
    ------
    ConfigError
        One line: an unknown ``kind`` (listing the known ones) or a bad
        parameter, located by its path in the scene (e.g. ``phases.2.shape.psi``).
    """
    size = _resolve_ref(scene, registry, "size", scene.size, ("size",))
    phases = tuple(
        ResolvedPhase(
            name=p.name,
            fraction=p.fraction,
            shape=_resolve_ref(scene, registry, "shape", p.shape, ("phases", i, "shape")),
        )
        for i, p in enumerate(scene.phases)
    )
    insertion = _resolve_ref(scene, registry, "insertion", scene.insertion, ("insertion",))
    density = _resolve_ref(scene, registry, "density", scene.density, ("density",))

    def resolve_list(
        category: str, field: str, items: Sequence[str | PluginRef]
    ) -> tuple[Any, ...]:
        """Resolve ``outputs.<field>``: names (defaults) or inline tables with parameters."""
        return tuple(
            _resolve_ref(
                scene,
                registry,
                category,
                PluginRef(kind=item) if isinstance(item, str) else item,
                ("outputs", field, i),
                kind_loc=("outputs", field, i) if isinstance(item, str) else None,
            )
            for i, item in enumerate(items)
        )

    _check_dimensions(scene, registry, phases, insertion)
    analyses = resolve_list("analysis", "analyses", scene.outputs.analyses)
    exports = resolve_list("export", "exports", scene.outputs.exports)
    _check_export_dimensions(scene, registry, exports)
    _check_output_files(scene, analyses, exports)
    return ResolvedScene(
        scene=scene,
        size=size,
        phases=phases,
        insertion=insertion,
        density=density,
        analyses=analyses,
        registry=registry,
        exports=exports,
    )


def _dimensions_of(spec: PluginSpec[Any], category: str) -> tuple[int, ...]:
    """Dimensions a shape or inserter plugin works in (2D unless its spec says otherwise)."""
    if category == "shape":
        return (int(getattr(spec, "dimension", 2)),)
    return tuple(getattr(spec, "dimensions", (2,)))


def _check_dimensions(
    scene: Scene,
    registry: Registry,
    phases: Sequence[ResolvedPhase],
    insertion: ResolvedPlugin[Any],
) -> None:
    """Refuse, in one line, a shape or an inserter of another dimension than the domain's."""
    dim = scene.domain.dimension
    picks = [
        (("phases", i, "shape", "kind"), "shape", p.shape, "shape") for i, p in enumerate(phases)
    ] + [(("insertion", "kind"), "insertion", insertion, "inserter")]
    for loc, category, plugin, noun in picks:
        if dim in _dimensions_of(plugin.spec, category):
            continue
        fitting = [
            n
            for n in registry.names(category)
            if dim in _dimensions_of(registry.get(category, n), category)
        ]
        blame = "domain.kind" if scene.origin("domain.kind") != scene.source else _dotted(loc)
        source = _where(blame, scene.source, scene._overridden)
        own = "/".join(f"{d}D" for d in _dimensions_of(plugin.spec, category))
        text = (
            f"{_dotted(loc)} = {plugin.kind!r} is a {own} {noun}, but domain.kind = "
            f"{scene.domain.kind!r} makes the scene {dim}D; "
            + (
                f"{dim}D {noun}s: {', '.join(fitting)}"
                if fitting
                else f"no {dim}D {noun} is installed"
            )
        )
        raise ConfigError(f"{source}: {text}" if source else text)


def _check_export_dimensions(
    scene: Scene, registry: Registry, exports: Sequence[ResolvedPlugin[Any]]
) -> None:
    """Refuse, in one line, an exporter of ``outputs.exports`` of another dimension."""
    dim = scene.domain.dimension
    for i, (plugin, item) in enumerate(zip(exports, scene.outputs.exports, strict=True)):
        own = served_dimensions(plugin.spec, plugin.kind)
        if dim in own:
            continue
        loc = f"outputs.exports.{i}" + ("" if isinstance(item, str) else ".kind")
        fitting = [
            n
            for n in registry.names("export")
            if dim in _dimensions_of(registry.get("export", n), "export")
        ]
        source = _where(loc, scene.source, scene._overridden)
        text = (
            f"{loc} = {plugin.kind!r} is a {'/'.join(f'{d}D' for d in own)} exporter, but "
            f"domain.kind = {scene.domain.kind!r} makes the scene {dim}D; "
            + (
                f"{dim}D exporters: {', '.join(fitting)}"
                if fitting
                else f"no {dim}D exporter is installed"
            )
        )
        raise ConfigError(f"{source}: {text}" if source else text)


# ---------------------------------------------------------------------------
# output files


@dataclass(frozen=True)
class _OutputFile:
    """One path a run writes into its folder, and how to name it in messages."""

    loc: str
    name: str
    value: Any
    description: str
    verb: str = ""


def _export_name(packing: str, suffix: str) -> str | None:
    """``<packing stem><suffix>``, or ``None`` when that is no plain file name."""
    try:
        name = Path(packing).with_suffix(suffix).name
    except ValueError:
        return None
    return name if name_problem(name) is None else None


def _output_entries(
    scene: Scene,
    analyses: Sequence[ResolvedPlugin[Any]],
    exports: Sequence[ResolvedPlugin[Any]],
) -> list[_OutputFile]:
    outputs = scene.outputs
    entries: list[_OutputFile] = []
    if analyses:
        entries.append(
            _OutputFile(
                "outputs.analyses",
                ANALYSIS_FOLDER,
                None,
                f'the analysis folder "{ANALYSIS_FOLDER}" of outputs.analyses',
            )
        )
    for field_name in ("packing", "summary"):
        name = getattr(outputs, field_name)
        loc = f"outputs.{field_name}"
        entries.append(_OutputFile(loc, name, name, f"{loc} ({_toml._value(name)})"))
    for i, (plugin, item) in enumerate(zip(exports, outputs.exports, strict=True)):
        loc = f"outputs.exports.{i}"
        value = item if isinstance(item, str) else None
        exporter = plugin.build()
        suffix_for = getattr(exporter, "suffix_for", None)
        suffix = (
            suffix_for(scene.domain.dimension)
            if callable(suffix_for)
            else getattr(exporter, "suffix", "")
        )
        main = _export_name(outputs.packing, suffix if isinstance(suffix, str) else "")
        if main is None:
            raise ConfigError(
                f"{loc}: the {plugin.kind!r} exporter's suffix {suffix!r} gives no plain "
                "file name beside the packing file"
            )
        names = [main]
        companions = getattr(exporter, "companions", None)
        if callable(companions):
            names += [Path(p).name for p in companions(Path(main))]
        for name in names:
            entries.append(
                _OutputFile(
                    loc,
                    name,
                    value,
                    f"{loc} ({plugin.kind}), which writes {name}",
                    verb=f"writes {name}, ",
                )
            )
    return entries


def _check_output_files(
    scene: Scene,
    analyses: Sequence[ResolvedPlugin[Any]],
    exports: Sequence[ResolvedPlugin[Any]],
) -> None:
    """Refuse two outputs of one run that are one path (before anything is written)."""
    claimed: dict[str, _OutputFile] = {
        name_key(MARKER): _OutputFile("", MARKER, None, f"regopack's marker file {MARKER}")
    }
    for entry in _output_entries(scene, analyses, exports):
        other = claimed.get(name_key(entry.name))
        if other is None:
            claimed[name_key(entry.name)] = entry
            continue
        shown = _format_value(entry.value) if entry.value is not None else None
        text = f"{entry.loc} = {shown}" if shown is not None else entry.loc
        where = _where(entry.loc, None, scene._overridden)
        if where is None and other.loc:
            where = _where(other.loc, None, scene._overridden)
        where = where or scene.source
        same = "the same path as" if entry.name == other.name else "the same path (on a "
        if entry.name != other.name:
            same += "case-insensitive file system) as"
        message = (
            f"{text}: {entry.verb}{same} {other.description}; "
            "every output of a run needs its own name"
        )
        raise ConfigError(f"{where}: {message}" if where else message)


def output_files(resolved: ResolvedScene) -> dict[str, list[str]]:
    """Return the names a run of ``resolved`` writes into its folder, by scene field.

    ``outputs.packing``, ``outputs.summary``, ``outputs.analyses`` (the
    analysis folder, when analyses are listed) and ``outputs.exports.<i>``
    (each exporter's files). :data:`regopack.base.outdir.MARKER` is written too.
    """
    out: dict[str, list[str]] = {}
    for entry in _output_entries(resolved.scene, resolved.analyses, resolved.exports):
        out.setdefault(entry.loc, []).append(entry.name)
    return out


def registry_or_default(registry: Registry | None) -> Registry:
    """Return ``registry``, or the default registry (built-in and installed plugins) for ``None``.

    Raises
    ------
    ConfigError
        When ``registry`` is not a :class:`~regopack.registry.manager.Registry`.
    """
    if registry is None:
        from regopack.registry.manager import (
            default_registry,  # looked up when called (tests patch it)
        )

        return default_registry()
    if not isinstance(registry, Registry):
        raise ConfigError(
            f"registry: expected a regopack.registry.manager.Registry, "
            f"not {type(registry).__name__}"
        )
    return registry


def dotted_name(name: str) -> str:
    """``domain__width`` → ``domain.width``; dotted names pass unchanged.

    Raises
    ------
    ConfigError
        When a part of the name is empty (``__x``, ``a____b``, ``a__``).
    """
    key = name.replace("__", ".")
    if any(not part for part in key.split(".")):
        raise ConfigError(
            f"{name}: empty part in the dotted name {key!r}; write e.g. domain__width=400"
        )
    return key


def plain_value(value: Any) -> Any:
    """NumPy scalars and arrays as the Python values a scene file would hold."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, Mapping):
        return {k: plain_value(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [plain_value(v) for v in value]
    return value


def make_scene(
    source: str | os.PathLike[str] | Mapping[str, Any] | ResolvedScene | None,
    *,
    seed: int | None = None,
    registry: Registry | None = None,
    overrides: Mapping[str, Any] | None = None,
) -> ResolvedScene:
    """Read, change and validate a scene (the work of :func:`regopack.scene`).

    ``overrides`` maps dotted names (``__`` for the dot) to Python values.
    """
    if isinstance(source, ResolvedScene):
        data = source.to_dict()
        origin = source.scene.source or f"scene {source.name!r}"
        registry = registry if registry is not None else source.registry
    elif isinstance(source, Mapping):
        data = copy.deepcopy(dict(source))
        origin = "scene dictionary"
    elif source is None or isinstance(source, str | os.PathLike):
        data, origin = read_scene_data(source if isinstance(source, str | None) else Path(source))
    else:
        raise ConfigError(
            f"scene: expected a built-in scene name, a TOML file, a dictionary or a scene, "
            f"not {type(source).__name__}"
        )
    overridden: dict[str, str] = {}
    for name, value in (overrides or {}).items():
        key = dotted_name(name)
        label = f"scene({name}=...)"
        set_value(data, key, plain_value(value), label)
        overridden[key] = label
    if seed is not None:
        data["seed"] = plain_value(seed)
        overridden["seed"] = "scene(seed=...)"
    structural = scene_from_dict(data, source=origin, overridden=overridden)
    return resolve_scene(structural, registry_or_default(registry))
