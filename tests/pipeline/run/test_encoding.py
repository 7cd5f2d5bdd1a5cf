import pytest

from pipeline.design.scene import Scene
from pipeline.run.encoding import _encode_tiny_signal

PAPER = Scene.paper()


@pytest.mark.parametrize(
    "readout",
    [
        PAPER.readout,
        PAPER.replace(**{"readout.encoder": "decaying"}).readout,
        Scene.builtin("smoke")
        .replace(**{"readout.effects": {"amplifier_noise": {"sigma_v": 0.01}, "saturation": {}}})
        .readout,
        PAPER.replace(**{"readout.effects": {"saturation": {"rail_v": 0.4}}}).readout,
    ],
    ids=["ideal", "decaying", "noisy", "saturating"],
)
def test_the_kernels_warm_up_on_a_tiny_signal_through_the_encoders_own_path(readout):
    # The warm-up gives up silently on failure: it must not fail where it is meant to work.
    assert _encode_tiny_signal(readout).event_rate_hz > 0
