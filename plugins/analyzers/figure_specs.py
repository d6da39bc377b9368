"""Which figures the built-in analyzers draw, for the analysis folder.

:func:`figure_specs` gives one :class:`~regopack.registry.plugin_types.FigureSpec` per
analyzer that has figures, in the order the figures are drawn; the plugin
returns them from :func:`regopack.registry.hookspecs.regopack_analysis_figures`. The
drawing itself lives in :mod:`regopack.plugins.analyzers.figures`, which is
imported (with matplotlib) only when a figure is drawn. An analyzer draws
the figures of :data:`STEMS` for a 2D packing and those of :data:`STEMS3D`
for a 3D one; the old 3D names (``contacts3d``, ...) keep figure specs of
their own, after the others, for as long as they are accepted.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from regopack.packing.core import Packing
from regopack.registry.interfaces import Analyzer
from regopack.registry.plugin_types import FigureMaker, FigureSpec

__all__ = ["CAPTIONS", "CAPTIONS3D", "STEMS", "STEMS3D", "figure_specs"]

CAPTIONS: dict[str, str] = {
    "packing": "Packing coloured by mineral, with a zoomed view (cf. paper Fig. 10)",
    "contact-network": "Contact network, line width proportional to A_c (cf. paper Fig. 12)",
    "contact-histograms": "Distributions of A_c, b_c, R_c and δ (cf. paper Fig. 13)",
    "z-vs-tol": "Coordination number against the contact tolerance (cf. paper Fig. 14)",
    "z-per-mineral": "Coordination number per mineral (cf. paper Fig. 15)",
    "rdf": "Radial distribution function per mineral, near and far field (cf. paper Fig. 16)",
    "homogeneity": "Number density, area fraction and mean diameter over rings and tiles",
    "psd": "Size distribution of the placed particles against the requested one",
    "local-fraction": "Local packing fraction of the particles from their Laguerre cells",
}
"""Caption of each figure, by file stem."""

CAPTIONS3D: dict[str, str] = {
    "contact-histograms-3d": "Distributions of A_c, V_c, b_c and the cap height δ (3D)",
    "z-vs-tol-3d": "Coordination number against the contact tolerance (3D)",
    "z-per-mineral-3d": "Coordination number per mineral (3D)",
    "rdf-3d": "Radial distribution function, all centres and each mineral with itself (3D)",
    "psd-3d": "Size distribution of the placed solids against the requested one, by volume (3D)",
    "homogeneity-3d": "Number density, volume fraction and mean diameter by layer and shell (3D)",
}
"""Caption of each figure of the 3D analyzers, by file stem."""

STEMS: dict[str, tuple[str, ...]] = {
    "density": ("packing",),
    "network": ("contact-network",),
    "contacts": ("contact-histograms",),
    "coordination": ("z-vs-tol", "z-per-mineral"),
    "rdf": ("rdf",),
    "homogeneity": ("homogeneity",),
    "psd": ("psd",),
    "local_fraction": ("local-fraction",),
}
"""File stems of the figures of each analyzer, in drawing order."""

STEMS3D: dict[str, tuple[str, ...]] = {
    "contacts": ("contact-histograms-3d",),
    "coordination": ("z-vs-tol-3d", "z-per-mineral-3d"),
    "rdf": ("rdf-3d",),
    "psd": ("psd-3d",),
    "homogeneity": ("homogeneity-3d",),
}
"""File stems of the figures of each analyzer of a 3D packing, in drawing order."""


def _maker(stems: tuple[str, ...]) -> FigureMaker:
    def draw(packing: Packing, analyzers: Mapping[str, Analyzer], out_dir: Path) -> Sequence[Path]:
        from regopack.plugins.analyzers.figures import figures_for

        return figures_for(packing, analyzers, out_dir, stems=stems)

    return draw


def _spec(name: str, stems: tuple[str, ...]) -> FigureSpec:
    captions = {stem: {**CAPTIONS, **CAPTIONS3D}[stem] for stem in stems}
    return FigureSpec(name, _maker(stems), captions)


def figure_specs() -> list[FigureSpec]:
    """One figure spec per analyzer of :data:`STEMS`, then per old 3D name, in drawing order.

    Examples
    --------
    >>> [(f.analyzer, list(f.captions)) for f in figure_specs()][3]
    ('coordination', ['z-vs-tol', 'z-per-mineral', 'z-vs-tol-3d', 'z-per-mineral-3d'])
    >>> [f.analyzer for f in figure_specs()][-5:]
    ['contacts3d', 'coordination3d', 'rdf3d', 'psd3d', 'homogeneity3d']
    """
    both = [_spec(name, stems + STEMS3D.get(name, ())) for name, stems in STEMS.items()]
    return both + [_spec(f"{name}3d", stems) for name, stems in STEMS3D.items()]
