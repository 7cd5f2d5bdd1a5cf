"""The report's hardware constants: which it used, which a designer overrode, and from where.

Every declared constant (:data:`pipeline.results.hardware_constants.DECLARED`: the readout's power
model, Pelgrom's coefficient, the decoder's per-operation energies) is one row of
:func:`constants_rows`: its name, the value the report used in its declared unit, whether it was
overridden (``eskin report --constants FILE``, or a command-line option), what it is and where
the value comes from. :func:`constants_blocks` is the report's section: one sentence saying which
were overridden, the table below it, folded.
"""

from __future__ import annotations

from collections.abc import Iterator

from pipeline.report.blocks import Block, Details, Heading, Paragraph, Table
from pipeline.results.hardware_constants import DECLARED, Constants

CONSTANTS_TITLE = "Hardware constants"
CONSTANTS_COLUMNS = ("constant", "value", "overridden", "what it is", "source")


def constants_rows(constants: Constants) -> tuple[tuple[str, str, str, str, str], ...]:
    """One row per declared constant, in
    :data:`~pipeline.results.hardware_constants.DECLARED` order: name, the value used in its
    declared unit, ``"yes"`` where overridden (else ``"no"``), what it is, its value's
    source."""
    return tuple(
        (
            name,
            declared.in_unit(constants.value(name)),
            "yes" if name in constants.overrides else "no",
            declared.parameter.what,
            constants.source(name),
        )
        for name, declared in DECLARED.items()
    )


def constants_blocks(constants: Constants) -> Iterator[Block]:
    """The report's section on the constants it used: which were overridden, then the table."""
    yield Heading(2, CONSTANTS_TITLE)
    overridden = [n for n in DECLARED if n in constants.overrides]
    if overridden:
        origin = f" from {constants.origin}" if constants.origin else ""
        changed = ", ".join(
            f"{n} = {DECLARED[n].in_unit(constants.value(n))} (declared "
            f"{DECLARED[n].in_unit(DECLARED[n].default)})"
            for n in overridden
        )
        said = f"{len(overridden)} of {len(DECLARED)} were overridden{origin}: {changed}."
    else:
        said = f"All {len(DECLARED)} are as declared (give your own with --constants FILE)."
    yield Paragraph(
        "The readout's power, the matched area and the decoder's energy rest on hardware "
        f"constants, not on the simulation. {said}"
    )
    yield Details(
        "Every constant the report used, with its source",
        (Table(CONSTANTS_COLUMNS, constants_rows(constants)),),
    )
