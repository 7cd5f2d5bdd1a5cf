"""The built-in materials: the class tables the module docstring prints, physical parameters,
ridge shapes, and one material sample per class."""

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import pipeline.recordings.materials as materials
from pipeline.recordings import touch
from pipeline.recordings.materials import TEXTURE_CLASSES, material_map, ridge_shape

SHAPES = ("sine", "square", "bumps", "sawtooth", "triangle", "none")


def test_the_material_sample_is_shared_by_a_class_and_differs_between_classes():
    sample = material_map(0, 2)
    np.testing.assert_array_equal(sample, material_map(0, 2))
    assert sample.std() == pytest.approx(1.0)
    # Independent draws (about 70 correlation lengths per period: |r| well below 0.6).
    assert abs(np.corrcoef(sample, material_map(0, 3))[0, 1]) < 0.6
    assert abs(np.corrcoef(sample, material_map(1, 2))[0, 1]) < 0.6


def _docstring_rows(heading: str, columns: int) -> list[list[str]]:
    section = materials.__doc__.split(heading)[1]
    return re.findall(r"^ *(\d+)" + r"\s+(\S+)" * columns + " *$", section, re.M)


def test_class_tables_in_docstring_match_the_code():
    rows = _docstring_rows("Classes\n", 8)[:12]
    mechanics = _docstring_rows("Mechanics (", 9)[:12]
    assert len(rows) == len(mechanics) == 12
    for (index, name, shape, *texture), (index2, *mech, period_mm, depth, rate_hz), m in zip(
        rows, mechanics, TEXTURE_CLASSES, strict=True
    ):
        assert int(index) == int(index2) == TEXTURE_CLASSES.index(m)
        assert (name, shape) == (m.name, m.shape)
        period, ridge, rough, corr, density, height = texture
        if shape != "none":
            assert float(period) == m.period_mm
        values = (m.ridge_um, m.roughness_um, m.correlation_mm, m.asperities_per_mm, m.asperity_um)
        assert [float(v) for v in (ridge, rough, corr, density, height)] == list(values)
        expected = (
            m.mu_static,
            m.mu_kinetic,
            m.stiffness_n_per_mm,
            m.relaxation,
            m.stribeck_mm_s,
            m.patchiness,
        )
        assert [float(v) for v in mech] == list(expected)
        assert float(depth) == m.macro_depth
        if m.macro_depth > 0:
            assert float(period_mm) == m.macro_period_mm
            expected_hz = touch.SCAN_SPEED_MM_S / m.macro_period_mm
            assert float(rate_hz) == pytest.approx(expected_hz, abs=0.05)
            assert 5.0 <= expected_hz <= 20.0
        else:
            assert period_mm == rate_hz == "--"


def test_materials_are_physical():
    for m in TEXTURE_CLASSES:
        assert 0 < m.mu_kinetic < m.mu_static < 1.5
        assert m.stiffness_n_per_mm > 0 and 0 <= m.relaxation < 1
        assert m.stribeck_mm_s > 0 and m.patchiness >= 0


@settings(max_examples=50, deadline=None)
@given(
    shape=st.sampled_from(SHAPES),
    phase=st.floats(-1e3, 1e3, allow_nan=False),
)
def test_ridge_shapes_have_period_one_and_unit_range(shape, phase):
    value = ridge_shape(shape, np.array([phase, phase + 1.0]))
    assert np.all(np.abs(value) <= 1.0 + 1e-12)
    np.testing.assert_allclose(value[0], value[1], atol=1e-9)


def test_unknown_ridge_shape():
    with pytest.raises(ValueError, match="unknown ridge shape"):
        ridge_shape("zigzag", np.zeros(3))
