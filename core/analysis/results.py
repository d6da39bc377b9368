"""Analysis results for Python users: scalars as a dict, tables as NumPy arrays.

:func:`regopack.analyze` returns an :class:`AnalysisResults`, a read-only
mapping from analyzer name to :class:`AnalysisResult`. Tables are structured
NumPy arrays (one field per column), so that ``res["rdf"].tables["rdf_near"]["total"]``
is a plain array; :meth:`AnalysisResult.to_pandas` gives a ``DataFrame`` when
pandas is installed (it is not a dependency of regopack).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from regopack.base.errors import ConfigError
from regopack.registry.interfaces import Analyzer

if TYPE_CHECKING:
    from regopack.analysis.pipeline import AnalysisFiles

__all__ = ["AnalysisResult", "AnalysisResults", "table_array"]


def table_array(columns: Mapping[str, Any]) -> np.ndarray:
    """Return the columns of one table as a structured array (one field per column).

    Examples
    --------
    >>> t = table_array({"r": [0.5, 1.5], "n": [3, 4]})
    >>> t.dtype.names, t["n"].tolist()
    (('r', 'n'), [3, 4])
    """
    arrays = {str(k): np.asarray(v) for k, v in columns.items()}
    length = len(next(iter(arrays.values()))) if arrays else 0
    out = np.empty(length, dtype=[(k, a.dtype) for k, a in arrays.items()])
    for name, values in arrays.items():
        out[name] = values
    return out


def _pandas() -> Any:
    try:
        import pandas
    except ImportError:
        raise ConfigError(
            "to_pandas() needs pandas, which regopack does not install: pip install pandas"
        ) from None
    return pandas


@dataclass(frozen=True)
class AnalysisResult:
    """What one analyzer found.

    Attributes
    ----------
    name
        The analyzer's name (``"contacts"``, ``"rdf"``, ...).
    scalars
        Its scalar results, as written to ``analysis.json``.
    tables
        Its tables by name, each a structured array with one field per column.
    analyzer
        The computed analyzer object, with every result it offers as an
        attribute (e.g. ``res["contacts"].analyzer.area``).
    """

    name: str
    scalars: dict[str, Any]
    tables: dict[str, np.ndarray]
    analyzer: Analyzer

    def __getitem__(self, key: str) -> Any:
        """Return a scalar result: ``res["density"]["phi_domain"]``."""
        try:
            return self.scalars[key]
        except KeyError:
            known = ", ".join(self.scalars)
            raise KeyError(f"{self.name} has no scalar {key!r} (it has: {known})") from None

    def to_pandas(self, table: str | None = None) -> Any:
        """Return a table as a ``pandas.DataFrame`` (the only table when ``table`` is None).

        Without tables, the scalars become a one-row frame.
        """
        pd = _pandas()
        if not self.tables:
            flat = {k: v for k, v in self.scalars.items() if not isinstance(v, dict | list)}
            return pd.DataFrame([flat])
        if table is None:
            if len(self.tables) > 1:
                raise ConfigError(
                    f"{self.name} has {len(self.tables)} tables; name one of: "
                    + ", ".join(self.tables)
                )
            table = next(iter(self.tables))
        if table not in self.tables:
            raise ConfigError(
                f"{self.name} has no table {table!r} (it has: {', '.join(self.tables)})"
            )
        return pd.DataFrame(self.tables[table])

    def __repr__(self) -> str:
        tables = ", ".join(f"{k}[{len(v)}]" for k, v in self.tables.items()) or "none"
        return f"AnalysisResult({self.name!r}: {len(self.scalars)} scalars, tables: {tables})"


class AnalysisResults(Mapping[str, AnalysisResult]):
    """Every computed analyzer by name, in the order of computation."""

    def __init__(self, analyzers: Mapping[str, Analyzer]) -> None:
        self._items = {
            name: AnalysisResult(
                name=name,
                scalars=analyzer.results(),
                tables={t: table_array(cols) for t, cols in analyzer.tables().items()},
                analyzer=analyzer,
            )
            for name, analyzer in analyzers.items()
        }
        self.analyzers: dict[str, Analyzer] = dict(analyzers)
        """The analyzer objects by name (what exporters and writers take)."""
        self.files: AnalysisFiles | None = None
        """The files written by :func:`regopack.analyze` with ``out``, or ``None``."""

    def __getitem__(self, name: str) -> AnalysisResult:
        try:
            return self._items[name]
        except KeyError:
            raise KeyError(
                f"no analysis {name!r} was computed (computed: {', '.join(self._items)})"
            ) from None

    def __iter__(self) -> Iterator[str]:
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def scalars(self) -> dict[str, dict[str, Any]]:
        """Scalar results of every analyzer, by name (the content of ``analysis.json``)."""
        return {name: item.scalars for name, item in self._items.items()}

    def __repr__(self) -> str:
        return f"AnalysisResults({', '.join(self._items)})"
