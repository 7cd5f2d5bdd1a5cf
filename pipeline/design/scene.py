"""Scenes: frozen, validated descriptions of one simulated situation.

A scene has five parts (``dataset``, ``array``, ``readout``, ``coding``, ``training``) and a
``seed``. It loads from a dict or a TOML file, rejects unknown keys and out-of-range values with a
message naming every offending field at once, and has a canonical form (sorted keys, units in the
field names) from which cache keys are hashed.

Every field is declared once, on its dataclass (:func:`pipeline.design.fields.param`): type,
default, units, accepted range, description, whether its default is neutral and what it does to a
point's cost. Reading and validation, the canonical form, dotted paths, result cubes' coordinate
labels and the listing of fields (:func:`scene_fields`) follow from those declarations. The
canonical form leaves out a field at a neutral default, so a field added with a neutral default
that reproduces what was simulated before it existed changes no existing cache key.

Readout *effects* are a mapping from effect name to parameters (:mod:`pipeline.design.effects`). An
effect that is not named is not simulated and is not part of any cache key; an ideal scene names
none. The scene seed enters the spike-train key only when a named effect draws random numbers.

Cache keys (:func:`pipeline.run.stages.cache_key`) hash exactly the fields a stage depends on; which
fields those are is declared with the stages themselves, in :mod:`pipeline.run.stages`::

    recordings : dataset
    spikes     : dataset, array, readout (+ seed if a random effect is named; readout.decay
                 only with the decaying encoder)
    rates      : spikes fields + coding
    results    : rates fields + training

Many scenes that differ in a few fields (a grid's points) are built by
:class:`pipeline.design.variants.SceneVariants`, which reads each part once per distinct
combination of the values in it and shares the part between the scenes. The canonical form is
written part by part (the JSON of a dict with sorted keys is its items' JSON in key order), so a
memo writes a shared part once for all its scenes.
"""

from __future__ import annotations

import enum
import functools
import json
import math
import tomllib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any, Literal

from pipeline.design import fields
from pipeline.design.effects import (
    EFFECT_TYPES,
    FIXED_EFFECTS,
    RANDOM_EFFECTS,
    Effect,
)
from pipeline.design.fields import POSITIVE, Cost, NonEmpty, Range, Seed, param, part
from pipeline.errors import SceneError

MAX_TAXELS_PER_SIDE = 256

_TAU = Range(0, 3600, low_open=True)


class DatasetKind(enum.StrEnum):
    """Where recordings come from."""

    SYNTHETIC = "synthetic"
    VIBTAC12 = "vibtac12"
    FOLDER = "folder"


class Axis(enum.StrEnum):
    """Accelerometer axis of the VibTac-12 recordings."""

    X = "x"
    Y = "y"
    Z = "z"


class ScanDirection(enum.StrEnum):
    """Scan direction ``(d_x, d_y)`` across the taxel grid."""

    Y = "y"  # along rows: taxel (i, j) is delayed by i * pitch / speed (the paper's Fig. 4)
    X = "x"  # along columns
    XY = "xy"  # diagonal, unit vector (1, 1) / sqrt(2)

    @property
    def vector(self) -> tuple[float, float]:
        """``(d_x, d_y)``."""
        return {"y": (0.0, 1.0), "x": (1.0, 0.0), "xy": (math.sqrt(0.5), math.sqrt(0.5))}[
            self.value
        ]


class Polarity(enum.StrEnum):
    """How ON and OFF spikes enter the rate code."""

    MERGED = "merged"  # one count per window, both polarities (the paper)
    SPLIT = "split"  # two channels: +1 spikes, then -1 spikes


class Model(enum.StrEnum):
    """Classifiers."""

    FFNN = "ffnn"
    CNN = "cnn"
    SNN = "snn"  # leaky integrate-and-fire layer on the spike trains, deciding at every step


class DecisionTraining(enum.StrEnum):
    """What decisions the decoders are trained for (:mod:`pipeline.chain.decoders`)."""

    FULL_TOUCH = "full_touch"  # the decision at the end of the touch; earlier ones read it early
    ALONG_TOUCH = "along_touch"  # a decision at every time along the touch (prefixes, steps)


class SNNInputs(enum.StrEnum):
    """How the spiking decoder's step counts become its input currents."""

    COUNTS = "counts"  # the event counts themselves
    LOG_COUNTS = "log_counts"  # log(1 + count): a burst counts less than its events
    STANDARDIZED = "standardized"  # per input and step, with the fold's training statistics


