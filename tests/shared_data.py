"""Data of the shared folder beside the repository (``../shared``, at a depth that differs between
checkouts): the VibTac-12 and FabricSlide copies.

A test that needs one (the ``vibtac12`` fixture, :func:`vibtac12_copy`, :func:`fabricslide_copy`)
skips where the folder is absent, as on a clone without it, but fails when the environment
variable ``CI`` is set: CI always has ``../shared``, so its absence there is a broken set-up, not
a reason to test less.
"""

import os
from pathlib import Path

import pytest


def _shared(name: str) -> Path:
    return next(
        (
            parent / "shared/datasets" / name
            for parent in Path(__file__).resolve().parents
            if (parent / "shared/datasets" / name).is_dir()
        ),
        Path("shared/datasets") / name,
    )


VIBTAC12 = _shared("vibtac12")
FABRICSLIDE = _shared("fabricslide")


def vibtac12_copy() -> Path:
    """The VibTac-12 copy's folder; the test skips without it, or fails under CI."""
    return _present(VIBTAC12, VIBTAC12 / "Z.csv", "VibTac-12")


def fabricslide_copy() -> Path:
    """The FabricSlide copy's folder (no dataset.toml: copy what you need and add one); the test
    skips without it, or fails under CI."""
    return _present(FABRICSLIDE, FABRICSLIDE / "PROVENANCE.md", "FabricSlide")


def _present(folder: Path, witness: Path, name: str) -> Path:
    if witness.is_file():
        return folder
    message = f"the {name} copy is absent at {folder}"
    if os.environ.get("CI"):
        pytest.fail(f"{message}, and CI always has ../shared", pytrace=False)
    pytest.skip(message)
