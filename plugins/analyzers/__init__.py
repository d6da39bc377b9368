"""Built-in structure analyzers (the paper's Stage 3).

Density, contacts, coordination, rdf, network, homogeneity, psd and local_fraction of
2D packings; density3d, contacts3d, coordination3d, rdf3d, network3d, homogeneity3d and
psd3d of 3D ones.
"""

from __future__ import annotations

from collections.abc import Iterable

from regopack.plugins.analyzers.contacts import Contacts, ContactsConfig
from regopack.plugins.analyzers.contacts3d import Contacts3D, Contacts3DConfig
from regopack.plugins.analyzers.coordination import Coordination, CoordinationConfig
from regopack.plugins.analyzers.coordination3d import Coordination3D, Coordination3DConfig
from regopack.plugins.analyzers.density import Density, DensityConfig
from regopack.plugins.analyzers.density3d import Density3D, Density3DConfig
from regopack.plugins.analyzers.figure_specs import figure_specs
from regopack.plugins.analyzers.homogeneity import Homogeneity, HomogeneityConfig
from regopack.plugins.analyzers.homogeneity3d import Homogeneity3D, Homogeneity3DConfig
from regopack.plugins.analyzers.local_fraction import LocalFraction, LocalFractionConfig
from regopack.plugins.analyzers.network import Network, NetworkConfig
from regopack.plugins.analyzers.network3d import Network3D, Network3DConfig
from regopack.plugins.analyzers.psd import Psd, PsdConfig
from regopack.plugins.analyzers.psd3d import Psd3D, Psd3DConfig
from regopack.plugins.analyzers.rdf import Rdf, RdfConfig
from regopack.plugins.analyzers.rdf3d import Rdf3D, Rdf3DConfig
from regopack.registry.hookspecs import hookimpl
from regopack.registry.plugin_types import AnalyzerSpec, FigureSpec


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
        AnalyzerSpec(
            "density3d",
            Density3DConfig,
            Density3D,
            "Volume fraction of a 3D packing over the box and the interior.",
            dimensions=(3,),
        ),
        AnalyzerSpec(
            "contacts3d",
            Contacts3DConfig,
            Contacts3D,
            "Contacts of polyhedra at tol: area, volume, normal and the equivalent spherical cap.",
            dimensions=(3,),
        ),
        AnalyzerSpec(
            "coordination3d",
            Coordination3DConfig,
            Coordination3D,
            "Coordination numbers of a 3D packing, Z(tol), rattlers.",
            dimensions=(3,),
        ),
        AnalyzerSpec(
            "rdf3d",
            Rdf3DConfig,
            Rdf3D,
            "Radial distribution function of a 3D packing, total and per mineral pair.",
            dimensions=(3,),
        ),
        AnalyzerSpec(
            "network3d",
            Network3DConfig,
            Network3D,
            "Contact network of a 3D packing and the fabric tensor of its contact normals.",
            dimensions=(3,),
        ),
        AnalyzerSpec(
            "homogeneity3d",
            Homogeneity3DConfig,
            Homogeneity3D,
            "Density, volume fraction and size of a 3D packing over layers and nested boxes.",
            dimensions=(3,),
        ),
        AnalyzerSpec(
            "psd3d",
            Psd3DConfig,
            Psd3D,
            "Size distribution of the placed solids against the drawn ones, by number and volume.",
            dimensions=(3,),
        ),
    ]


@hookimpl
def regopack_analysis_figures() -> Iterable[FigureSpec]:
    """Register the figures of the built-in analyzers (drawn with matplotlib)."""
    return figure_specs()