class SNNTimeConstants(enum.StrEnum):
    """The membrane time constants of the spiking decoder's neurons."""

    SHARED = "shared"  # one, tau_mem_s, for every neuron, fixed
    LEARNED = "learned"  # one per neuron, starting at tau_mem_s, trained with the weights


class SNNReadout(enum.StrEnum):
    """How the spiking decoder's output currents become a decision at a step."""

    MEAN_CURRENT = "mean_current"  # their mean since the touch began (weighted spike counts)
    LAST_MEMBRANE = "last_membrane"  # a leaky integrator's membrane (tau_mem_s) at that step
    MAX_MEMBRANE = "max_membrane"  # that membrane's maximum since the touch began


class SNNAlongLoss(enum.StrEnum):
    """What the spiking decoder's training along the touch minimizes."""

    EVERY_STEP = "every_step"  # the mean over the steps of each step's cross-entropy
    DRAWN_STEP = "drawn_step"  # each sample's at one step drawn per epoch, as the FFNN's and CNN's
    EARLY_STEPS = "early_steps"  # every step's, weighed toward the early ones (1 / sqrt(t))


class Encoder(enum.StrEnum):
    """Encoder architecture of the readout."""

    LCS = "lcs"  # level crossing with a fixed threshold (the paper)
    DECAYING = "decaying"  # the threshold restarts at threshold_v after a spike, then decays


class Deployment(enum.StrEnum):
    """How one trained classifier meets the chips of a design (:mod:`pipeline.chain.deployment`)."""

    PER_CHIP = "per_chip"  # each chip is calibrated: trained and tested on its own encoding
    SHARED = "shared"  # one classifier, trained on the nominal chip, loaded into every chip
    ROBUST = "robust"  # one classifier, trained on chips drawn apart from the tested ones


# ---------------------------------------------------------------------------------------------
# Scene parts


@dataclass(frozen=True)
class DatasetSpec:
    """Which recordings, and how they are cut.

    ``kind="synthetic"`` is the embedded default (``seed``, ``recordings_per_class``,
    ``duration_s``); ``vibtac12`` reads the X/Y/Z CSVs in ``path`` (``axis``, ``segments``,
    ``sampling_rate_hz``, default 200 Hz); ``folder`` reads ``path/dataset.toml``.
    """

    kind: DatasetKind = param(DatasetKind.SYNTHETIC, "1", "source of the recordings")
    path: str | None = param(None, "1", "folder of the recordings")
    sampling_rate_hz: float | None = param(
        None, "Hz", "sampling rate of the VibTac-12 recordings", within=POSITIVE
    )
    axis: Axis = param(Axis.Z, "1", "accelerometer axis of the VibTac-12 recordings")
    segments: int = param(
        10, "1", "segments cut from each VibTac-12 recording", within=Range(1, 1000)
    )
    seed: Seed = param(0, "1", "seed of the built-in recordings", cost=Cost.FREE)
    recordings_per_class: int = param(
        10, "1", "built-in recordings per class", within=Range(1, 10_000)
    )
    duration_s: float = param(
        5.0, "s", "duration of each built-in recording", within=Range(0.1, 36_000)
    )

    def refusals(self) -> Iterator[tuple[str, str]]:
        """What the fields refuse together: a dataset read from files needs its path."""
        if self.kind in (DatasetKind.VIBTAC12, DatasetKind.FOLDER) and not self.path:
            yield "path", f"required for kind {self.kind.value!r}"


_SIDE = Range(1, MAX_TAXELS_PER_SIDE)


