"""AnalysisResults: a mapping of analyzer results with tables as structured arrays."""

from __future__ import annotations

import numpy as np
import pytest

from regopack.analysis.results import AnalysisResults, table_array
from regopack.base.errors import ConfigError
from regopack.registry.interfaces import Analyzer


class _Fake(Analyzer):
    name = "fake"

    def __init__(self, tables):
        self._tables = tables

    def compute(self, packing, context):
        return self

    def results(self):
        return {"n": 2, "nested": {"a": 1}}

    def tables(self):
        return self._tables


def test_table_array_keeps_column_order_and_dtypes():
    t = table_array({"r": np.array([0.5, 1.5]), "n": np.array([3, 4])})
    assert t.dtype.names == ("r", "n")
    assert t["n"].dtype.kind == "i"
    np.testing.assert_array_equal(t["r"], [0.5, 1.5])


def test_results_mapping_and_pandas():
    res = AnalysisResults({"fake": _Fake({"a": {"x": [1.0, 2.0]}, "b": {"y": [3]}})})
    assert list(res) == ["fake"] and len(res) == 1
    assert res["fake"]["n"] == 2
    assert res.scalars() == {"fake": {"n": 2, "nested": {"a": 1}}}
    pd = pytest.importorskip("pandas")
    with pytest.raises(ConfigError, match="name one of: a, b"):
        res["fake"].to_pandas()
    assert list(res["fake"].to_pandas("b")["y"]) == [3]
    with pytest.raises(ConfigError, match="no table 'c'"):
        res["fake"].to_pandas("c")
    one_row = AnalysisResults({"fake": _Fake({})})["fake"].to_pandas()
    assert isinstance(one_row, pd.DataFrame) and list(one_row.columns) == ["n"]
