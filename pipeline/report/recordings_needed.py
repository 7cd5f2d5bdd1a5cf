"""How many recordings per class would decide the answer, said beside it.

"Not significantly below the best" with a wide interval leaves a designer without a next step.
For each model's answer (:mod:`pipeline.report.answer`), the designs it names against the best
(the cheapest by data rate, the cheapest by power, and the *runner-up*, the most accurate of
the other designs compared with the best) each get the recordings per class at which a paired
test would find a loss of :data:`LOSS` (5 points) against the best with 80 % power at alpha
0.05, from the paired differences per recording this run measured
(:func:`pipeline.results.sample_size.recordings_per_class`, its method and limits there).

On the built-in recordings more touches are a scene field away (``dataset.recordings_per_class``),
and the sentence says what they would cost: the run's paid compute seconds
(:attr:`pipeline.report.cost.SweepCost.total_s`) per point and recording, times the recordings
asked for, times the points, taking the cost as proportional to the recordings (training and
encoding both are; the shared load of the recordings is too).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from pipeline.report.answer import Candidate, ModelAnswer
from pipeline.report.cost import SweepCost
from pipeline.report.evidence import Evidence
from pipeline.results.sample_size import ALPHA, POWER, recordings_per_class

LOSS = 0.05
"""The loss the recordings are counted for, as a fraction of accuracy (5 points)."""
#: The built-in dataset's kind, whose touches the scene can make more of.
BUILT_IN = "synthetic"
#: The scene field that sets how many built-in touches each class has.
PER_CLASS_FIELD = "dataset.recordings_per_class"


@dataclass(frozen=True)
class Needed:
    """One design against the model's best: its ``roles`` in the answer, its label, and the
    recordings per class a loss of :data:`LOSS` needs (None: cannot be estimated, the two
    designs predicted every recording alike)."""

    roles: tuple[str, ...]
    label: str
    per_class: int | None


@dataclass(frozen=True)
class RecordingsNeeded:
    """What would decide one model's answer.

    ``recordings`` is the recordings compared, of ``n_classes`` classes;
    ``seconds_per_recording`` the run's paid compute seconds per point and recording (NaN when
    unknown); ``points`` the run's distinct points; ``built_in`` whether the run's recordings
    are the built-in ones.
    """

    model: str
    needed: tuple[Needed, ...]
    recordings: int
    n_classes: int
    seconds_per_recording: float
    points: int
    built_in: bool

    @property
    def per_class_now(self) -> float:
        """This run's recordings per class."""
        return self.recordings / self.n_classes

    def seconds_for(self, per_class: int) -> float:
        """The run's compute seconds again at ``per_class`` recordings per class (s)."""
        return self.seconds_per_recording * self.points * per_class * self.n_classes


def recordings_needed(
    answers: Sequence[ModelAnswer],
    evidence: Evidence,
    n_classes: int | None,
    dataset: str,
    cost: SweepCost,
) -> tuple[RecordingsNeeded, ...]:
    """One :class:`RecordingsNeeded` per model whose answer names a design other than the best
    that was compared with it; none without the class count."""
    if not n_classes:
        return ()
    found = []
    for answer in answers:
        rows: dict[str, tuple[Candidate, list[str]]] = {}
        for chosen, role in _compared(answer):
            rows.setdefault(chosen.design.key, (chosen, []))[1].append(role)
        needed, recordings = [], 0
        for chosen, roles in rows.values():
            d = evidence.differences(chosen.design.key, answer.best.design.key, answer.model)
            if d is None:
                continue
            recordings = max(recordings, d.size)
            k = recordings_per_class(d, LOSS, n_classes)
            needed.append(Needed(tuple(roles), chosen.design.label, k))
        if not needed:
            continue
        paid = cost.total_s / (cost.n_points * recordings) if cost.n_points else math.nan
        found.append(
            RecordingsNeeded(
                model=answer.model,
                needed=tuple(needed),
                recordings=recordings,
                n_classes=n_classes,
                seconds_per_recording=paid if paid > 0 else math.nan,
                points=cost.n_points,
                built_in=dataset == BUILT_IN,
            )
        )
    return tuple(found)


def needed_sentence(found: RecordingsNeeded) -> str:
    """The recordings per class that would decide the answer, in one or two sentences."""
    name = found.model.upper()
    counted = [
        f"about {n.per_class} touches per class for {_who(n)}"
        for n in found.needed
        if n.per_class is not None
    ]
    alike = [_who(n) for n in found.needed if n.per_class is None]
    text = ""
    if counted:
        text = (
            f"to show a loss of {100 * LOSS:g} points or more against the best, record "
            + "; ".join(counted)
            + f" (this run has {found.per_class_now:g} per class; a paired t-test at "
            f"{100 * POWER:g} % power and alpha {ALPHA:g} on the differences per recording this "
            "run measured)"
        )
    if alike:
        text += "; " if text else ""
        text += (
            " and ".join(alike)
            + f" and the best agree on every recording: {'its' if len(alike) == 1 else 'their'} "
            "differences give no spread to count recordings from"
        )
    text = f"{name}: {text}."
    asked = [n.per_class for n in found.needed if n.per_class is not None]
    if found.built_in and asked:
        most = max(asked)
        text += f" The built-in data makes more touches ({PER_CLASS_FIELD} = {most})"
        if math.isfinite(found.seconds_per_recording):
            text += (
                f": at this run's {found.seconds_per_recording:.3g} s of compute per recording "
                f"and point, its {found.points} points would take about "
                f"{_seconds(found.seconds_for(most))}"
            )
        text += "."
    return text


def _who(needed: Needed) -> str:
    """``the cheapest by data rate and by power, also the runner-up (label)``."""
    cheapest = [r.removeprefix(_CHEAPEST) for r in needed.roles if r.startswith(_CHEAPEST)]
    others = [r for r in needed.roles if not r.startswith(_CHEAPEST)]
    named = [_CHEAPEST + " and by ".join(cheapest)] if cheapest else []
    text = ", also ".join(named + others) if named else " and ".join(others)
    return f"{text} ({needed.label})"


_CHEAPEST = "the cheapest by "


def _compared(answer: ModelAnswer) -> list[tuple[Candidate, str]]:
    """The answer's designs other than the best that were compared with it, with their role."""
    chosen = [
        (answer.by_data_rate, "the cheapest by data rate"),
        (answer.by_power, "the cheapest by power"),
    ]
    tested = [c for c in answer.candidates if c is not answer.best and c.versus_best is not None]
    if tested:
        chosen.append((max(tested, key=lambda c: c.accuracy.mean), "the runner-up"))
    return [(c, role) for c, role in chosen if c is not None and c is not answer.best]


def _seconds(seconds: float) -> str:
    """``950 s`` or, from an hour on, ``3.2 h`` beside it."""
    if seconds < 3600:
        return f"{seconds:.0f} s"
    return f"{seconds:.3g} s ({seconds / 3600:.2g} h)"
