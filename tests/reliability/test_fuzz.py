"""Property-based fuzzing of the parsers and the numeric core.

Scenes and grids built from arbitrary TOML-like structures raise nothing but
:class:`SceneError`; the encoders and the rate coder, fed arbitrary finite arrays (huge and tiny
magnitudes included), raise nothing but their documented errors (``ValueError``, of which
:class:`SimulationError` is one) and never put a NaN in an output.
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from pipeline.chain.coding import rate_code
from pipeline.chain.readout import level_crossings
from pipeline.chain.readout_effects import real_train
from pipeline.design.grid import Grid, load_grid
from pipeline.design.scene import Scene
from pipeline.errors import SceneError, SimulationError

FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])

# TOML values: what tomllib can produce.
scalars = st.one_of(
    st.booleans(),
    st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=12),
)
SCENE_WORDS = [
    "dataset", "array", "readout", "coding", "training", "name", "seed", "kind", "path",
    "rows", "cols", "threshold_v", "full_scale_v", "effects", "amplifier_noise", "sigma_v",
    "window_s", "n_windows", "models", "folds", "epochs", "synthetic", "folder", "saturation",
    "rail_v", "threshold_mismatch", "sigma_rel", "floor_rel", "polarity", "direction",
]  # fmt: skip
keys = st.one_of(st.sampled_from(SCENE_WORDS), st.text(max_size=8))
toml_values = st.recursive(
    scalars,
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.dictionaries(keys, inner, max_size=5)),
    max_leaves=20,
)
tables = st.dictionaries(keys, toml_values, max_size=6)


@FUZZ
@given(tables)
def test_scene_from_arbitrary_tables_raises_only_scene_errors(data):
    try:
        scene = Scene.from_dict(data)
    except SceneError as error:
        assert "\n" not in str(error)
        return
    assert Scene.from_dict(scene.to_dict()).canonical() == scene.canonical()


@FUZZ
@given(
    st.fixed_dictionaries(
        {},
        optional={
            "dataset": st.dictionaries(st.sampled_from(SCENE_WORDS), toml_values, max_size=3),
            "readout": st.dictionaries(st.sampled_from(SCENE_WORDS), toml_values, max_size=3),
            "coding": st.dictionaries(st.sampled_from(SCENE_WORDS), scalars, max_size=3),
            "array": st.dictionaries(st.sampled_from(SCENE_WORDS), scalars, max_size=3),
            "training": st.dictionaries(st.sampled_from(SCENE_WORDS), toml_values, max_size=3),
        },
    )
)
def test_scene_parts_with_arbitrary_values_raise_only_scene_errors(data):
    try:
        Scene.from_dict(data)
    except SceneError as error:
        assert "\n" not in str(error)


grid_tables = st.fixed_dictionaries(
    {},
    optional={
        "name": toml_values,
        "base": st.one_of(st.sampled_from(["smoke", "paper", "nope"]), tables, toml_values),
        "sweeps": st.dictionaries(
            keys,
            st.one_of(
                toml_values,
                st.fixed_dictionaries(
                    {"axes": st.dictionaries(keys, toml_values, max_size=3)},
                    optional={"mode": toml_values, "set": tables, "correlate": toml_values},
                ),
            ),
            max_size=3,
        ),
    },
)


@FUZZ
@given(grid_tables)
def test_grid_from_arbitrary_tables_raises_only_scene_errors(data):
    try:
        grid = Grid.from_dict(data)
    except SceneError as error:
        assert "\n" not in str(error)
        return
    for point in grid.points():
        assert "/" not in point.sweep and ".." not in grid.name


@settings(max_examples=100, deadline=None)
@given(st.binary(max_size=200))
def test_grid_files_of_arbitrary_bytes_raise_only_scene_errors(tmp_path_factory, content):
    path = tmp_path_factory.mktemp("grid") / "g.toml"
    path.write_bytes(content)
    try:
        load_grid(path)
    except SceneError as error:
        assert str(path) in str(error) and "\n" not in str(error)


# -- numeric core -------------------------------------------------------------------------------

finite = st.floats(allow_nan=False, allow_infinity=False)
signals = hnp.arrays(np.float64, st.integers(0, 200), elements=finite)
positive = st.floats(min_value=1e-300, max_value=1e300, allow_nan=False, allow_infinity=False)
rates = st.floats(min_value=1e-3, max_value=1e9)
MAX_SPIKES = 20_000  # keeps each example fast; longer trains are a SimulationError


def check_train(times, polarity, n_samples, fs_hz):
    assert times.dtype == np.float64 and polarity.dtype == np.int8
    assert times.shape == polarity.shape
    assert not np.isnan(times).any()
    assert np.all(np.diff(times) >= 0)
    assert np.all(np.abs(polarity) == 1)
    if times.size:
        assert times[0] >= 0 and times[-1] <= max(n_samples - 1, 0) / fs_hz * (1 + 1e-12)


@FUZZ
@given(signals, rates, positive)
def test_level_crossings_on_arbitrary_finite_arrays(v, fs_hz, threshold_v):
    try:
        times, polarity = level_crossings(v, fs_hz, threshold_v, max_spikes=MAX_SPIKES)
    except ValueError:  # documented: SimulationError (too many spikes) is a ValueError
        return
    check_train(times, polarity, v.size, fs_hz)


@pytest.mark.parametrize("jump", [1e19, 1e300, -1e308])
def test_one_huge_jump_is_a_simulation_error(jump):
    # More levels in one sample than an int64 holds: counted saturating, refused by the cap.
    with pytest.raises(SimulationError, match="spikes"):
        level_crossings(np.array([0.0, jump]), 1.0, 1.0, max_spikes=100)


effects = st.dictionaries(
    st.sampled_from(
        ["amplifier_offset", "amplifier_noise", "saturation", "comparator_offset",
         "comparator_noise", "threshold_mismatch"]
    ),
    st.just({}),
    max_size=6,
)  # fmt: skip


@FUZZ
@given(signals, rates, positive, effects, st.integers(0, 2**32))
def test_real_train_on_arbitrary_finite_arrays(v, fs_hz, threshold_v, named, seed):
    readout = Scene.from_dict(
        {"readout": {"threshold_v": threshold_v, "full_scale_v": 2 * threshold_v, "effects": named}}
    ).readout
    try:
        times, polarity = real_train(
            v, fs_hz, readout, seed=seed, taxel=0, recording=0, max_spikes=MAX_SPIKES
        )
    except ValueError:
        return
    check_train(times, polarity, v.size, fs_hz)


@FUZZ
@given(
    hnp.arrays(np.float64, st.integers(0, 300), elements=finite),
    positive,
    st.integers(1, 2000),
)
def test_rate_code_on_arbitrary_finite_arrays(times_s, window_s, n_windows):
    try:
        counts, dropped = rate_code(times_s, window_s, n_windows)
    except ValueError:
        return
    assert counts.dtype == np.int64 and counts.shape == (n_windows,)
    assert np.all(counts >= 0) and dropped >= 0
    assert int(counts.sum()) + dropped == times_s.size
