"""Errors raised for bad user input.

Every error a user can cause is an :class:`EskinError`. Its message is one line that names what
was wrong and where (a scene field, a file, a recording), so the command line can print it as is.
Programming errors stay ordinary exceptions.
"""

from __future__ import annotations


class EskinError(ValueError):
    """Bad user input; ``str(error)`` is one line naming what and where.

    ``exit_status`` is the command line's exit status for it: 2 for bad input or usage; a
    subclass for a run that failed on good input says 1.
    """

    exit_status = 2


class SceneError(EskinError):
    """A scene or grid description is invalid; lists every problem found, not just the first.

    Parameters
    ----------
    problems
        One entry per problem, each of the form ``"<field>: <what is wrong>"``.
    source
        Where the description came from (a file path or ``"<dict>"``).
    kind
        What is described: ``"scene"`` or ``"grid"``.
    """

    def __init__(self, problems: list[str], source: str = "<dict>", kind: str = "scene"):
        self.problems = list(problems)
        self.source = source
        n = len(self.problems)
        head = f"invalid {kind} {source}" + (f" ({n} problems)" if n > 1 else "")
        text = f"{head}: " + "; ".join(self.problems)
        # Keys and values come from user files and may hold line breaks; the message is one line.
        super().__init__(text.replace("\r", "\\r").replace("\n", "\\n"))


class DatasetError(EskinError):
    """A dataset cannot be read or is unusable; the message names the file or recording."""


class SimulationError(EskinError):
    """A scene is valid on its own but cannot run on these recordings (e.g. too many spikes)."""
