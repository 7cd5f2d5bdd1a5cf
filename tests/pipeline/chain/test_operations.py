"""The operation counter, through the decoder registry, against small networks counted by
hand."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from pipeline.chain.decoders import build_model, count_operations
from pipeline.chain.models import fold_generator
from pipeline.chain.operations import conv3x3_fan_out
from pipeline.chain.spiking import FoldSNN
from pipeline.design.scene import SNNInputs, SNNSpec, SNNTimeConstants


def _zeroed(net: torch.nn.Module) -> None:
    with torch.no_grad():
        for p in net.parameters():
            p.zero_()


def test_ffnn_counts_nonzero_real_inputs_times_fan_out():
    net = build_model("ffnn", (1, 2, 2), 2, 3, 1, [fold_generator(0, 0, "init")])
    _zeroed(net)
    with torch.no_grad():
        net.b1.copy_(torch.tensor([[1.0, -1.0, 0.0]]))  # hidden = relu(b1) = [1, 0, 0]
    x = torch.tensor([[0.0, 1.5], [-2.0, 0.0]]).reshape(1, 1, 1, 2, 2)
    ops = count_operations("ffnn", net, x)
    # 2 nonzero inputs x 3 hidden units + 1 nonzero hidden unit x 2 classes.
    assert ops.macs.tolist() == [[[2 * 3 + 1 * 2]]]
    assert ops.acs.tolist() == [[[0.0]]] and ops.neuron_updates.tolist() == [[[0.0]]]


def test_conv_fan_out_counts_the_outputs_a_pixel_reaches():
    fan = conv3x3_fan_out(3, 4, 1)
    assert fan.tolist() == [[4, 6, 6, 4], [6, 9, 9, 6], [4, 6, 6, 4]]
    assert conv3x3_fan_out(1, 1, 16).tolist() == [[16]]  # one pixel reaches only itself


def test_cnn_counts_both_convolutions_and_the_linear_layer():
    net = build_model("cnn", (1, 3, 4), 2, 0, 1, [fold_generator(0, 0, "init")])
    _zeroed(net)
    with torch.no_grad():
        net.conv1_b[0, 0] = 1.0  # channel 0 of the first map is 1 everywhere, the others 0
        net.conv2_b[0, 0] = 1.0  # likewise the second
    x = torch.zeros(1, 1, 1, 3, 4)
    x[0, 0, 0, 0, 0] = 2.0  # a corner: 2 x 2 output positions x 16 channels
    x[0, 0, 0, 1, 1] = -1.0  # inside: 3 x 3 x 16
    ops = count_operations("cnn", net, x)
    conv1 = (4 + 9) * 16
    conv2 = 4 * (2 * 2) * 32  # the pooled 2x2 map: 4 pixels of channel 0, each reaching 2 x 2
    linear = 1 * 2  # one nonzero feature after the second pooling (1x1), 2 classes
    assert ops.macs.tolist() == [[[conv1 + conv2 + linear]]]
    assert ops.acs.tolist() == [[[0.0]]]


def test_snn_counts_events_and_spikes_as_accumulates_and_every_neuron_update():
    generators = [fold_generator(0, 0, "init")]
    net = FoldSNN(
        (1, 1, 4),
        3,
        2,
        generators,
        step_s=0.01,
        tau_mem_s=1e-3,  # beta = exp(-10): the membrane forgets within a step
        threshold=1.0,
        surrogate_slope=25.0,
    )
    _zeroed(net)
    with torch.no_grad():
        net.w1[0, 0, 0] = 5.0  # the input drives hidden neuron 0 only
    x = torch.tensor([2.0, 0.0, 1.0, 0.0]).reshape(1, 1, 1, 1, 4)  # events per step
    spikes, _ = net.hidden_spikes(x)
    assert spikes[0, 0, :, 0].tolist() == [1.0, 0.0, 1.0, 0.0]
    assert spikes[0, 0, :, 1].tolist() == [0.0, 0.0, 0.0, 0.0]
    ops = count_operations("snn", net, x)
    # Step 1: 2 events x 2 hidden + 1 spike x 3 classes; step 3: 1 x 2 + 1 x 3 more.
    assert ops.acs.tolist() == [[[7.0, 7.0, 12.0, 12.0]]]
    assert ops.macs.tolist() == [[[0.0, 0.0, 0.0, 0.0]]]
    assert ops.neuron_updates.tolist() == [[[5.0, 10.0, 15.0, 20.0]]]
    # The same numbers as real inputs (standardized, log counts): a MAC per nonzero input.
    net.events_in = False
    real = count_operations("snn", net, x)
    assert real.macs.tolist() == [[[2.0, 2.0, 4.0, 4.0]]]
    assert real.acs.tolist() == [[[3.0, 3.0, 6.0, 6.0]]]
    assert np.array_equal(real.neuron_updates, ops.neuron_updates)


def test_a_second_snn_layer_counts_the_first_layers_spikes_and_its_updates():
    net = build_model(
        "snn",
        (1, 1, 4),
        3,
        0,
        1,
        [fold_generator(0, 0, "init")],
        SNNSpec(
            hidden_neurons=2,
            tau_mem_s=1e-3,
            step_s=0.01,
            hidden_layers=2,
            inputs=SNNInputs.COUNTS,
            time_constants=SNNTimeConstants.SHARED,  # the membranes forget within a step
        ),
    )
    _zeroed(net)
    with torch.no_grad():
        net.w1[0, 0, 0] = 5.0  # the input drives neuron 0 of the first layer
        net.wh[0, 0, 0, 1] = 5.0  # which drives neuron 1 of the second
    x = torch.tensor([2.0, 0.0, 1.0, 0.0]).reshape(1, 1, 1, 1, 4)
    ops = count_operations("snn", net, x)
    # Step 1: 2 events x 2 + 1 first-layer spike x 2 + 1 second-layer spike x 3;
    # step 3: 1 x 2 + 2 + 3 more.
    assert ops.acs.tolist() == [[[9.0, 9.0, 16.0, 16.0]]]
    assert ops.neuron_updates.tolist() == [[[7.0, 14.0, 21.0, 28.0]]]


def test_counts_are_per_fold_and_sample():
    net = build_model("ffnn", (1, 1, 3), 2, 4, 2, [fold_generator(0, f, "init") for f in (0, 1)])
    x = torch.zeros(2, 3, 1, 1, 3)
    x[1, 2, 0, 0, :2] = 1.0
    ops = count_operations("ffnn", net, x)
    assert ops.macs.shape == (2, 3, 1)
    with torch.no_grad():
        hidden = torch.relu(x[1, 2].reshape(-1) @ net.w1[1] + net.b1[1])
        idle = torch.relu(net.b1)  # an all-zero input reaches the hidden units through b1 only
    assert ops.macs[1, 2, 0] == 2 * 4 + int((hidden != 0).sum()) * 2
    assert ops.macs[0, :, 0].tolist() == [int((idle[0] != 0).sum()) * 2] * 3
    assert np.all(ops.stacked()[..., [0, 2]] == 0)


def test_unknown_models_are_refused():
    with pytest.raises(ValueError, match="lsnn"):
        count_operations("lsnn", torch.nn.Linear(2, 2), torch.zeros(1, 1, 1, 1, 2))