@dataclass(frozen=True)
class ArraySpec:
    """Taxel grid ``rows x cols`` at ``pitch_mm``, scanned at ``speed_mm_s`` along ``direction``:
    an array made of time-shifted copies of one recorded channel.

    On recordings of a real array (one column per taxel), ``taxels`` says how many of its taxels
    the design reads (:mod:`pipeline.chain.real_taxels`) and the grid stays ``1 x 1``: time
    shifts and real taxels are two ways of making an array, not to be mixed
    (:mod:`pipeline.run.fit` refuses a design that asks for both, or for more taxels than the
    recordings hold).
    """

    rows: int = param(3, "1", "taxel rows of the array", within=_SIDE, cost=Cost.SIZE)
    cols: int = param(3, "1", "taxel columns of the array", within=_SIDE, cost=Cost.SIZE)
    pitch_mm: float = param(1.0, "mm", "distance between neighbouring taxels", within=POSITIVE)
    speed_mm_s: float = param(20.0, "mm/s", "scan speed across the array", within=POSITIVE)
    direction: ScanDirection = param(ScanDirection.Y, "1", "scan direction across the taxel grid")
    taxels: int | None = param(
        None,
        "1",
        "taxels of a real array read (recordings with one column per taxel; unset: all): "
        "spread evenly over the taxel positions when the dataset gives them, else over its "
        "declared order of taxels",
        within=Range(1, MAX_TAXELS_PER_SIDE**2),
    )

    @property
    def n_taxels(self) -> int:
        """Number of taxels of the time-shift grid, ``rows * cols``; the taxels of a real array
        are :func:`pipeline.chain.real_taxels.taxels_read`."""
        return self.rows * self.cols


@dataclass(frozen=True)
class DecaySpec:
    """Threshold of the decaying encoder: after each spike it restarts at ``threshold_v`` and
    decays toward ``theta_min_v`` with time constant ``tau_s``."""

    theta_min_v: float = param(
        0.03, "V", "lowest threshold of the decaying encoder", within=POSITIVE, cost=Cost.FREE
    )
    tau_s: float = param(
        0.02, "s", "time constant of the decaying threshold", within=_TAU, cost=Cost.FREE
    )


@dataclass(frozen=True)
class ReadoutSpec:
    """Level-crossing readout: ``threshold_v`` of a ``full_scale_v`` range, the ``encoder``
    architecture (with the ``decay`` of its threshold for the decaying one), and effects."""

    threshold_v: float = param(
        0.09,
        "V",
        "comparator threshold (level-crossing step)",
        within=POSITIVE,
        cost=Cost.FREE,
    )
    full_scale_v: float = param(1.0, "V", "full-scale input range of the readout", within=POSITIVE)
    encoder: Encoder = param(
        Encoder.LCS, "1", "encoder architecture (threshold_v is its first threshold)", neutral=True
    )
    decay: DecaySpec = part(DecaySpec, only_when=("encoder", Encoder.DECAYING))
    effects: Mapping[Effect, Any] = param(
        units="1",
        long_name="non-ideal readout effects and their parameters",
        default_factory=dict,
        entries=EFFECT_TYPES,
    )

    def refusals(self) -> Iterator[tuple[str, str]]:
        """What the fields refuse together: the threshold must be below the full scale, and the
        decaying encoder's lowest threshold not above its first."""
        if self.threshold_v >= self.full_scale_v:
            yield (
                "threshold_v",
                f"{self.threshold_v!r} V is not below full_scale_v = {self.full_scale_v!r} V",
            )
        if self.encoder is Encoder.DECAYING and self.decay.theta_min_v > self.threshold_v:
            yield (
                "decay.theta_min_v",
                f"{self.decay.theta_min_v!r} V is above threshold_v = {self.threshold_v!r} V "
                "(the decaying threshold starts at threshold_v)",
            )

    @property
    def theta_min_v(self) -> float:
        """The lowest threshold the encoder reaches (V), ``threshold_v`` for a fixed threshold."""
        if self.encoder is Encoder.DECAYING:
            return self.decay.theta_min_v
        return self.threshold_v

    @property
    def is_ideal(self) -> bool:
        """Whether the readout names no effect (its REAL train is its TRUE train)."""
        return not self.effects

    @property
    def is_random(self) -> bool:
        """Whether a named effect draws random numbers (every effect but ``saturation``), so
        that the scene's ``seed`` matters."""
        return any(e in RANDOM_EFFECTS for e in self.effects)

    @property
    def draws_fixed_effects(self) -> bool:
        """Whether a named effect is drawn once per chip
        (:data:`~pipeline.design.effects.FIXED_EFFECTS`), so that chips of the design differ."""
        return any(e in FIXED_EFFECTS for e in self.effects)

    @property
    def equivalent_bits(self) -> float:
        """Resolution in bits, ``log2(full_scale_v / threshold_v)`` (of the first threshold)."""
        return math.log2(self.full_scale_v / self.threshold_v)


