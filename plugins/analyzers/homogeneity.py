"""Spatial homogeneity: density, solid fraction, size (and minerals) over regions.

A 3D packing is cut into horizontal layers and nested boxes (in a cylinder:
discs of its cross-section and nested coaxial cylinders)
(:mod:`~regopack.plugins.analyzers.homogeneity_boxes`); a 2D one as follows.
The interior window (see :func:`~regopack.plugins.analyzers.common.interior_window`)
is cut into rings about the domain centre and into a grid of tiles. In each
region: the number density of the particle centres, the area fraction φ of the
particles cut exactly to the region, the mean equivalent diameter and the
mineral number fractions, each with its sampling error; against the ring
radius, the weighted least-squares trend of each quantity.

Sampling errors (standard errors):

- number density ``n / A``: Poisson, ``sqrt(max(n, 1)) / A``;
- φ: from the data, by the scatter of φ between equal parts of the region
  (:func:`~regopack.plugins.analyzers.regions.scatter_error`): a ring is cut
  into :data:`SECTORS` wedges about the centre, a tile into
  :data:`TILE_SPLIT` × :data:`TILE_SPLIT` cells, the whole window into the
  wedges of all its rings, every outline cut exactly to each part. The
  compound Poisson error ``sqrt(sum(a_i^2)) / A`` (``a_i`` the area of
  particle ``i`` inside the region) assumes particles placed independently;
  particles that cannot overlap fill a region far more evenly than that, and
  in the built-in packings it came out 7 to 20 times the scatter of φ between
  seeds, between tiles and between rings. Over 20 seeds of the ``small``
  scene the scatter of the parts gives 0.86 to 1.39 times (median 1.03) the
  seed-to-seed scatter of a ring's φ, and 0.52 to 1.25 times (median 0.82)
  that of a tile's, whose cells are smaller than the largest particles and
  fill together. A real trend across a region (the packings are radially
  graded) adds to the scatter of its parts, an error on the large side;
- mean diameter: ``std(d) / sqrt(n)`` (``ddof = 1``; NaN when ``n < 2``);
- mineral fraction ``p``: binomial, ``sqrt(p (1 - p) / n)`` (the trends use
  the window's fraction for ``p``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, model_validator

from regopack.base.errors import ConfigError
from regopack.base.limits import derived_count
from regopack.base.units import length_scale
from regopack.geometry.domain import Cylinder, PlaneDomain
from regopack.packing.core import Packing
from regopack.plugins.analyzers.common import (
    Measured,
    eta_of,
    interior_margin,
    interior_window,
)
from regopack.plugins.analyzers.homogeneity_boxes import (
    layers_and_shells,
    layers_and_shells_cylinder,
)
from regopack.plugins.analyzers.regions import (
    Tiles,
    ring_edges,
    ring_mean_radius,
    ring_piece_areas,
    ring_sector_areas,
    ring_window_areas,
    scatter_error,
    tile_cell_areas,
    tile_grid,
    tile_piece_areas,
    window_pieces,
    window_reach,
)
from regopack.registry.interfaces import Analyzer

__all__ = ["QUANTITIES", "Homogeneity", "HomogeneityConfig", "Trend", "region_stats", "trend"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

QUANTITIES: tuple[tuple[str, str], ...] = (
    ("density", "number_density"),
    ("phi", "phi"),
    ("mean_d", "mean_d"),
)
"""Result prefix and table column of the three quantities whose trends are reported."""

PER_LENGTH = 100.0
"""Slopes are given per this length at the built-in scale (``d_min = 2``): ``50 d_min``.

