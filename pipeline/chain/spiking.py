r"""The spiking decoder: layers of leaky integrate-and-fire neurons, batched over folds.

Input
    A recording's spike trains counted in steps of :math:`\Delta t` (``training.snn.step_s``),
    per polarity and taxel: ``x`` of shape ``(C=2, H=taxels, T=steps)``, ON (+1) counts then OFF
    (-1) counts (:func:`pipeline.chain.coding.frames` with ``Polarity.SPLIT``). They are fed as
    ``training.snn.inputs`` says (:meth:`pipeline.chain.decoders.SNNDecoder.prepare`):
    standardized per input and step with the fold's training statistics (the default), as
    the event counts they are, or as ``log(1 + count)``.

Neuron (the leaky integrate-and-fire neuron of snnTorch's ``snn.Leaky``, reset by subtraction)
    With :math:`\beta = \exp(-\Delta t / \tau_\mathrm{mem})` (``tau_mem_s``), threshold
    :math:`\vartheta` (``threshold``) and input current
    :math:`I_t = W_1^\top x_t + b_1` (one matrix product for all steps at once),

    .. math::

        u_t = \beta u_{t-1} + I_t - \vartheta s_{t-1}, \qquad
        s_t = \Theta(u_t - \vartheta), \qquad u_0 = s_0 = 0,

    :math:`\Theta(v) = 1` for :math:`v > 0`, else 0. The reset term :math:`s_{t-1}` carries no
    gradient (snnTorch's default ``reset_delay`` with a detached reset). With
    ``time_constants = "learned"`` each neuron :math:`i` of each fold has its own
    :math:`\beta_i = \exp(-\Delta t / \tau_i)`, :math:`\tau_i = \exp(\ell_i)` with
    :math:`\ell_i` (``log_tau_s``) a parameter starting at :math:`\log \tau_\mathrm{mem}`, so
    that every :math:`\tau_i > 0` and :math:`\beta_i \in (0, 1)` (the parametric LIF neuron of
    Fang et al., ICCV 2021). With ``hidden_layers`` :math:`L > 1`, layer :math:`k + 1` is driven
    by the spikes of layer :math:`k`, :math:`I^{(k+1)}_t = W_h^{(k)\top} s^{(k)}_t + b_h^{(k)}`,
    and the readout reads the last layer's spikes.

Surrogate gradient
    The spike's derivative is replaced by the fast sigmoid's (SuperSpike; snnTorch's
    ``surrogate.fast_sigmoid``) with slope :math:`k` (``surrogate_slope``):

    .. math::

        \frac{\partial s_t}{\partial u_t} \approx \frac{1}{(1 + k |u_t - \vartheta|)^2}.

    Backpropagation through time is then a linear recursion backwards in time,
    :math:`g_t = \frac{\partial L}{\partial s_t} \frac{\partial s_t}{\partial u_t}
    + \beta g_{t+1}`, :math:`\partial L / \partial I_t = g_t`, and for a learned decay
    :math:`\partial L / \partial \beta_i = \sum_t g_{t,i} u_{t-1,i}`.

Readout and decisions
    Each step's output current is :math:`o_t = W_2^\top s_t + b_2`; the decision read at step
    :math:`t` (at :math:`t \Delta t` seconds of touch) is the argmax of logits :math:`z_t`, its
    confidence the softmax probability of that class, with :math:`z_t` as ``readout`` says:

    * ``mean_current``: their running mean, :math:`z_t = \frac{1}{t} \sum_{t' \le t} o_{t'}`
      (a non-spiking integrator; at the end of the touch, linear in the spike counts);
    * ``last_membrane``: the membrane of a non-spiking leaky integrator with the hidden
      neurons' :math:`\beta` (``tau_mem_s``), :math:`z_t = \beta z_{t-1} + (1 - \beta) o_t`,
      :math:`z_0 = 0`;
    * ``max_membrane``: that membrane's maximum so far, :math:`\max_{t' \le t} z_{t'}` per class.

    Training (``training.decisions``, :meth:`pipeline.chain.decoders.SNNDecoder.loss`)
    minimizes the cross-entropy of :math:`z_T`, the decision at the end of the touch
    (``full_touch``), or its weighed sum over the steps, :math:`\sum_t w_t \mathrm{CE}(z_t)`
    (``along_touch``: every step's decision is trained, as the FFNN's and CNN's are on the
    windows so far), with :math:`w_t = 1/T` (``along_touch_loss = "every_step"``) or
    :math:`w_t \propto t^{-1/2}`, :math:`\sum_t w_t = 1` (``"early_steps"``). For the mean
    readout its gradient needs no decision kept: with :math:`g_t = w_t \, \partial
    \mathrm{CE}(z_t) / \partial z_t`, :math:`G_t = \sum_{t' \ge t} g_{t'} / t'` (a sum backwards
    in time), :math:`\partial L / \partial s_t = W_2 G_t` and :math:`\partial L / \partial W_2 =
    \sum_t s_t G_t^\top`.

Speed
    The time loop runs in two compiled kernels (forward: membranes and spikes; backward: the
    recursion above, the surrogate derivative and :math:`u_{t-1}` read from the kept membranes)
    wrapped in one :class:`torch.autograd.Function`, so that autograd sees one node per layer,
    not :math:`T` of them, and the backward pass costs :math:`O(T)` (a Python loop of autograd
    operations over the steps costs tens of microseconds per operation and step; indexing a
    tensor that requires grad inside such a loop costs :math:`O(T^2)` in the backward pass).
    Trained along the touch, the mean readout's running mean, softmax and cross-entropy of every
    step run in one more pair of kernels (:class:`MeanCurrentLoss`, with the gradient above),
    not as operations over every step's logits in autograd; its two products are computed with
    the classes first, the layout a narrow product is fastest in. The kernels use numpy's error
    model: a division checked for zero (numba's default) keeps a loop from vectorizing, and no
    division here can be by zero. Each kernel's gradient is tested against plain autograd on the
    same equations. Parameters carry a leading fold dimension ``F`` as the FFNN's and CNN's do.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from pipeline.chain.folded import FoldModel, two_layers, uniform
from pipeline.design.scene import SNNAlongLoss, SNNReadout, SNNTimeConstants
from pipeline.jit import kernel


@kernel(error_model="numpy")
def _lif_forward(current, beta, threshold, ends, spikes, membrane, rate):  # pragma: no cover
    """Step ``M x N`` neurons through ``T`` steps: ``current``, ``membrane`` (each step's
    :math:`u_t`, from which the backward pass derives the surrogate derivative and, for a
    learned decay, :math:`u_{t-1}`) and, unless it is empty, ``spikes`` are float32
    ``(M, T, N)`` (``M`` independent groups, each with its ``N`` neurons contiguous); ``beta``
    float32 ``(M, N)`` is each neuron's decay; ``rate`` float32 ``(M, N)`` gets each neuron's
    mean spike count over the steps up to ``ends[m]`` (int64 ``(M,)``), the steps after which
    are not computed (their ``membrane`` and ``spikes`` are left as they were)."""
    n_groups, _, n = current.shape
    keep = spikes.size > 0
    threshold = np.float32(threshold)
    u = np.zeros(n, dtype=np.float32)
    s = np.zeros(n, dtype=np.float32)
    for m in range(n_groups):
        u[:] = 0.0
        s[:] = 0.0
        rate[m, :] = 0.0
        for t in range(ends[m] + 1):
            for i in range(n):
                value = beta[m, i] * u[i] + current[m, t, i] - threshold * s[i]
                u[i] = value
                membrane[m, t, i] = value
                s[i] = np.float32(1.0) if value > threshold else np.float32(0.0)
                rate[m, i] += s[i]
            if keep:
                spikes[m, t, :] = s
        rate[m, :] /= ends[m] + 1


@kernel(error_model="numpy")
def _lif_backward(
    grad_spikes, grad_rate, membrane, beta, threshold, slope, ends, grad_current, grad_beta
):  # pragma: no cover
    """``dL/dI`` (float32 ``(M, T, N)``) from ``dL/ds`` (``grad_spikes``, or empty when only the
    rate was used), ``dL/d rate`` (``(M, N)``) and the surrogate derivatives of the forward
    pass's ``membrane``; and, unless ``grad_beta`` is empty, ``dL/d beta`` (``(M, N)``): the sum
    over the steps of :math:`g_t u_{t-1}`; the steps after ``ends[m]`` get no gradient."""
    n_groups, _, n = membrane.shape
    keep = grad_spikes.size > 0
    learned = grad_beta.size > 0
    threshold, slope = np.float32(threshold), np.float32(slope)
    g = np.zeros(n, dtype=np.float32)
    decay = np.zeros(n, dtype=np.float32)  # dL/d beta so far
    for m in range(n_groups):
        per_step = np.float32(1.0 / (ends[m] + 1))
        g[:] = 0.0
        decay[:] = 0.0
        grad_current[m, ends[m] + 1 :, :] = 0.0
        for t in range(ends[m], -1, -1):
            for i in range(n):
                grad = grad_rate[m, i] * per_step
                if keep:
                    grad += grad_spikes[m, t, i]
                value = membrane[m, t, i]
                if learned:  # g_{t+1} u_t: the term of step t + 1, read with u_t
                    decay[i] += g[i] * value
                d = np.float32(1.0) + slope * abs(value - threshold)
                g[i] = grad * (np.float32(1.0) / (d * d)) + beta[m, i] * g[i]
                grad_current[m, t, i] = g[i]
        if learned:
            grad_beta[m, :] = decay


@kernel(error_model="numpy")
def _mean_current_loss_forward(
    currents, b2, targets, step_weights, batch, losses, grad_logits
):  # pragma: no cover
    """Each group's sum over its ``T`` steps of the cross-entropy of the ``mean_current``
    decision :math:`z_t = \\frac{1}{t} \\sum_{t' \\le t} W_2^\\top s_{t'} + b_2`, weighed by
    ``step_weights`` float32 ``(T,)`` (``losses``, float32 ``(M,)``), for ``M = F x batch``
    groups (group ``m`` is sample ``m % batch`` of fold ``m // batch``), from ``currents``
    float32 ``(F, C, batch x T)``, :math:`W_2^\\top s_t` of every sample and step (classes
    first, the layout the product gives fastest), ``b2`` ``(F, C)`` and int64 ``targets``
    ``(M,)``; ``grad_logits`` ``(M, T, C)`` gets each step's
    :math:`\\mathrm{softmax}(z_t) - \\mathrm{onehot}(y)`."""
    n_groups, n_steps, n_classes = grad_logits.shape
    total = np.zeros(n_classes, dtype=np.float32)  # the currents so far
    z = np.zeros(n_classes, dtype=np.float32)
    for m in range(n_groups):
        f, first, target = m // batch, (m % batch) * n_steps, targets[m]
        total[:] = 0.0
        loss = 0.0
        for t in range(n_steps):
            per_step = np.float32(1.0 / (t + 1))
            top = np.float32(-np.inf)
            for c in range(n_classes):
                total[c] += currents[f, c, first + t]
                z[c] = total[c] * per_step + b2[f, c]
                top = max(top, z[c])
            norm = np.float32(0.0)
            for c in range(n_classes):
                e = np.exp(z[c] - top)
                grad_logits[m, t, c] = e
                norm += e
            loss += step_weights[t] * (top + np.log(norm) - z[target])
            for c in range(n_classes):
                grad_logits[m, t, c] /= norm
            grad_logits[m, t, target] -= np.float32(1.0)
        losses[m] = loss


@kernel(error_model="numpy")
def _mean_current_loss_backward(
    grad_logits, grad_losses, step_weights, batch, grad_sums, grad_b2
):  # pragma: no cover
    """From each group's loss gradient ``grad_losses`` (float32 ``(M,)``) and the saved
    ``grad_logits`` ``(M, T, C)`` of the steps weighed by ``step_weights`` ``(T,)``:
    ``grad_sums`` ``(M, T, C)``, :math:`G_t = \\sum_{t' \\ge t} \\frac{1}{t'}
    \\frac{\\partial L}{\\partial z_{t'}}` (a sum backwards in time), and the gradient of
    ``b2`` ``(F, C)`` summed over each fold's groups."""
    n_groups, n_steps, n_classes = grad_logits.shape
    grad_b2[:] = 0.0
    sums = np.zeros(n_classes, dtype=np.float32)
    for m in range(n_groups):
        f = m // batch
        sums[:] = 0.0
        for t in range(n_steps - 1, -1, -1):
            per_step = np.float32(1.0 / (t + 1))
            scale = grad_losses[m] * step_weights[t]
            for c in range(n_classes):
                grad = scale * grad_logits[m, t, c]
                grad_b2[f, c] += grad
                sums[c] += grad * per_step
                grad_sums[m, t, c] = sums[c]


class MeanCurrentLoss(torch.autograd.Function):
    """Each sample's loss along the touch, float32 ``(F, B)``: the cross-entropy of its
    ``mean_current`` decision at every step, summed over the steps weighed by ``step_weights``
    float32 ``(T,)``, from the last layer's ``spikes`` float32 ``(F, B, T, N)``, the readout
    ``w2 (F, N, C)``, ``b2 (F, C)`` and int64 ``targets (F, B)``: the loss of
    :meth:`FoldSNN.decision_logits` read at every step, with the running mean, the softmax and
    the cross-entropy of every step in one compiled pass forwards and their gradient in one
    backwards, not as operations over every step's logits in autograd. Differentiable in
    ``spikes``, ``w2`` and ``b2``: :math:`\\partial L / \\partial s_t = W_2 G_t` and
    :math:`\\partial L / \\partial W_2 = \\sum_t s_t G_t^\\top` (the backward kernel's
    :math:`G_t`), one matrix product each, in the layouts they are fastest in."""

    @staticmethod
    def forward(ctx, spikes, w2, b2, targets, step_weights):  # type: ignore[override]
        """``(F, B)`` losses (see the class docstring)."""
        n_folds, batch, n_steps, n = spikes.shape
        spikes = spikes.detach().reshape(n_folds, batch * n_steps, n)
        w2 = w2.detach()
        currents = torch.bmm(w2.transpose(1, 2), spikes.transpose(1, 2))  # (F, C, B*T)
        losses = torch.empty(n_folds * batch, dtype=torch.float32)
        grad_logits = torch.empty((n_folds * batch, n_steps, w2.shape[2]), dtype=torch.float32)
        _mean_current_loss_forward(
            currents.numpy(),
            b2.detach().contiguous().numpy(),
            targets.to(torch.int64).reshape(-1).contiguous().numpy(),
            step_weights.numpy(),
            batch,
            losses.numpy(),
            grad_logits.numpy(),
        )
        ctx.save_for_backward(spikes, w2, grad_logits, step_weights)
        return losses.reshape(n_folds, batch)

    @staticmethod
    def backward(ctx, grad_losses):  # type: ignore[override]
        """The gradients of ``spikes``, ``w2`` and ``b2``."""
        spikes, w2, grad_logits, step_weights = ctx.saved_tensors
        n_folds, n, n_classes = w2.shape
        batch = grad_losses.shape[1]
        grad_sums = torch.empty_like(grad_logits)
        grad_b2 = torch.empty((n_folds, n_classes), dtype=torch.float32)
        _mean_current_loss_backward(
            grad_logits.numpy(),
            grad_losses.detach().to(torch.float32).reshape(-1).contiguous().numpy(),
            step_weights.numpy(),
            batch,
            grad_sums.numpy(),
            grad_b2.numpy(),
        )
        grad_sums = grad_sums.reshape(n_folds, -1, n_classes)  # (F, B*T, C)
        grad_spikes = torch.bmm(grad_sums, w2.transpose(1, 2)).reshape(n_folds, batch, -1, n)
        grad_w2 = torch.bmm(grad_sums.transpose(1, 2), spikes).transpose(1, 2)
        return grad_spikes, grad_w2, grad_b2, None, None


class LeakyLayer(torch.autograd.Function):
    """Spikes ``float32 (M, T, N)`` of ``M x N`` LIF neurons driven by ``current`` ``float32
    (M, T, N)`` over ``T`` steps (see the module docstring), and their mean over the steps
    ``(M, N)``; differentiable in ``current`` through the surrogate, and in ``beta`` when it is
    a tensor ``(M, N)`` that requires grad (a float is one fixed decay for every neuron). With
    ``keep=False`` the spikes are not kept (an empty tensor): training reads only the mean, and
    the time loop then moves a third less memory. ``ends`` (int64 ``(M,)``, with ``keep=False``;
    None: the last step) stops group ``m`` after step ``ends[m]``: its rate is the mean up to
    there, the decision a training along the touch draws."""

    @staticmethod
    def forward(ctx, current, beta, threshold, slope, keep=True, ends=None):  # type: ignore[override]
        """``(spikes, rate)`` of the layer driven by ``current`` (see the class docstring)."""
        current = current.detach().contiguous()
        n_groups, n_steps, n = current.shape
        if ends is None:
            ends = torch.full((n_groups,), n_steps - 1, dtype=torch.int64)
        ends = ends.to(torch.int64).contiguous()
        learned = isinstance(beta, torch.Tensor) and ctx.needs_input_grad[1]
        if isinstance(beta, torch.Tensor):
            beta = beta.detach().to(torch.float32).expand(n_groups, n).contiguous()
        else:
            beta = torch.full((n_groups, n), float(beta), dtype=torch.float32)
        spikes = torch.empty_like(current) if keep else torch.empty((0, 0, 0))
        membrane = torch.empty_like(current)
        rate = torch.empty((n_groups, n), dtype=current.dtype)
        _lif_forward(
            current.numpy(),
            beta.numpy(),
            float(threshold),
            ends.numpy(),
            spikes.numpy(),
            membrane.numpy(),
            rate.numpy(),
        )
        ctx.save_for_backward(membrane, beta, ends)
        ctx.learned, ctx.threshold, ctx.slope = learned, float(threshold), float(slope)
        return spikes, rate

    @staticmethod
    def backward(ctx, grad_spikes, grad_rate):  # type: ignore[override]
        """``dL/d current`` from the gradients of the spikes and of the rate (the surrogate),
        and ``dL/d beta`` for a learned decay."""
        membrane, beta, ends = ctx.saved_tensors
        grad = torch.empty_like(membrane)
        grad_beta = torch.empty_like(beta) if ctx.learned else torch.empty((0, 0))
        grad_spikes = grad_spikes.detach().contiguous()
        grad_rate = grad_rate.detach().contiguous()
        _lif_backward(
            grad_spikes.numpy(),
            grad_rate.numpy(),
            membrane.numpy(),
            beta.numpy(),
            ctx.threshold,
            ctx.slope,
            ends.numpy(),
            grad.numpy(),
            grad_beta.numpy(),
        )
        return grad, grad_beta if ctx.learned else None, None, None, None, None


class FoldSNN(FoldModel):
    """Spiking decoder batched over folds: ``Linear(C*H, hidden) -> LIF -> Linear(hidden,
    n_classes) -> readout over steps`` (the module docstring).

    Parameters (float32): ``w1 (F, C*H, hidden)``, ``b1 (F, hidden)``, ``w2 (F, hidden,
    n_classes)``, ``b2 (F, n_classes)``, drawn per fold in that order as the FFNN's
    (``U(-1/sqrt(fan_in), 1/sqrt(fan_in))``), and, with learned time constants,
    ``log_tau_s (F, hidden)`` (log seconds, drawn from no generator).

    ``events_in``: whether its inputs are event counts (for the operation counter,
    :func:`pipeline.chain.operations.snn_operations`).

    ``forward(x: float32 (F, B, C, H, T)) -> float32 (F, B, n_classes)``: the logits of the
    decision at the last step; :meth:`decision_logits` those of every step.
    """

    def __init__(
        self,
        input_shape: tuple[int, int, int],
        n_classes: int,
        hidden_neurons: int,
        generators: Sequence[torch.Generator],
        *,
        step_s: float,
        tau_mem_s: float,
        threshold: float,
        surrogate_slope: float,
        time_constants: SNNTimeConstants = SNNTimeConstants.SHARED,
        readout: SNNReadout = SNNReadout.MEAN_CURRENT,
        events_in: bool = True,
        hidden_layers: int = 1,
        along_touch_loss: SNNAlongLoss = SNNAlongLoss.EVERY_STEP,
    ):
        super().__init__(input_shape, n_classes, len(generators))
        c, h, _ = self.input_shape
        self.hidden_neurons = int(hidden_neurons)
        self.step_s = float(step_s)
        self.beta = math.exp(-step_s / tau_mem_s)
        self.threshold = float(threshold)
        self.surrogate_slope = float(surrogate_slope)
        self.readout = SNNReadout(readout)
        self.events_in = bool(events_in)  # its inputs are event counts (else real numbers)
        self.hidden_layers = int(hidden_layers)
        self.along_touch_loss = SNNAlongLoss(along_touch_loss)  # read by its decoder's loss
        two_layers(self, c * h, self.hidden_neurons, n_classes, generators)
        if self.hidden_layers > 1:
            # Drawn after the first layers, so that those stay a one-layer decoder's.
            n, extra = self.hidden_neurons, self.hidden_layers - 1
            draws = [
                (uniform(g, (n, n), n), uniform(g, (n,), n))
                for g in generators
                for _ in range(extra)
            ]
            weights = torch.stack([w for w, _ in draws]).reshape(self.n_folds, extra, n, n)
            biases = torch.stack([b for _, b in draws]).reshape(self.n_folds, extra, n)
            self.wh, self.bh = nn.Parameter(weights), nn.Parameter(biases)
        if SNNTimeConstants(time_constants) is SNNTimeConstants.LEARNED:
            # After the drawn layers, and drawn from no generator: the weights stay those of
            # a shared time constant with the same seed.
            start = torch.full(
                (self.n_folds, self.hidden_layers, self.hidden_neurons), math.log(tau_mem_s)
            )
            self.log_tau_s = nn.Parameter(start)

    def decays(self, batch: int, layer: int = 0) -> float | torch.Tensor:
        """The decay :math:`\\beta` of hidden layer ``layer``'s neurons: one float for a shared
        time constant, else float32 ``(F * batch, hidden)``, :math:`\\exp(-\\Delta t / \\tau_i)`
        of each fold's learned :math:`\\tau_i`, exp(``log_tau_s``), repeated over its ``batch``
        samples."""
        if not hasattr(self, "log_tau_s"):
            return self.beta
        beta = torch.exp(-self.step_s / torch.exp(self.log_tau_s[:, layer]))  # (F, hidden)
        return beta.unsqueeze(1).expand(-1, batch, -1).reshape(-1, self.hidden_neurons)

    def layer_spikes(
        self, x: torch.Tensor, keep: bool = True, ends: torch.Tensor | None = None
    ) -> list[tuple[torch.Tensor, torch.Tensor]]:
        """For each hidden LIF layer, its spikes ``float32 (F, B, T, hidden)`` for
        ``x: (F, B, C, H, T)`` (the last layer's empty unless ``keep``) and their mean over the
        steps ``(F, B, hidden)``; a layer after the first is driven by the current
        :math:`W_h^\\top s_t + b_h` of the spikes of the one before. ``ends`` (int64
        ``(F, B)``, with ``keep=False``): the last layer's mean is over the steps up to
        ``ends[f, b]``."""
        self._check(x)
        n_folds, batch, c, h, n_steps = x.shape
        n = self.hidden_neurons
        steps = x.reshape(n_folds, batch, c * h, n_steps).transpose(2, 3)  # (F, B, T, C*H)
        current = torch.baddbmm(
            self.b1.unsqueeze(1), steps.reshape(n_folds, batch * n_steps, c * h), self.w1
        )  # (F, B*T, hidden): every step's input current in one product
        layers = []
        for layer in range(self.hidden_layers):
            last = layer == self.hidden_layers - 1
            spikes, rate = LeakyLayer.apply(
                current.reshape(n_folds * batch, n_steps, n),
                self.decays(batch, layer),
                self.threshold,
                self.surrogate_slope,
                keep or not last,
                None if ends is None or not last else ends.reshape(-1),
            )
            if keep or not last:
                spikes = spikes.reshape(n_folds, batch, n_steps, n)
            layers.append((spikes, rate.reshape(n_folds, batch, n)))
            if not last:
                current = torch.baddbmm(
                    self.bh[:, layer].unsqueeze(1),
                    spikes.reshape(n_folds, batch * n_steps, n),
                    self.wh[:, layer],
                )
        return layers

    def hidden_spikes(
        self, x: torch.Tensor, keep: bool = True, ends: torch.Tensor | None = None
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Spikes ``float32 (F, B, T, hidden)`` of the last LIF layer for ``x: (F, B, C, H, T)``
        (empty unless ``keep``), and their mean over the steps ``(F, B, hidden)``."""
        return self.layer_spikes(x, keep, ends)[-1]

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """Logits ``float32 (F, B, n_classes)`` of the decision read at the last step: what
        training for the full touch fits (for the mean readout, from the spike counts alone)."""
        if self.readout is not SNNReadout.MEAN_CURRENT:
            return self.decision_logits(x)[:, :, -1]
        _, rate = self.hidden_spikes(x, keep=False)
        return torch.baddbmm(self.b2.unsqueeze(1), rate, self.w2)

    def logits_at(self, x: torch.Tensor, ends: torch.Tensor) -> torch.Tensor:
        """Logits ``float32 (F, B, n_classes)`` of each sample's decision at its step
        ``ends[f, b]`` (int64 ``(F, B)``): for the mean readout, from the spike counts up to it
        alone, :math:`z_k = W_2^\\top \\frac{1}{k} \\sum_{t \\le k} s_t + b_2`."""
        if self.readout is not SNNReadout.MEAN_CURRENT:
            every = self.decision_logits(x)  # (F, B, T, n_classes)
            index = ends.reshape(*ends.shape, 1, 1).expand(-1, -1, 1, self.n_classes)
            return every.gather(2, index).squeeze(2)
        _, rate = self.hidden_spikes(x, keep=False, ends=ends)  # (F, B, hidden)
        return torch.baddbmm(self.b2.unsqueeze(1), rate, self.w2)

    def step_weights(self, n_steps: int) -> torch.Tensor:
        """float32 ``(T,)``, summing to 1: how the loss along the touch weighs each step's
        decision (``along_touch_loss``): equally (``every_step``), or :math:`\\propto
        t^{-1/2}` (``early_steps``)."""
        t = torch.arange(1, n_steps + 1, dtype=torch.float64)
        early = self.along_touch_loss is SNNAlongLoss.EARLY_STEPS
        weights = t**-0.5 if early else torch.ones_like(t)
        return (weights / weights.sum()).to(torch.float32)

    def step_losses(self, x: torch.Tensor, targets: torch.Tensor) -> torch.Tensor:
        """float32 ``(F, B)``: each sample's cross-entropy of the decision read at each step
        (:meth:`decision_logits`) for the int64 ``targets (F, B)``, summed over the steps
        weighed by :meth:`step_weights`; for the mean readout by :class:`MeanCurrentLoss`, the
        same loss without every step's logits in autograd."""
        weights = self.step_weights(x.shape[-1])
        if self.readout is SNNReadout.MEAN_CURRENT:
            spikes, _ = self.hidden_spikes(x)
            return MeanCurrentLoss.apply(spikes, self.w2, self.b2, targets, weights)
        logits = self.decision_logits(x)  # (F, B, T, n_classes)
        n_steps = logits.shape[2]
        every = targets.unsqueeze(2).expand(-1, -1, n_steps)
        losses = F.cross_entropy(
            logits.reshape(-1, self.n_classes), every.reshape(-1), reduction="none"
        )
        return losses.reshape(*targets.shape, n_steps) @ weights

    def decision_logits(self, x: torch.Tensor) -> torch.Tensor:
        """Logits ``float32 (F, B, T, n_classes)`` of a decision read at every step, as
        ``readout`` says (the module docstring; the last step's is :meth:`forward`'s)."""
        spikes, _ = self.hidden_spikes(x)
        n_folds, batch, n_steps, hidden = spikes.shape
        out = torch.bmm(spikes.reshape(n_folds, batch * n_steps, hidden), self.w2)
        out = out.reshape(n_folds, batch, n_steps, self.n_classes)
        bias = self.b2.reshape(n_folds, 1, 1, -1)
        if self.readout is SNNReadout.MEAN_CURRENT:
            count = torch.arange(1, n_steps + 1, dtype=out.dtype).reshape(1, 1, -1, 1)
            return out.cumsum(dim=2) / count + bias
        out = out + bias
        lag = torch.arange(n_steps).reshape(-1, 1) - torch.arange(n_steps).reshape(1, -1)
        weights = torch.where(
            lag >= 0, (1 - self.beta) * self.beta ** lag.clamp(min=0).to(out.dtype), 0.0
        )  # (T, T): row t weighs the steps up to t, as the leaky integrator does
        membrane = torch.einsum("ts,fbsc->fbtc", weights.to(out.dtype), out)
        if self.readout is SNNReadout.LAST_MEMBRANE:
            return membrane
        return torch.cummax(membrane, dim=2).values