@dataclass(frozen=True)
class CodingSpec:
    """Rate coding: ``n_windows`` windows of ``window_s``; ``"auto"`` fits the recordings."""

    window_s: float = param(0.1, "s", "rate-coding window length", within=Range(1e-6, 3600))
    n_windows: int | Literal["auto"] = param(
        "auto",
        "1",
        "rate-coding windows per recording",
        within=Range(1, 100_000, also=("auto",)),
        cost=Cost.SIZE,
    )
    polarity: Polarity = param(Polarity.MERGED, "1", "how ON and OFF spikes enter the rate code")


@dataclass(frozen=True)
class SNNSpec:
    """The spiking decoder (:class:`~pipeline.chain.spiking.FoldSNN`): ON and OFF spikes of each
    taxel counted in steps of ``step_s``, ``hidden_layers`` layers of ``hidden_neurons`` leaky
    integrate-and-fire neurons (their time constants as ``time_constants`` says), a readout read
    at every step as ``readout`` says; trained ``epochs`` epochs through time with a
    fast-sigmoid surrogate gradient of slope ``surrogate_slope``, on its counts as ``inputs``
    says, at its own ``learning_rate`` when set."""

    # Its step and epochs: chosen by measurement at the paper point (docs/model.md).
    step_s: float = param(
        0.05,
        "s",
        "time step of the spiking decoder (spikes binned per step; divides coding.window_s)",
        within=Range(1e-4, 3600),
    )
    hidden_neurons: int = param(
        100, "1", "leaky integrate-and-fire neurons of the spiking decoder", within=Range(1, 10_000)
    )
    tau_mem_s: float = param(
        0.1, "s", "membrane time constant of the spiking decoder's neurons", within=_TAU
    )
    threshold: float = param(
        1.0,
        "1",
        "firing threshold of the spiking decoder's membrane (input current units)",
        within=POSITIVE,
        cost=Cost.FREE,
    )
    surrogate_slope: float = param(
        25.0,
        "1",
        "slope of the fast-sigmoid surrogate gradient of a spike (per unit of membrane)",
        within=POSITIVE,
        cost=Cost.FREE,
    )
    epochs: int = param(
        200, "1", "training epochs of the spiking decoder", within=Range(1, 100_000)
    )
    # Its inputs and learning rate: chosen by measurement at the paper point (docs/model.md);
    # the counts at training.learning_rate, as it was first built, keep their keys.
    inputs: SNNInputs = param(
        SNNInputs.STANDARDIZED,
        "1",
        "how step counts become the spiking decoder's inputs",
        formerly=SNNInputs.COUNTS,
    )
    # Its time constants: learned, chosen by measurement along the touch (docs/model.md).
    time_constants: SNNTimeConstants = param(
        SNNTimeConstants.LEARNED,
        "1",
        "membrane time constants of the spiking decoder: tau_mem_s for every neuron, or one per "
        "neuron learned from it",
        formerly=SNNTimeConstants.SHARED,
    )
    hidden_layers: int = param(
        1,
        "1",
        "layers of hidden_neurons leaky integrate-and-fire neurons, each driven by the spikes "
        "of the one before",
        within=Range(1, 4),
        formerly=1,
    )
    along_touch_loss: SNNAlongLoss = param(
        SNNAlongLoss.EVERY_STEP,
        "1",
        "what the spiking decoder's training along the touch minimizes: every step's decision, "
        "one drawn step's per sample and epoch, or every step's weighed toward the early ones",
        formerly=SNNAlongLoss.EVERY_STEP,
    )
    readout: SNNReadout = param(
        SNNReadout.MEAN_CURRENT,
        "1",
        "how the spiking decoder's output currents become its decision at a step",
        formerly=SNNReadout.MEAN_CURRENT,
    )
    learning_rate: float | None = param(
        0.01,
        "1",
        "Adam learning rate of the spiking decoder (unset: training.learning_rate)",
        within=Range(0, 10, low_open=True),
    )


