"""Built-in structure analyzers (the paper's Stage 3).

Density, contacts, coordination, rdf, network, homogeneity, psd and local_fraction.
"""

from __future__ import annotations

from collections.abc import Iterable

from regopack.hookspecs import hookimpl
from regopack.plugin_types import AnalyzerSpec, FigureSpec
from regopack.plugins.analysis.contacts import Contacts, ContactsConfig
from regopack.plugins.analysis.coordination import Coordination, CoordinationConfig
from regopack.plugins.analysis.density import Density, DensityConfig
from regopack.plugins.analysis.figure_specs import figure_specs
from regopack.plugins.analysis.homogeneity import Homogeneity, HomogeneityConfig
from regopack.plugins.analysis.local_fraction import LocalFraction, LocalFractionConfig
from regopack.plugins.analysis.network import Network, NetworkConfig
from regopack.plugins.analysis.psd import Psd, PsdConfig
from regopack.plugins.analysis.rdf import Rdf, RdfConfig


@hookimpl
def regopack_analyzers() -> Iterable[AnalyzerSpec]:
    """Register the built-in analyzers."""
    return [
        AnalyzerSpec(
            "density", DensityConfig, Density, "Packing density over the domain and the interior."
        ),
        AnalyzerSpec(
            "contacts", ContactsConfig, Contacts, "Contacts at tol with the bow-shaped model."
        ),
        AnalyzerSpec(
            "coordination", CoordinationConfig, Coordination, "Coordination numbers and Z(tol)."
        ),
        AnalyzerSpec(
            "rdf", RdfConfig, Rdf, "Radial distribution function, total and per mineral pair."
        ),
        AnalyzerSpec(
            "network", NetworkConfig, Network, "Contact network and fabric of the contact normals."
        ),
        AnalyzerSpec(
            "homogeneity",
            HomogeneityConfig,
            Homogeneity,
            "Density, area fraction, size and minerals over rings and tiles; radial trends.",
        ),
        AnalyzerSpec(
            "psd",
            PsdConfig,
            Psd,
            "Size distribution of the placed particles against the requested one, by sieve class.",
        ),
        AnalyzerSpec(
            "local_fraction",
            LocalFractionConfig,
            LocalFraction,
            "Local packing fraction of every particle from its Laguerre or Voronoi cell.",
        ),
    ]


@hookimpl
def regopack_analysis_figures() -> Iterable[FigureSpec]:
    """Register the figures of the built-in analyzers (drawn with matplotlib)."""
    return figure_specs()