For another packing the length is ``PER_LENGTH`` times
:func:`~regopack.base.units.length_scale` (``d_min / 2``), reported as ``slope_length``
in the results; the ``*_slope_per_100`` keys keep their names."""


MAX_RINGS = 1000
"""Most rings the window may be cut into (``rings`` or the window's reach / ``ring_width``)."""

RING_FIELD = "homogeneity.ring_width"
"""The field a refused ring width is reported under."""

SECTORS = 8
"""Equal wedges each ring is cut into: the scatter of φ between them gives its error."""

TILE_SPLIT = 3
"""Each tile is cut into this many by this many equal cells for the error of its φ."""


DEFAULT_REGIONS: dict[str, Any] = {"tiles": (4, 4), "layers": 6, "shells": 4}
"""Regions of the window when the config leaves them out."""


PLANE: dict[str, Any] = {"dimensions": [2]}
SOLID: dict[str, Any] = {"dimensions": [3]}
"""Parameters of one dimension (see :func:`regopack.registry.plugin_types.field_dimensions`)."""


class HomogeneityConfig(BaseModel):
    """Parameters of the homogeneity analyzer."""

    model_config = ConfigDict(extra="forbid", strict=True)

    ring_width: float | None = Field(
        None,
        gt=0,
        json_schema_extra=PLANE,
        allow_inf_nan=False,
        description=(
            "Width of the rings about the domain centre (length unit); default: "
            "min(2 d_max, a quarter of the distance from the centre to the window's nearest "
            "edge)."
        ),
    )
    rings: int | None = Field(
        None,
        ge=1,
        le=MAX_RINGS,
        json_schema_extra=PLANE,
        description=(
            "Number of rings instead of a width: the ring width is the distance from the "
            "centre to the farthest window point over rings."
        ),
    )
    tiles: tuple[int, int] | None = Field(
        None,
        strict=False,
        json_schema_extra=PLANE,
        description="Tiles along x and y over the interior window's bounding box; default: [4, 4].",
    )
    layers: int | None = Field(
        None,
        ge=1,
        le=1000,
        json_schema_extra={"dimensions": [2, 3]},
        description=(
            "Horizontal layers of the window, bottom to top (along y in 2D, z in 3D): the "
            "height profile of a packing built from its floor; default: 6."
        ),
    )
    shells: int | None = Field(
        None,
        ge=1,
        le=1000,
        json_schema_extra=SOLID,
        description="Nested boxes about a 3D window's centre; default: 4.",
    )
    margin: float | None = Field(
        None, ge=0, description="Exclusion margin from the walls; default: the scene's d_max."
    )

    @model_validator(mode="after")
    def _check(self) -> HomogeneityConfig:
        if self.ring_width is not None and self.rings is not None:
            raise ValueError("give at most one of ring_width and rings")
        nx, ny = self.tiles or DEFAULT_REGIONS["tiles"]
        if not (1 <= nx <= 100 and 1 <= ny <= 100):
            raise ValueError(f"tiles must be two counts from 1 to 100, got [{nx}, {ny}]")
        return self


@dataclass(frozen=True)
class Trend:
    """Weighted least-squares line ``y = intercept + slope x``.

    Attributes
    ----------
    slope, slope_err
        Slope and its standard error; the error from the given errors, scaled
        up by ``sqrt(chi2_dof)`` when that exceeds 1.
    intercept
        Value at ``x = 0``.
    chi2_dof
        χ² of the residuals per degree of freedom (NaN with fewer than 3 points).
    n
        Points used (finite values with a positive error).
    """

    slope: float
    slope_err: float
    intercept: float
    chi2_dof: float
    n: int


def trend(x: FloatArray, y: FloatArray, err: FloatArray) -> Trend:
    """Fit a straight line to ``y(x)`` with weights ``1 / err^2``.

    Examples
    --------
    >>> t = trend(np.array([0.0, 1.0, 2.0]), np.array([1.0, 3.0, 5.0]), np.ones(3))
    >>> round(t.slope, 12), round(t.intercept, 12), t.chi2_dof
    (2.0, 1.0, 0.0)
    """
    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(err) & (err > 0)
    n = int(ok.sum())
    nan = math.nan
    if n < 2:
        return Trend(nan, nan, nan, nan, n)
    xx, yy, w = x[ok], y[ok], 1.0 / err[ok] ** 2
    s, sx, sy = w.sum(), (w * xx).sum(), (w * yy).sum()
    sxx, sxy = (w * xx * xx).sum(), (w * xx * yy).sum()
    delta = s * sxx - sx * sx
    if not delta > 0:
        return Trend(nan, nan, nan, nan, n)
    slope = (s * sxy - sx * sy) / delta
    intercept = (sxx * sy - sx * sxy) / delta
    chi2_dof = float((w * (yy - intercept - slope * xx) ** 2).sum() / (n - 2)) if n > 2 else nan
    scale = math.sqrt(chi2_dof) if chi2_dof > 1 else 1.0
    return Trend(float(slope), float(math.sqrt(s / delta) * scale), float(intercept), chi2_dof, n)


def region_stats(
    region: IntArray,
    n_regions: int,
    area: FloatArray,
    piece_area: FloatArray,
    diameter: FloatArray,
    mineral: IntArray,
    mineral_names: tuple[str, ...],
    cells: tuple[FloatArray, FloatArray],
) -> dict[str, FloatArray]:
    """Measure number density, φ, mean diameter and mineral fractions per region, with errors.

    Parameters
    ----------
    region
        Region of each particle by its centre (``-1``: in none).
    n_regions
        Number of regions.
    area
        ``(R,)`` area of each region.
    piece_area
        ``(m, R)`` area of each particle piece in each region.
    diameter, mineral
        Equivalent diameter and mineral of each particle (same order as ``region``).
    mineral_names
        Names of the minerals, for the ``frac_<name>`` columns.
    cells
        ``(R, C)`` particle area and window area of the parts of each region
        whose scatter gives the error of its φ
        (:func:`~regopack.plugins.analyzers.regions.scatter_error`).

    Returns
    -------
    dict
        Columns ``area``, ``n``, ``number_density``, ``number_density_err``,
        ``phi``, ``phi_err``, ``mean_d``, ``mean_d_err``, then
        ``frac_<mineral>`` and ``frac_<mineral>_err`` per mineral.
    """
    inside = (region >= 0) & (region < n_regions)
    reg = region[inside]
    n = np.bincount(reg, minlength=n_regions).astype(np.float64)
    d = diameter[inside]
    sum_d = np.bincount(reg, weights=d, minlength=n_regions)
    sum_d2 = np.bincount(reg, weights=d * d, minlength=n_regions)
    with np.errstate(divide="ignore", invalid="ignore"):
        mean_d = np.where(n > 0, sum_d / n, np.nan)
        var = np.where(n > 1, (sum_d2 - n * mean_d**2) / (n - 1), np.nan)
        cols: dict[str, FloatArray] = {
            "area": area,
            "n": n.astype(np.int64),
            "number_density": n / area,
            "number_density_err": np.sqrt(np.maximum(n, 1.0)) / area,
            "phi": piece_area.sum(axis=0) / area,
            "phi_err": scatter_error(*cells),
            "mean_d": mean_d,
            "mean_d_err": np.sqrt(np.maximum(var, 0.0) / n),
        }
        for m, name in enumerate(mineral_names):
            p = np.where(
                n > 0, np.bincount(reg[mineral[inside] == m], minlength=n_regions) / n, np.nan
            )
            cols[f"frac_{name}"] = p
            cols[f"frac_{name}_err"] = np.sqrt(p * (1.0 - p) / n)
    return cols


def _max_rel_dev(values: FloatArray, reference: float) -> float | None:
    ok = np.isfinite(values)
    if not ok.any() or not (math.isfinite(reference) and reference != 0):
        return None
    return float(np.max(np.abs(values[ok] / reference - 1.0)))


def _chi2_dof(values: FloatArray, err: FloatArray) -> float | None:
    """χ² per degree of freedom of the values about their weighted mean."""
    ok = np.isfinite(values) & np.isfinite(err) & (err > 0)
    if ok.sum() < 2:
        return None
    w = 1.0 / err[ok] ** 2
    mean = float((w * values[ok]).sum() / w.sum())
    return float((w * (values[ok] - mean) ** 2).sum() / (ok.sum() - 1))


def _none(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


PLANE_FIELDS = ("ring_width", "rings", "tiles")
"""Parameters that cut a 2D window; ``shells`` cuts a 3D one, ``layers`` either."""


def height_profile(
    height: FloatArray, layers: Mapping[str, Any], overall: Mapping[str, float], per_length: float
) -> dict[str, float | None]:
    """Compare the layers with the whole window and fit their trends with height.

    For each of number density, φ and mean diameter: the largest relative
    deviation of a layer from the window's value (``layer_<q>_max_rel_dev``),
    the χ² per degree of freedom of the layers about their weighted mean
    (``layer_<q>_chi2_dof``: about 1 when they differ by their sampling
    errors only), and the weighted straight line against the layers' mid
    heights (``layer_<q>_slope_per_100`` and its error, per ``per_length``).
    """
    out: dict[str, float | None] = {}
    for prefix, column in QUANTITIES:
        values = np.asarray(layers[column], dtype=np.float64)
        err = np.asarray(layers[f"{column}_err"], dtype=np.float64)
        fit = trend(height, values, err)
        out[f"layer_{prefix}_max_rel_dev"] = _max_rel_dev(values, overall[column])
        out[f"layer_{prefix}_chi2_dof"] = _chi2_dof(values, err)
        out[f"layer_{prefix}_slope_per_100"] = _none(fit.slope * per_length)
        out[f"layer_{prefix}_slope_err"] = _none(fit.slope_err * per_length)
    return out


SHELL_QUANTITIES: tuple[tuple[str, str], ...] = (
    ("density", "number_density"),
    ("mean_d", "mean_d"),
)
"""The quantities of a 3D window's shells that carry sampling errors (prefix, column)."""


def shell_profile(
    shells: Mapping[str, Any], overall: Mapping[str, float]
) -> dict[str, float | None]:
    """Compare a 3D window's shells with the whole window, as :func:`height_profile` the layers.

    For number density and mean diameter: the largest relative deviation of a
    shell from the window's value (``shell_<q>_max_rel_dev``) and the χ² per
    degree of freedom of the shells about their weighted mean
    (``shell_<q>_chi2_dof``: about 1 when they differ by their sampling errors only).
    """
    out: dict[str, float | None] = {}
    for prefix, column in SHELL_QUANTITIES:
        values = np.asarray(shells[column], dtype=np.float64)
        err = np.asarray(shells[f"{column}_err"], dtype=np.float64)
        out[f"shell_{prefix}_max_rel_dev"] = _max_rel_dev(values, overall[column])
        out[f"shell_{prefix}_chi2_dof"] = _chi2_dof(values, err)
    return out


class Homogeneity(Measured):
    """Number density, φ, mean diameter (and mineral fractions) over the regions of the window.

    In 2D, over rings and tiles: after :meth:`compute`, :attr:`rings` and
    :attr:`tiles_table` hold the tables, :attr:`trends` the fitted lines (by
    quantity prefix, in length units, not per 100), :attr:`overall` the
    values over the whole window, :attr:`window` the interior window and
    :attr:`centre` the ring centre. In 3D, over horizontal layers and nested
    boxes: :attr:`layers` and :attr:`shells` hold the tables.
    """

    name = "homogeneity"

    def __init__(self, config: HomogeneityConfig | None = None) -> None:
        self.config = config or HomogeneityConfig()
        self._tables: dict[str, dict[str, Any]] = {}
        self.rings: dict[str, Any] = {}
        self.tiles_table: dict[str, Any] = {}
        self.trends: dict[str, Trend] = {}
        self.overall: dict[str, float] = {}
        self.layers: dict[str, Any] = {}

    def _ring_width(self, packing: Packing, window: PlaneDomain) -> float:
        near, far = window_reach(window, self.centre)
        if self.config.rings is not None:
            return far / self.config.rings
        if self.config.ring_width is not None:
            given = self.config.ring_width
            hint = f"give a ring width of at least {far / MAX_RINGS:.6g} or set rings"
            derived_count(far / given, "rings", MAX_RINGS, field=RING_FIELD, given=given, hint=hint)
            return given
        d_max = interior_margin(packing, None)
        quarter = near / 4 if near > 0 else far / 4
        return min(2.0 * d_max, quarter) if d_max > 0 else quarter

    def compute(self, packing: Packing, context: Mapping[str, Analyzer]) -> Self:
        """Cut the window into regions and measure each; in 2D, fit the radial trends."""
        own = ("layers", "shells") if packing.dimension == 3 else (*PLANE_FIELDS, "layers")
        other = set(PLANE_FIELDS + ("layers", "shells")) - set(own)
        given = sorted(f for f in other if getattr(self.config, f) is not None)
        if given:
            raise ConfigError(
                f"{self.name}.{given[0]} has no meaning for a {packing.domain.dimension}D "
                f"packing; its regions are set by {', '.join(own)}"
            )
        margin = interior_margin(packing, self.config.margin)
        window = interior_window(packing, margin)
        self.window = window
        if packing.dimension == 3:
            layers = self.config.layers or DEFAULT_REGIONS["layers"]
            shells = self.config.shells or DEFAULT_REGIONS["shells"]
            measure = (
                layers_and_shells_cylinder if isinstance(window, Cylinder) else layers_and_shells
            )
            self._tables, self._results = measure(packing, window, margin, layers, shells)
            self.layers = self._tables["homogeneity_layers"]
            self.shells = self._tables["homogeneity_shells"]
            overall = {
                key: math.nan if self._results[key] is None else self._results[key]
                for key in ("number_density", "phi", "mean_d")
            }
            per_length = PER_LENGTH * length_scale(packing)
            self._results["slope_length"] = per_length
            self._results["layers"] = len(self.layers["z_lo"])
            self._results.update(
                height_profile(
                    0.5 * (self.layers["z_lo"] + self.layers["z_hi"]),
                    self.layers,
                    overall,
                    per_length,
                )
            )
            self._results.update(shell_profile(self.shells, overall))
            return self
        self.centre = packing.domain.center
        names = packing.mineral_names
        idx = np.flatnonzero(packing.placed).astype(np.int64)
        centre_xy = packing.centre[idx]
        inside = window.contains(centre_xy) if window.area > 0 else np.zeros(len(idx), bool)
        diameter = 2.0 * packing.radius[idx]
        mineral = packing.mineral[idx]
        pieces = window_pieces(packing, window)
        notes: list[str] = []

        # rings
        width = self._ring_width(packing, window) if window.area > 0 else 0.0
        edges = ring_edges(window, self.centre, width)
        k = len(edges) - 1
        rho = np.hypot(centre_xy[:, 0] - self.centre[0], centre_xy[:, 1] - self.centre[1])
        ring_of = np.clip(np.searchsorted(edges, rho, side="right") - 1, 0, max(k - 1, 0))
        ring_of = np.where(inside & (k > 0), ring_of, -1).astype(np.int64)
        ring_area = ring_window_areas(window, self.centre, edges)
        ring_pieces = ring_piece_areas(pieces, self.centre, edges)
        sectors = ring_sector_areas(pieces, window, self.centre, edges, SECTORS)
        rings = region_stats(ring_of, k, ring_area, ring_pieces, diameter, mineral, names, sectors)
        r_mean = np.array(
            [ring_mean_radius(window, self.centre, edges[j], edges[j + 1]) for j in range(k)]
        )
        self.rings = {
            "ring": np.arange(k, dtype=np.int64),
            "r_inner": edges[:-1],
            "r_outer": edges[1:],
            "r_mean": r_mean,
            **rings,
        }

        # tiles
        nx, ny = self.config.tiles or DEFAULT_REGIONS["tiles"]
        grid = (centre_xy, inside, window, pieces, diameter, mineral, names)
        tiles, tile_stats = self._grid_stats(*grid, nx, ny)
        self.tiles_table = {
            "tile": np.arange(len(tiles.area), dtype=np.int64),
            "ix": tiles.ix,
            "iy": tiles.iy,
            "x_min": tiles.bounds[:, 0],
            "x_max": tiles.bounds[:, 1],
            "y_min": tiles.bounds[:, 2],
            "y_max": tiles.bounds[:, 3],
            **tile_stats,
        }

        # layers: the height profile
        n_layers = self.config.layers or DEFAULT_REGIONS["layers"]
        bands, layer_stats = self._grid_stats(*grid, 1, n_layers)
        self.layers = {
            "layer": np.arange(len(bands.area), dtype=np.int64),
            "y_min": bands.bounds[:, 2],
            "y_max": bands.bounds[:, 3],
            **layer_stats,
        }

        # the whole window, the trends and the spread
        whole = region_stats(
            np.where(inside, 0, -1).astype(np.int64),
            1,
            np.array([window.area]),
            ring_pieces.sum(axis=1, keepdims=True),
            diameter,
            mineral,
            names,
            (sectors[0].reshape(1, -1), sectors[1].reshape(1, -1)),
        )
        self.overall = {key: float(v[0]) for key, v in whole.items()}
        per_length = PER_LENGTH * length_scale(packing)
        res: dict[str, Any] = {
            "interior_margin": margin,
            "eta": eta_of(packing),
            "window_kind": window.kind,
            "window_area": float(window.area),
            "centre": [float(self.centre[0]), float(self.centre[1])],
            "ring_width": float(width),
            "n_rings": k,
            "tiles": [nx, ny],
            "n_tiles": len(tiles.area),
            "n_interior": int(inside.sum()),
            "slope_length": per_length,
        }
        for key in ("number_density", "phi", "mean_d"):
            res[key] = _none(self.overall[key])
            res[f"{key}_err"] = _none(self.overall[f"{key}_err"])
        for prefix, column in QUANTITIES:
            fit = trend(r_mean, self.rings[column], self.rings[f"{column}_err"])
            self.trends[prefix] = fit
            res[f"{prefix}_slope_per_100"] = _none(fit.slope * per_length)
            res[f"{prefix}_slope_err"] = _none(fit.slope_err * per_length)
            res[f"{prefix}_trend_chi2_dof"] = _none(fit.chi2_dof)
            res[f"{prefix}_max_rel_dev"] = _max_rel_dev(self.rings[column], self.overall[column])
        res["layers"] = len(bands.area)
        res.update(
            height_profile(
                0.5 * (bands.bounds[:, 2] + bands.bounds[:, 3]),
                self.layers,
                self.overall,
                per_length,
            )
        )
        for prefix, column in QUANTITIES:
            res[f"tile_{prefix}_max_rel_dev"] = _max_rel_dev(
                self.tiles_table[column], self.overall[column]
            )
            res[f"tile_{prefix}_chi2_dof"] = _chi2_dof(
                self.tiles_table[column], self.tiles_table[f"{column}_err"]
            )
        slopes: dict[str, float | None] = {}
        errs: dict[str, float | None] = {}
        n_ring = np.asarray(self.rings["n"], dtype=np.float64)
        for name in names:
            # errors from the window's fraction, so that rings without the mineral count too
            p = self.overall[f"frac_{name}"]
            with np.errstate(divide="ignore", invalid="ignore"):
                err = np.sqrt(p * (1.0 - p) / n_ring)
            fit = trend(r_mean, self.rings[f"frac_{name}"], err)
            slopes[name] = _none(fit.slope * per_length)
            errs[name] = _none(fit.slope_err * per_length)
        res["fraction_slope_per_100"] = slopes
        res["fraction_slope_err"] = errs
        if not window.area > 0:
            notes.append(f"the interior window is empty (margin {margin:g})")
        elif k < 3:
            notes.append(f"only {k} ring(s): no trend error without 3 rings or more")
        res["notes"] = notes
        self._results = res
        self._tables = {
            "homogeneity_rings": self.rings,
            "homogeneity_tiles": self.tiles_table,
            "homogeneity_layers": self.layers,
        }
        return self

    @classmethod
    def _grid_stats(
        cls,
        xy: FloatArray,
        inside: NDArray[np.bool_],
        window: PlaneDomain,
        pieces: Any,
        diameter: FloatArray,
        mineral: IntArray,
        names: tuple[str, ...],
        nx: int,
        ny: int,
    ) -> tuple[Tiles, dict[str, FloatArray]]:
        """Cut the window into an ``nx`` by ``ny`` grid (tiles, or layers when ``nx`` is 1)."""
        cells: Tiles = tile_grid(window, nx, ny)
        stats = region_stats(
            cls._tile_of(xy, inside, cells, window, nx, ny),
            len(cells.area),
            cells.area,
            tile_piece_areas(pieces, cells),
            diameter,
            mineral,
            names,
            tile_cell_areas(pieces, window, cells, TILE_SPLIT),
        )
        return cells, stats

    @staticmethod
    def _tile_of(
        xy: FloatArray,
        inside: NDArray[np.bool_],
        tiles: Tiles,
        window: PlaneDomain,
        nx: int,
        ny: int,
    ) -> IntArray:
        """Tile of each centre in the window (``-1``: none or a left-out tile)."""
        out = np.full(len(xy), -1, dtype=np.int64)
        if len(tiles.area) == 0:
            return out
        x0, x1, y0, y1 = (float(b) for b in window.bounds())
        ix = np.clip(np.floor((xy[:, 0] - x0) / (x1 - x0) * nx), 0, nx - 1)
        iy = np.clip(np.floor((xy[:, 1] - y0) / (y1 - y0) * ny), 0, ny - 1)
        cell = np.full(nx * ny, -1, dtype=np.int64)
        cell[tiles.iy * nx + tiles.ix] = np.arange(len(tiles.area))
        ok = inside & np.isfinite(ix) & np.isfinite(iy)
        out[ok] = cell[(iy[ok] * nx + ix[ok]).astype(np.int64)]
        return out

    def tables(self) -> dict[str, dict[str, Any]]:
        """Tables ``homogeneity_rings``, ``_tiles``, ``_layers`` (3D: ``_layers``, ``_shells``)."""
        self._need()
        return {name: dict(table) for name, table in self._tables.items()}