@dataclass(frozen=True)
class TrainingSpec:
    """Classifiers and stratified k-fold cross-validation."""

    models: tuple[Model, ...] = param(
        (Model.FFNN, Model.CNN), "1", "classifiers trained", within=NonEmpty(), cost=Cost.SIZE
    )
    epochs: int = param(100, "1", "training epochs", within=Range(1, 100_000))
    learning_rate: float = param(
        1e-3, "1", "Adam learning rate", within=Range(0, 10, low_open=True)
    )
    hidden_units: int = param(100, "1", "hidden units of the FFNN", within=Range(1, 100_000))
    batch_size: int = param(16, "1", "training batch size", within=Range(1, 1_000_000))
    folds: int = param(10, "1", "cross-validation folds", within=Range(2, 1000))
    repeats: int = param(
        1,
        "1",
        "cross-validation repeats, each a fresh stratified split",
        within=Range(1, 100),
    )
    seed: Seed = param(0, "1", "training seed", cost=Cost.FREE)
    decisions: DecisionTraining = param(
        DecisionTraining.ALONG_TOUCH,
        "1",
        "decisions the decoders are trained for: along the touch, or at its end only",
        formerly=DecisionTraining.FULL_TOUCH,
    )
    snn: SNNSpec = part(SNNSpec, only_when=("models", Model.SNN))


MAX_CHIPS = 1000


@dataclass(frozen=True)
class ChipsSpec:
    """Chips built from the design: ``count`` simulated chips, each with its own draw of the
    readout's fixed effects (offsets, threshold mismatch), and how the classifier is
    ``deployment`` onto them (:mod:`pipeline.chain.chips`, :mod:`pipeline.chain.deployment`).

    ``yield_target`` is the accuracy a chip must reach to count toward the yield
    (:mod:`pipeline.results.yields`); it changes no simulation, only the cube's yield share.
    Its default, 0.5, is a plain majority-correct bar that does not depend on the data set
    (chance is one over the class count); a designer sets the bar the application needs.
    """

    count: int = param(
        1,
        "1",
        "simulated chips of the design",
        within=Range(1, MAX_CHIPS),
        neutral=True,
        cost=Cost.SIZE,
    )
    deployment: Deployment = param(
        Deployment.PER_CHIP,
        "1",
        "how the trained classifier is deployed onto the chips",
        neutral=True,
    )
    yield_target: float = param(
        0.5,
        "1",
        "accuracy a chip must reach to count toward the yield",
        within=Range(0, 1, low_open=True, high_open=True),
        neutral=True,
        cost=Cost.FREE,
    )

    @property
    def simulated(self) -> bool:
        """Whether the scene simulates chips beyond today's one (more than one, or a
        deployment other than ``per_chip``)."""
        return self.count > 1 or self.deployment is not Deployment.PER_CHIP


