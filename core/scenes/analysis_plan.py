"""Planning and computing analyses: which analyzers run, in what order, with what parameters.

:func:`run_analyses` looks the requested analyzers up in a registry, adds
those they require, validates every parameter against the packing (its
dimension and the work a parameter implies) before any is computed, and
computes them requirements first. Writing the results is
:mod:`regopack.analysis.pipeline`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from pydantic import ValidationError

from regopack.base.errors import ConfigError, PluginError
from regopack.base.limits import LimitError
from regopack.base.messages import describe_validation_error
from regopack.registry.interfaces import Analyzer
from regopack.registry.manager import Registry
from regopack.registry.plugin_types import misplaced_field, served_dimensions

if TYPE_CHECKING:
    from regopack.packing.core import Packing

__all__ = [
    "DEFAULT_ANALYSES",
    "DEFAULT_ANALYSES_3D",
    "check_dimension",
    "default_analyses",
    "dimensions_of",
    "plan_analyses",
    "run_analyses",
]

DEFAULT_ANALYSES: tuple[str, ...] = ("density", "contacts", "coordination", "rdf", "network")
"""Analyzers that ``regopack analyze`` runs on a 2D packing when ``--only`` is not given."""

DEFAULT_ANALYSES_3D: tuple[str, ...] = (
    "density3d",
    "contacts3d",
    "coordination3d",
    "rdf3d",
    "network3d",
)
"""Analyzers that ``regopack analyze`` runs on a 3D packing when ``--only`` is not given.

