"""Tests of the comparators' matched area: Pelgrom's law per device, taxel and array."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from pipeline.results.matched_area import (
    A_VT_V_M,
    MATCHED_DEVICES_PER_TAXEL,
    array_area_m2,
    matched_device_area_m2,
    offset_sigma_v,
    taxel_area_m2,
)


def test_pelgrom_area_is_a_vt_over_the_offset_squared_per_matched_device():
    # 5 % of 0.09 V is an offset sigma of 4.5 mV; 5 mV um / 4.5 mV = 1.111 um, squared.
    assert offset_sigma_v(0.05, 0.09) == pytest.approx(4.5e-3, rel=1e-12)
    assert matched_device_area_m2(4.5e-3) == pytest.approx((5e-9 / 4.5e-3) ** 2, rel=1e-12)
    assert A_VT_V_M == 5e-9 and MATCHED_DEVICES_PER_TAXEL == 4
    assert taxel_area_m2(0.05, 0.09) == pytest.approx(4 * (5e-9 / 4.5e-3) ** 2, rel=1e-12)
    assert array_area_m2(9, 0.05, 0.09) == pytest.approx(9 * taxel_area_m2(0.05, 0.09))
    # Halving the mismatch quadruples the area (1/sigma^2).
    assert taxel_area_m2(0.025, 0.09) == pytest.approx(4 * taxel_area_m2(0.05, 0.09))


def test_pelgrom_area_is_nan_without_mismatch_and_broadcasts():
    values = taxel_area_m2(np.array([0.0, 0.1, 0.5]), 0.09)
    assert np.isnan(values[0]) and np.all(np.isfinite(values[1:]))
    assert values[1] == pytest.approx(25 * values[2])
    sigma = xr.DataArray([0.1, 0.2], dims=("sigma_rel",), coords={"sigma_rel": [0.1, 0.2]})
    found = taxel_area_m2(sigma, 0.09)
    assert isinstance(found, xr.DataArray) and found.dims == ("sigma_rel",)
    with pytest.raises(ValueError, match="sigma_rel"):
        taxel_area_m2(-0.1, 0.09)