@dataclass(frozen=True)
class Scene:
    """One simulated situation. Build with :meth:`from_dict`, :meth:`from_toml` or :meth:`paper`."""

    name: str = param("scene", "1", "scene name", label=True)
    seed: Seed = param(0, "1", "scene seed (random readout effects)", cost=Cost.FREE)
    dataset: DatasetSpec = part(DatasetSpec)
    array: ArraySpec = part(ArraySpec)
    readout: ReadoutSpec = part(ReadoutSpec)
    coding: CodingSpec = part(CodingSpec)
    training: TrainingSpec = part(TrainingSpec)
    chips: ChipsSpec = part(ChipsSpec)

    def refusals(self) -> Iterator[tuple[str, str]]:
        """What the parts refuse together: a deployment of one classifier onto many chips
        needs a readout whose chips differ (a named fixed effect); the spiking decoder's step
        must fit whole in a rate-coding window, so that every window boundary is one of its
        decision times."""
        yield from chip_refusals(self)
        if not fields.part_applies(self.training, "snn"):
            return
        step_s, window_s = self.training.snn.step_s, self.coding.window_s
        steps = round(window_s / step_s)
        if step_s > window_s:
            yield (
                "training.snn.step_s",
                f"{step_s!r} s is longer than coding.window_s = {window_s!r} s",
            )
        elif abs(steps * step_s - window_s) > 1e-9 * window_s:
            yield (
                "training.snn.step_s",
                f"{step_s!r} s does not divide coding.window_s = {window_s!r} s",
            )

    # -- construction ---------------------------------------------------------------------------

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "<dict>") -> Scene:
        """Validate ``data`` (the TOML layout) and build a scene; raise
        :class:`~pipeline.errors.SceneError`."""
        problems: list[str] = []
        scene = fields.read(cls, data, "", problems)
        if problems:
            raise SceneError(problems, source)
        return scene

    @classmethod
    def from_toml(cls, path: str | Path) -> Scene:
        """Load a scene from a TOML file."""
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            raise SceneError([f"cannot read file: {exc.strerror}"], str(path)) from None
        except UnicodeDecodeError as exc:
            raise SceneError([f"not UTF-8 text (byte {exc.start})"], str(path)) from None
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise SceneError([f"not valid TOML: {exc}"], str(path)) from None
        data.setdefault("name", path.stem)
        return cls.from_dict(with_dataset_path_from(data, path.parent), source=str(path))

    @classmethod
    def builtin(cls, name: str) -> Scene:
        """A scene shipped with the package (``paper``, ``smoke``)."""
        names = builtin_scene_names()
        if name not in names:
            raise SceneError([f"no built-in scene {name!r} (built-in: {', '.join(names)})"], name)
        text = resources.files("pipeline.design.scenes").joinpath(f"{name}.toml").read_text("utf-8")
        data = tomllib.loads(text)
        data.setdefault("name", name)
        return cls.from_dict(data, source=f"built-in scene {name!r}")

    @classmethod
    def paper(cls) -> Scene:
        """The paper's operating point: 3x3 taxels, 0.09 V of 1 V, 0.1 s x 40 windows, FFNN+CNN."""
        return cls.builtin("paper")

    @classmethod
    def load(cls, name_or_path: str) -> Scene:
        """A built-in scene by name, or a TOML file by path."""
        if name_or_path in builtin_scene_names():
            return cls.builtin(name_or_path)
        return cls.from_toml(name_or_path)

    def replace(self, **changes: Any) -> Scene:
        """A copy with dotted fields replaced (``{"readout.threshold_v": 0.05}``), re-validated."""
        data = self.to_dict()
        for dotted, value in changes.items():
            fields.put(data, dotted, value)
        return type(self).from_dict(data, source=f"scene {self.name!r} with {sorted(changes)}")

    # -- canonical form -------------------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict in the TOML layout (enums as strings, tuples as lists)."""
        return fields.plain(self)

    def canonical(
        self, parts: tuple[str, ...] | None = None, memo: CanonicalMemo | None = None
    ) -> str:
        """Stable JSON of the scene (or of ``parts``: top-level parts such as ``"readout"``, or
        dotted fields of one such as ``"readout.full_scale_v"``), sorted, units in names; a
        field that is ``None`` or at a neutral default (:func:`pipeline.design.fields.param`) is
        left out, so that a field added with such a default changes no existing key.

        ``memo`` holds the canonical form of part objects already written: give the same dict
        for many scenes that share part objects (the scenes of a
        :class:`~pipeline.design.variants.SceneVariants`) and each part is written once. The text
        does not depend on it.
        """
        # The JSON of a dict with sorted keys is its items' JSON in key order, so each part can
        # be written (and remembered) on its own: the text is that of the whole selection.
        items = []
        plan = _canonical_plan(type(self), None if parts is None else tuple(parts))
        for top, paths in plan:
            value = getattr(self, top)
            if paths is None:
                slot = fields.slot_named(type(self))[top]
                if slot.part is None and fields.left_out(slot, value, canonical=True):
                    continue
                text = _canonical_part(value, memo)
            else:
                data = {top: fields.plain(value, canonical=True)}
                text = _canonical_json(fields.select(data, paths).get(top, {}))
            if text == "{}" and top in _LEFT_OUT_WHEN_EMPTY:
                continue  # a part added later, at its neutral defaults: no key changes
            items.append(f'"{top}":{text}')
        return "{" + ",".join(items) + "}"


#: Parts added after keys existed whose fields are all neutral: left out of the canonical form
#: (and of every key) while all of them hold their defaults.
_LEFT_OUT_WHEN_EMPTY = frozenset({"chips"})


def part_left_out(top: str, value: Any) -> bool:
    """Whether top-level part ``top`` holding ``value`` is left out of the canonical form (and
    of a cube's scene coordinates): a part added after keys existed, at its neutral defaults."""
    return top in _LEFT_OUT_WHEN_EMPTY and not fields.plain(value, canonical=True)


def chip_refusals(scene: Scene) -> Iterator[tuple[str, str]]:
    """``(field, text)`` for a ``shared`` or ``robust`` deployment whose readout draws no fixed
    effect: every chip would be the nominal one."""
    chips = scene.chips
    if chips.deployment is not Deployment.PER_CHIP and not scene.readout.draws_fixed_effects:
        fixed = ", ".join(sorted(e.value for e in FIXED_EFFECTS))
        yield (
            "chips.deployment",
            f"{chips.deployment.value!r} needs a readout effect drawn per chip ({fixed}); "
            "with none every chip is identical",
        )


