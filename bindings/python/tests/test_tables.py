# SPDX-License-Identifier: Apache-2.0
"""The lookup tables that bindings/gen_tables.py generates from the headers
(flatline/_tables.py) agree with SWIG's own reading of the same headers and
with the library."""
import pytest

import flatline
from flatline import _tables, capi

# (table, the C enumerators' prefix)
TABLES = [
    (_tables.SHEET_VALUES, "FLT_SHEET_"),
    (_tables.GAUGE_COUNTERS, "FLT_GAUGE_COUNT_"),
    (_tables.SOURCE_COUNTERS, "FLT_COUNT_"),
    (_tables.CAMERA_STRINGS, "FLT_CAMERA_"),
    (_tables.CAMERA_VALUES, "FLT_CAMERA_"),
]


@pytest.mark.parametrize("table,prefix", TABLES)
def test_every_name_is_the_headers_enumerator(table, prefix):
    assert table, prefix
    for name, key in table.items():
        assert getattr(capi, prefix + name.upper()) == key, name
    # key order, no gaps: what the bindings read by index
    assert list(table.values()) == list(range(len(table)))


def test_the_tables_reach_the_public_api():
    calib = flatline.Calibration.reference()
    with flatline.Gauge(calib) as gauge:
        assert list(gauge.counters()) == list(_tables.GAUGE_COUNTERS)
        # the library knows no counter past the table's last: none is missing
        with pytest.raises(flatline.InvalidArgumentError, match="not a flt_gauge_counter"):
            capi.flt_gauge_count(gauge._handle, len(_tables.GAUGE_COUNTERS))
