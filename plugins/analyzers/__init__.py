"""Built-in structure analyzers (the paper's Stage 3).

Density, contacts, coordination, rdf, network, homogeneity and psd of 2D and
3D packings, local_fraction of 2D ones. The 3D analyzers' old names
(``contacts3d``, ...) select the same analyzers for one release, with a
deprecation warning; their results keep those names.
"""

from __future__ import annotations

from collections.abc import Iterable

from regopack.plugins.analyzers.contacts import Contacts, ContactsConfig
from regopack.plugins.analyzers.coordination import Coordination, CoordinationConfig
from regopack.plugins.analyzers.density import Density, DensityConfig
from regopack.plugins.analyzers.figure_specs import figure_specs
from regopack.plugins.analyzers.homogeneity import Homogeneity, HomogeneityConfig
from regopack.plugins.analyzers.local_fraction import LocalFraction, LocalFractionConfig
from regopack.plugins.analyzers.network import Network, NetworkConfig
from regopack.plugins.analyzers.psd import Psd, PsdConfig
from regopack.plugins.analyzers.rdf import Rdf, RdfConfig
from regopack.registry.hookspecs import hookimpl
from regopack.registry.plugin_types import AnalyzerSpec, FigureSpec

BOTH = (2, 3)


@hookimpl
def regopack_analyzers() -> Iterable[AnalyzerSpec]:
    """Register the built-in analyzers."""
    return [
        AnalyzerSpec(
            "density",
            DensityConfig,
            Density,
            "Packing density (area or volume fraction) over the domain and the interior.",
            dimensions=BOTH,
            aliases=("density3d",),
            alias_dimensions=(3,),
        ),
        AnalyzerSpec(
            "contacts",
            ContactsConfig,
            Contacts,
            "Contacts at tol: the bow-shaped model in 2D, area, volume and spherical cap in 3D.",
            dimensions=BOTH,
            aliases=("contacts3d",),
            alias_dimensions=(3,),
        ),
        AnalyzerSpec(
            "coordination",
            CoordinationConfig,
            Coordination,
            "Coordination numbers, Z(tol) and rattlers.",
            dimensions=BOTH,
            aliases=("coordination3d",),
            alias_dimensions=(3,),
        ),
        AnalyzerSpec(
            "rdf",
            RdfConfig,
            Rdf,
            "Radial distribution function, total and per mineral pair.",
            dimensions=BOTH,
            aliases=("rdf3d",),
            alias_dimensions=(3,),
        ),
        AnalyzerSpec(
            "network",
            NetworkConfig,
            Network,
            "Contact network and fabric of the contact normals.",
            dimensions=BOTH,
            aliases=("network3d",),
            alias_dimensions=(3,),
        ),
        AnalyzerSpec(
            "homogeneity",
            HomogeneityConfig,
            Homogeneity,
            "Density, solid fraction, size (and minerals) over rings and tiles, or layers "
            "and shells in 3D.",
            dimensions=BOTH,
            aliases=("homogeneity3d",),
            alias_dimensions=(3,),
        ),
        AnalyzerSpec(
            "psd",
            PsdConfig,
            Psd,
            "Size distribution of the placed particles against the requested one, by sieve class.",
            dimensions=BOTH,
            aliases=("psd3d",),
            alias_dimensions=(3,),
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
