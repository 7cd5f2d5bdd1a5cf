"""Data of the shared folder beside the repository (``../shared``, at a depth that differs between
checkouts): the VibTac-12 copy.

A test that needs it (the ``vibtac12`` fixture, :func:`vibtac12_copy`) skips where the folder is
absent, as on a clone without it, but fails when the environment variable ``CI`` is set: CI
always has ``../shared``, so its absence there is a broken set-up, not a reason to test less.
"""

import os
from pathlib import Path

import pytest

VIBTAC12 = next(
    (
        parent / "shared/datasets/vibtac12"
        for parent in Path(__file__).resolve().parents
        if (parent / "shared/datasets/vibtac12").is_dir()
    ),
    Path("shared/datasets/vibtac12"),
)


def vibtac12_copy() -> Path:
    """The VibTac-12 copy's folder; the test skips without it, or fails under CI."""
    if (VIBTAC12 / "Z.csv").is_file():
        return VIBTAC12
    message = f"the VibTac-12 copy is absent at {VIBTAC12}"
    if os.environ.get("CI"):
        pytest.fail(f"{message}, and CI always has ../shared", pytrace=False)
    pytest.skip(message)