The analyzers of :data:`DEFAULT_ANALYSES`, under their old 3D names, so that
their results keep those names until the names go (requested without a warning).
"""


def default_analyses(packing: Packing) -> tuple[str, ...]:
    """Return the analyzers run by default on ``packing`` (2D or 3D defaults)."""
    return DEFAULT_ANALYSES_3D if packing.dimension == 3 else DEFAULT_ANALYSES


def _known(registry: Registry) -> str:
    return ", ".join(registry.names("analysis")) or "(none)"


def _registered(registry: Registry, name: str, warn: bool = True) -> str:
    """Return the registered name of the analyzer ``name`` (an old name warns, see ``warn``)."""
    if ("analysis", name) not in registry:
        raise ConfigError(f"unknown analyzer {name!r}; known analyzers: {_known(registry)}")
    if warn:
        registry.get("analysis", name)  # an old name warns
    return registry.canonical("analysis", name)


def _build(
    registry: Registry,
    name: str,
    filed: str,
    params: Mapping[str, Any],
    prefix: str,
    params_source: str | None = None,
    dimension: int = 2,
    source: str | None = None,
    given: Iterable[str] = (),
) -> Analyzer:
    """Validate ``params`` with the config model of the analyzer ``name`` and build it.

    The analyzer's :attr:`~regopack.registry.interfaces.Analyzer.name` becomes
    ``filed``, the name its results are filed under (when it differs from the
    class's). ``prefix`` (the name the parameters were given for) and
    ``params_source`` (e.g. ``--set``) start the message refusing a parameter;
    a parameter of another dimension than ``dimension`` is refused too,
    located by ``params_source`` when it is among ``given`` (the parameters
    from there), by ``source`` otherwise.
    """
    spec = registry.get("analysis", name)
    try:
        config = spec.config_model.model_validate(dict(params))
    except ValidationError as err:
        raise ConfigError(
            describe_validation_error(
                err, source=params_source, prefix=(prefix,), model=spec.config_model
            )
        ) from err
    misplaced = misplaced_field(config, dimension)
    if misplaced is not None:
        field, line = misplaced
        where = params_source if field in given else source
        raise ConfigError(f"{where + ': ' if where else ''}{prefix}.{line}")
    analyzer = spec.factory(config)
    if not isinstance(analyzer, Analyzer):
        origin = registry.origin("analysis", name)
        raise PluginError(
            f"analysis plugin {name!r} ({origin}) built a {type(analyzer).__name__}, "
            "not an Analyzer"
        )
    if analyzer.name != filed:
        setattr(analyzer, "name", filed)  # noqa: B010 (a class variable, set on this instance)
    return analyzer


def dimensions_of(registry: Registry, name: str) -> tuple[int, ...]:
    """Dimensions of the packings that the analyzer ``name`` (or an old name) analyses.

    An old name serves the dimensions it served before (``contacts3d``: 3D),
    when its spec says so (:attr:`~regopack.registry.plugin_types.PluginSpec.alias_dimensions`).
    """
    return served_dimensions(registry.get("analysis", registry.canonical("analysis", name)), name)


def _fitting(registry: Registry, dimension: int) -> str:
    names = [n for n in registry.names("analysis") if dimension in dimensions_of(registry, n)]
    return ", ".join(names) or "(none)"


def check_dimension(
    registry: Registry, names: Iterable[str], dimension: int, source: str | None = None
) -> None:
    """Refuse, in one line, an analyzer that does not analyse packings of ``dimension``.

    Unknown names are left to the planning, which lists the known ones.
    ``source`` (a file and key, or an option) starts the message.
    """
    for name in names:
        if ("analysis", name) not in registry:
            continue
        dims = dimensions_of(registry, name)
        if dimension not in dims:
            where = f"{source}: " if source else ""
            fits = " or ".join(f"{d}D" for d in dims)
            raise ConfigError(
                f"{where}analyzer {name!r} analyses {fits} packings, not {dimension}D ones; "
                f"analyzers of {dimension}D packings: {_fitting(registry, dimension)}"
            )


def _filed_requirement(registry: Registry, requirement: str, needed_by: str, asked: str) -> str:
    """Name a requirement is filed under: its first old name when ``asked`` is an old name.

    An analyzer asked for by its old name (``coordination3d``) files what it
    requires under the old name too (``contacts3d``), as before the names merged.
    """
    if asked == needed_by:
        return requirement
    spec = registry.get("analysis", requirement)
    return spec.aliases[0] if spec.aliases else requirement


def plan_analyses(
    registry: Registry,
    requests: Sequence[tuple[str, Mapping[str, Any]]],
    params: Mapping[str, Mapping[str, Any]],
    dimension: int = 2,
    source: str | None = None,
    params_source: str | None = None,
    warn: bool = True,
) -> dict[str, Analyzer]:
    """Build every analyzer to run, requirements before the analyzers needing them.

    Analyzers are known by their registered names; each is filed under the
    name it was asked for (see :func:`_filed_requirement` for the others).
    Nothing is computed: a run makes the plan before packing, so that what the
    analyses would refuse is refused first. Arguments and errors as
    :func:`run_analyses`, with the packing's ``dimension``.
    """
    asked: dict[str, str] = {}
    wanted: dict[str, dict[str, Any]] = {}
    for name, request_params in requests:
        new = _registered(registry, name, warn)
        first = asked.setdefault(new, name)
        if first != name:
            where = f"{source}: " if source else ""
            raise ConfigError(
                f"{where}analyzers {first!r} and {name!r} are one analyzer ({new!r}); "
                "ask for it once"
            )
        wanted.setdefault(new, {}).update(request_params)
    given: dict[str, dict[str, Any]] = {}
    given_as: dict[str, str] = {}
    for name, fields in params.items():
        new = _registered(registry, name)
        first = given_as.setdefault(new, name)
        if first != name:
            where = f"{params_source}: " if params_source else ""
            raise ConfigError(
                f"{where}parameters given for {first!r} and for {name!r}, which are one "
                f"analyzer ({new!r}); give them under one name"
            )
        given.setdefault(new, {}).update(fields)
    check_dimension(registry, [*asked.values(), *params], dimension, source)

    planned: dict[str, Analyzer] = {}
    filed_as: dict[str, str] = {}

    def visit(name: str, filed: str, chain: tuple[str, ...]) -> None:
        if name in filed_as:
            return
        if name in chain:
            cycle = " -> ".join((*chain, name))
            raise PluginError(f"analyzers require each other in a cycle: {cycle}")
        check_dimension(registry, [name], dimension, source)
        merged = {**wanted.get(name, {}), **given.get(name, {})}
        prefix = given_as.get(name, filed)
        analyzer = _build(
            registry,
            name,
            filed,
            merged,
            prefix,
            params_source,
            dimension,
            source,
            given.get(name, {}),
        )
        for requirement in analyzer.requires:
            if ("analysis", requirement) not in registry:
                raise PluginError(
                    f"analyzer {filed!r} requires {requirement!r}, which is not registered; "
                    f"known analyzers: {_known(registry)}"
                )
            new = _registered(registry, requirement)  # an old name here warns too
            required_as = (
                asked.get(new)
                or (requirement if requirement != new else None)  # required by an old name
                or _filed_requirement(registry, new, name, filed)
            )
            visit(new, required_as, (*chain, name))
        planned[filed] = analyzer
        filed_as[name] = filed

    for name, filed in asked.items():
        visit(name, filed, ())
    unused = [given_as[name] for name in given if name not in filed_as]
    if unused:
        raise ConfigError(
            f"parameters given for analyzer {unused[0]!r}, which is not run "
            f"(running: {', '.join(planned) or 'none'})"
        )
    return planned


def run_analyses(
    packing: Packing,
    registry: Registry,
    requests: Sequence[tuple[str, Mapping[str, Any]]],
    *,
    params: Mapping[str, Mapping[str, Any]] | None = None,
    source: str | None = None,
    params_source: str | None = None,
    warn: bool = True,
    computed: Mapping[str, Analyzer] | None = None,
) -> dict[str, Analyzer]:
    """Compute the requested analyzers and those they require, requirements first.

    Parameters
    ----------
    packing
        The packing to analyse.
    registry
        Registry the analyzers are looked up in (``kind = "analysis"``).
    requests
        ``(name, parameters)`` pairs. An analyzer that another one requires is
        computed once; when it is also requested, it keeps the requested
        parameters, and otherwise it uses its defaults. A name requested twice
        gets the parameters of both requests (the later wins). An old name of
        an analyzer (``contacts3d``) warns and files the results under it, and
        what that analyzer requires under their old names too.
    params
        Parameters by analyzer name (or old name), applied over ``requests``; they also reach
        analyzers that run only as a requirement (``{"contacts": {"tol": 0.1}}``
        with ``requests=[("coordination", {})]``). Naming an analyzer that is
        not run is an error.
    source
        Where the requests come from (a scene file and key, an option); it
        starts the message that refuses an analyzer of another dimension.
    params_source
        Where ``params`` come from (e.g. ``--set``); it starts the message
        that refuses a parameter.
    warn
        Warn about old names among ``requests``; regopack's own default
        requests (:func:`default_analyses`) pass ``False``.
    computed
        Analyzers already computed on ``packing``, by the name their results
        are filed under (a run's scene analyses): an analyzer of the same
        registered name is taken from there, with the parameters it was
        computed with, instead of being computed again.

    Returns
    -------
    dict
        Every computed analyzer by the name its results are filed under, in
        the order of computation (the requested ones and their requirements).

    Raises
    ------
    ConfigError
        One line: an unknown analyzer (listing the known ones), an analyzer
        asked for by two names, an analyzer
        of another dimension than the packing's (listing those that fit), a bad parameter
        (naming the field, e.g. ``contacts.tol = -1: ...``), parameters
        for an analyzer that is not run, or a parameter that implies more work
        on this packing than allowed (a :class:`~regopack.base.limits.LimitError`,
        prefixed with ``params_source`` or ``source``). Every analyzer is validated before
        any is computed.
    PluginError
        Analyzers that require each other in a cycle, or an unregistered
        requirement.
    PackingError
        The packing breaks the packing format (see
        :meth:`~regopack.packing.core.Packing.validate`); nothing is computed.

    Examples
    --------
    >>> from regopack.registry.manager import default_registry
    >>> from regopack.testing import packing_from_polygons
    >>> p = packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]], domain=(0, 2, 0, 2))
    >>> done = run_analyses(p, default_registry(), [("density", {"margin": 0.0})])
    >>> list(done), done["density"].results()["phi_domain"]
    (['density'], 0.25)
    """
    packing.validate()  # the arrays may have changed in place since the packing was built
    dimension = packing.dimension
    planned = plan_analyses(
        registry, requests, params or {}, dimension, source, params_source, warn
    )
    done: dict[str, Analyzer] = {}
    by_name = {registry.canonical("analysis", name): name for name in planned}
    reuse = {registry.canonical("analysis", name): a for name, a in (computed or {}).items()}
    for name, analyzer in planned.items():
        known = reuse.get(registry.canonical("analysis", name))
        if known is not None:
            done[name] = known
            continue
        context = {
            req: done[by_name[registry.canonical("analysis", req)]] for req in analyzer.requires
        }
        try:
            result = analyzer.compute(packing, context)
        except LimitError as err:  # a size a parameter implies on this packing
            field = err.field.removeprefix(f"{name}.")
            given = params_source if field in (params or {}).get(name, {}) else source
            raise ConfigError(err.located(given)) from err
        if not isinstance(result, Analyzer):
            raise PluginError(
                f"analyzer {name!r}: compute() returned {type(result).__name__}, not the analyzer"
            )
        done[name] = result
    return done
