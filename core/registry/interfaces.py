"""Interfaces of the six plugin kinds.

A plugin supplies an implementation of one of these classes through a spec
record (:mod:`regopack.registry.plugin_types`). The core never depends on a concrete
implementation.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Generic, Self, TypeVar

import numpy as np
from numpy.typing import NDArray

from regopack.geometry.domain import Domain
from regopack.geometry.population import Population, ShapeBatch
from regopack.geometry.solids import SolidBatch

if TYPE_CHECKING:
    from regopack.packing.core import Packing

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
ProgressCallback = Callable[[int, int, int], None]
"""Called as ``progress(done, placed, total)`` while particles are inserted."""


class SizeDistribution(ABC):
    """Distribution of equivalent particle radii."""

    @abstractmethod
    def sample(self, n: int, rng: np.random.Generator) -> FloatArray:
        """Draw ``n`` equivalent radii (area = pi r^2)."""

    @property
    @abstractmethod
    def mean_area(self) -> float:
        """Expected particle area E[pi r^2]; sets the particle count of ``count = "auto"``."""

    @property
    def mean_volume(self) -> float:
        """Expected particle volume E[4/3 pi r^3]; sets ``count = "auto"`` of a 3D scene.

        NaN (the default) when the distribution does not know it: a 3D scene
        with this distribution then needs an explicit ``count``.
        """
        return math.nan

    @property
    @abstractmethod
    def r_min(self) -> float:
        """Smallest radius the distribution can return."""

    @property
    @abstractmethod
    def r_max(self) -> float:
        """Largest radius the distribution can return."""


class ShapeGenerator(ABC):
    """Generator of convex particle outlines of prescribed area."""

    @abstractmethod
    def generate(self, radius: FloatArray, rng: np.random.Generator) -> ShapeBatch:
        """Return one convex outline per radius, of area ``pi r^2``.

        Outlines are counter-clockwise and relative to the particle's reference
        point, which must lie strictly inside.
        """


class SolidGenerator(ABC):
    """Generator of convex solids of prescribed volume (the shapes of 3D scenes)."""

    @abstractmethod
    def generate(self, radius: FloatArray, rng: np.random.Generator) -> SolidBatch:
        """Return one convex solid per radius, of volume ``4/3 pi r^3``.

        Solids are relative to the particle's reference point, which must lie
        strictly inside; every random choice comes from ``rng``.
        """


class DensityController(ABC):
    """Rule that trims available arcs before a centre is sampled on them."""

    identity: bool = False
    """True when :meth:`shrink` never changes the arcs; inserters may then skip it."""

    @abstractmethod
    def shrink(
        self, arcs: FloatArray, r_new: float, r_candidate: float, rng: np.random.Generator
    ) -> FloatArray:
        """Trim arcs.

        Parameters
        ----------
        arcs
            ``(k, 2)`` polar-angle intervals ``[start, end]`` with ``start < end``,
            unwrapped: an arc through the reference angle has ends outside
            ``[-pi, pi]`` (below or above), so ends may be negative or exceed 2 pi.
        r_new, r_candidate
            Equivalent radii of the particle being inserted and of the candidate.
        rng
            The run's generator.

        Returns
        -------
        ndarray
            ``(k', 2)`` arcs, each contained in one of the input arcs; arcs of
            zero or negative length are dropped.
        """


@dataclass
class DensitySearch:
    """How a :class:`DensityTarget` chose its controller.

    Attributes
    ----------
    chosen
        Index into ``tries`` of the packing kept: the first within the
        tolerance, or else the closest to the target (the first of equals).
    tries
        One mapping per packing made, in order: the chosen controller's
        parameters (e.g. ``{"eta": 12.5}``) and the measured ``phi``.
    met
        Whether the kept packing is within the target's tolerance.
    """

    chosen: int
    tries: list[dict[str, float]]
    met: bool


class DensityTarget(DensityController):
    """A density goal (a packing fraction to reach) met by choosing another controller.

    The run packs the scene once per controller :meth:`search` tries, each
    time from the scene's seed, and keeps the packing it chooses: that
    packing is the one the chosen controller gives on its own.
    """

    controls: str = "eta"
    """Kind of the density controller the search chooses (what inserters are checked against)."""

    measure: str = "interior"
    """The packing fraction the goal is about: ``"interior"`` or ``"domain"``."""

    phi: float = math.nan
    """The packing fraction to reach."""

    tolerance: float = 0.0
    """How close to :attr:`phi` the packing kept must be to meet the goal."""

    @abstractmethod
    def search(self, probe: Callable[[DensityController], float]) -> DensitySearch:
        """Choose a controller by packing: ``probe(controller)`` packs and returns its fraction.

        Raises
        ------
        regopack.base.field_error.FieldValueError
            When the goal is out of the scene's reach (one line naming the
            field, its value and the reachable range).
        """

    def shrink(
        self, arcs: FloatArray, r_new: float, r_candidate: float, rng: np.random.Generator
    ) -> FloatArray:
        """Refuse: a target is met by the controller its search chooses, not applied itself."""
        raise TypeError("a density target packs through the controller its search chooses")


@dataclass
class InsertionResult:
    """Outcome of an insertion run.

    Attributes
    ----------
    centre
        ``(n, 2)`` reference-point position of every particle; NaN where not placed.
    insertion_index
        ``(n,)`` order in which particles were placed, ``-1`` where not placed.
    stats
        Counters of the run (e.g. candidate analyses performed) as ``int``,
        and timings or lengths as ``float``; they are written to JSON as they are.
    """

    centre: FloatArray
    insertion_index: IntArray
    stats: dict[str, float] = field(default_factory=dict)

    @property
    def placed(self) -> NDArray[np.bool_]:
        """Mask of the particles that were placed."""
        return self.insertion_index >= 0


@dataclass(frozen=True)
class TileTask:
    """What a tile of a tiled packing packs against (see :mod:`regopack.tiling`).

    Attributes
    ----------
    lo, hi
        The centre window: every placed particle's reference point lies in
        ``[lo, hi]`` (``dimension`` values each; the vertical bounds are the
        domain's). In a periodic domain the window may be given in any image.
    obstacles
        The particles of the tiles packed before this one that the tile's
        particles can reach, already placed: solids (or outlines) relative
        to their reference points, as a population's shapes are.
    obstacle_centre
        ``(m, dimension)`` reference points of the obstacles.
    obstacle_radius
        ``(m,)`` equivalent radii of the obstacles.
    """

    lo: FloatArray
    hi: FloatArray
    obstacles: SolidBatch | ShapeBatch
    obstacle_centre: FloatArray
    obstacle_radius: FloatArray


class InsertionStrategy(ABC):
    """Algorithm that places a population inside a domain without overlaps."""

    steered_by_density: ClassVar[bool] = True
    """Whether the density controller changes what :meth:`pack` places (a
    density target needs it; a strategy that ignores the controller says False)."""

    packs_tiles: ClassVar[bool] = False
    """Whether :meth:`pack_tile` packs one tile of a tiled packing (``tiles`` in a scene)."""

    @abstractmethod
    def pack(
        self,
        population: Population,
        domain: Domain,
        controller: DensityController,
        rng: np.random.Generator,
        progress: ProgressCallback | None = None,
    ) -> InsertionResult:
        """Place the particles in population order; return where each went."""

    def pack_tile(
        self,
        population: Population,
        domain: Domain,
        controller: DensityController,
        rng: np.random.Generator,
        tile: TileTask,
        progress: ProgressCallback | None = None,
    ) -> InsertionResult:
        """Place ``population`` with every centre in ``tile``'s window, against its obstacles.

        The obstacles stay where they are and are neither counted nor
        returned; the result holds the population's particles only. A
        strategy that sets :attr:`packs_tiles` implements it; the default
        refuses.
        """
        raise NotImplementedError(f"{type(self).__name__} does not pack tiles")

    def tile_conflict(self) -> tuple[str, str] | None:
        """Say, before anything is drawn, why this strategy as configured cannot pack tiles.

        Returns ``(field, reason)`` (a dotted scene path such as
        ``insertion.order``) or ``None`` (the default).
        """
        return None

    def scene_conflict(self, shapes: Sequence[str], density: str) -> tuple[str, str] | None:
        """Say, before anything is drawn, why this strategy cannot pack a scene.

        ``shapes`` are the kinds of the phases' shapes, in phase order, and
        ``density`` the kind of the density controller. Returns ``(field,
        reason)``, the field a dotted scene path such as ``density.kind`` or
        ``phases.2.shape.kind``, or ``None`` when nothing is known to conflict
        (the default). :meth:`pack` still refuses what it cannot pack.
        """
        return None

    def may_overlap(self) -> bool:
        """Tell whether this strategy, as configured, can place overlapping particles.

        A run verifies the packing of a strategy that says so (an approximate
        interference test, say) and reports what it finds. The default is
        ``False``: the strategy guarantees overlap-free packings.
        """
        return False


class Analyzer(ABC):
    """Structure analysis of a packing.

    ``compute`` returns ``self``; results are properties or :meth:`results`.
    Analyzers declare the names of the analyzers whose results they need in
    ``requires``; the runner computes those first and passes them in ``context``.
    ``name`` is the registered name; when an analyzer's results are filed
    under another name (an old name it was asked for by), the runner sets
    that name on the instance, for the analyzer's messages.
    """

    name: ClassVar[str] = ""
    requires: ClassVar[tuple[str, ...]] = ()

    @abstractmethod
    def compute(self, packing: Packing, context: Mapping[str, Analyzer]) -> Self:
        """Analyse ``packing``; ``context`` maps required analyzer names to computed ones."""

    @abstractmethod
    def results(self) -> dict[str, Any]:
        """Scalar results (JSON-serialisable) of the last :meth:`compute`."""

    def tables(self) -> dict[str, dict[str, Any]]:
        """Tables of the last :meth:`compute`: name -> column name -> 1-D array.

        Columns of one table have equal length. The default has no tables.
        """
        return {}


P = TypeVar("P", bound="Packing")
"""The packings an exporter takes: ``Packing`` (either dimension) or, say, ``Packing[Box]``."""


class Exporter(ABC, Generic[P]):
    """Writer of a packing in a file format that other programs read.

    One exporter may write packings of both dimensions (its spec,
    :class:`~regopack.registry.plugin_types.ExporterSpec`, lists them in
    ``dimensions``); the type parameter may narrow the packings it takes
    (``Exporter[Packing[Box]]`` for 3D packings only). ``suffix`` is the file
    name suffix (with its dot, e.g. ``".vtp"``) of the main file it writes;
    ``suffixes`` gives another suffix for the packings of a dimension that
    need one (``{3: ".vtu"}``), and the command line names the output with
    :meth:`suffix_for`.
    """

    suffix: str = ""
    suffixes: ClassVar[Mapping[int, str]] = {}

    def suffix_for(self, dimension: int) -> str:
        """Suffix of the main file written for a packing of ``dimension`` (2 or 3).

        ``suffixes[dimension]`` where given, else :attr:`suffix`.
        """
        return self.suffixes.get(dimension, self.suffix)

    @abstractmethod
    def export(
        self,
        packing: P,
        path: Path,
        *,
        analyses: Mapping[str, Analyzer] | None = None,
    ) -> Path:
        """Write ``packing`` to ``path``; return the path of the main file written.

        Parameters
        ----------
        packing
            The packing to write, of a dimension the exporter's spec lists.
        path
            Main output file. An exporter may write companion files beside it,
            named after its stem.
        analyses
            Computed analyzers by name (e.g. ``"coordination"``); an exporter
            may add their per-particle results to the file and ignores the rest.
        """

    def companions(self, path: Path) -> tuple[Path, ...]:
        """Companion files that :meth:`export` writes beside the main file ``path``.

        A run checks that no two of its outputs are one file, so an exporter
        that writes more than its main file lists the others here. The
        default is none.
        """
        return ()

    def read_state(self, packing: P, path: Path) -> P:
        """Return ``packing`` as a run of the exported files left it, read from ``path``.

        An exporter whose files make a program write its particles' final
        state (a DEM code's dump) reads that state back: the same particles,
        moved and turned (:func:`regopack.packing.motion.moved`). The default
        reads none.

        Raises
        ------
        NotImplementedError
            When the exporter reads no state.
        PackingFileError
            One line naming ``path``, when the file is not a state of ``packing``.
        """
        raise NotImplementedError(f"{type(self).__name__} reads no state back")


class _SolidExporter(Exporter[Any]):
    """An :class:`Exporter` of 3D packings, under its deprecated name ``SolidExporter``.

    Kept for one release so that exporters written against it still work;
    subclass :class:`Exporter` instead.
    """


def __getattr__(name: str) -> Any:
    """Give the deprecated ``SolidExporter`` (PEP 562): :class:`Exporter` writes 3D packings too."""
    if name == "SolidExporter":
        from regopack._compat import warn_moved

        warn_moved(f"{__name__}.SolidExporter", f"{__name__}.Exporter")
        return _SolidExporter
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