#: Canonical memo: the canonical JSON of a part object by its ``id``, with the object itself,
#: which keeps it alive so that its ``id`` is not reused while the memo holds it.
CanonicalMemo = dict[int, tuple[Any, str]]


def _canonical_json(data: Any) -> str:
    return json.dumps(data, sort_keys=True, separators=(",", ":"), allow_nan=False)


def _canonical_part(value: Any, memo: CanonicalMemo | None) -> str:
    """The canonical JSON of one top-level part, from ``memo`` if it was written before."""
    if memo is None:
        return _canonical_json(fields.plain(value, canonical=True))
    found = memo.get(id(value))
    if found is None:
        found = memo[id(value)] = (value, _canonical_json(fields.plain(value, canonical=True)))
    return found[1]


def canonical_parts(cls: type[Scene]) -> tuple[str, ...]:
    """The top-level fields a canonical form of a ``cls`` holds: every field but labels."""
    return tuple(
        slot.name for slot in fields.slots(cls) if slot.declared is None or not slot.declared.label
    )


@functools.lru_cache(maxsize=64)
def _canonical_plan(
    cls: type[Scene], parts: tuple[str, ...] | None
) -> tuple[tuple[str, tuple[str, ...] | None], ...]:
    """The top-level parts ``parts`` (all if None) selects, sorted, each whole (None) or with
    its dotted fields; raises ``KeyError`` for a part that is not in the canonical form."""
    known = canonical_parts(cls)
    whole: set[str] = set()
    dotted: dict[str, list[str]] = {}
    for path in known if parts is None else parts:
        top = path.split(".", 1)[0]
        if top not in known:
            raise KeyError(top)
        if top == path:
            whole.add(top)
        else:
            dotted.setdefault(top, []).append(path)
    return tuple(
        (top, None if top in whole else tuple(dotted[top])) for top in sorted(whole | dotted.keys())
    )


#: Revision of what the stages compute for a given scene. Bump it with any change that alters a
#: stage's output for the same fields (a different random stream, a fixed bug, a new training
#: step), so that stores made before the change are recomputed instead of mixed with new points.
#: 2: comparator noise takes one draw per decision; ``threshold_mismatch.floor_rel`` is used.
#: 3: results keep every recording's out-of-fold prediction; the built-in recordings' classes
#: follow the statistics measured on real texture recordings.
#: 4: the built-in recordings are touches with a time course (contact, press, sliding).
#: 5: the built-in touches slide in stick-slip cycles and with macro texture (modulated at
#: 5-20 Hz, never quiet).
MODEL_REVISION = 5


def with_dataset_path_from(data: Mapping[str, Any], folder: Path) -> Mapping[str, Any]:
    """``data`` with a relative ``dataset.path`` made absolute against ``folder``.

    A scene file's dataset path means the same folder whatever directory the command runs in:
    a relative path is taken from the folder of the file that names it (``~`` is expanded).
    Anything but a string path is left for validation to report.
    """
    dataset = data.get("dataset")
    if not isinstance(dataset, Mapping) or not isinstance(dataset.get("path"), str):
        return data
    if not dataset["path"]:
        return data
    path = Path(dataset["path"]).expanduser()
    if not path.is_absolute():
        path = Path(folder).absolute() / path
    return {**data, "dataset": {**dataset, "path": str(path)}}


def scene_field(path: str) -> str:
    """Dotted ``path`` (``"readout.threshold_v"``) once checked against the declarations, so that
    code naming a field by its path fails when it loads, not when a cube lacks the field.

    Raises
    ------
    pipeline.design.fields.UnknownField
        ``path`` names no scene field.
    """
    fields.resolve(Scene, path)
    return path


def scene_fields() -> list[fields.FieldInfo]:
    """Every scene field with its type, default, units, range and description, effects'
    parameters included (:func:`pipeline.design.fields.listing`), for ``--help`` and the docs."""
    return fields.listing(Scene)


def builtin_scene_names() -> tuple[str, ...]:
    """Names of the built-in scenes (the TOML files of :mod:`pipeline.design.scenes`), sorted."""
    files = resources.files("pipeline.design.scenes").iterdir()
    return tuple(sorted(f.name[:-5] for f in files if f.name.endswith(".toml")))
