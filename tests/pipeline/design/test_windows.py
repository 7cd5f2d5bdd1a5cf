"""Whole windows: the most windows of a length that fit a duration."""

from hypothesis import given, settings
from hypothesis import strategies as st

from pipeline.design.windows import whole_windows


@settings(max_examples=100, deadline=None)
@given(duration=st.floats(1e-3, 100.0), window=st.floats(1e-3, 10.0))
def test_whole_windows_fit(duration, window):
    k = whole_windows(duration, window)
    assert k * window <= duration or k == 0
    assert (k + 1) * window > duration
