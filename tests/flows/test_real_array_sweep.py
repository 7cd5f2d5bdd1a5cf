"""A sweep over the number of a real array's taxels read, from a folder of 2-D ``.npy``
recordings through ``eskin sweep`` to the cube and the report; a design that reads more taxels
than recorded, or a time-shift grid on the array, refused before anything is written.
"""

import json

import pytest

from pipeline.design.scene import DatasetKind, DatasetSpec
from pipeline.recordings.sources import load_recordings
from storage import open_results
from tests.flows.helpers import eskin, hermetic_env
from tests.real_array_helpers import N_TAXELS, one_informative_taxel, write_npy_folder

pytestmark = pytest.mark.slow

GRID = """name = "taxels"
base = "smoke"

[sweeps.taxels]
axes = { "array.taxels" = [1, 2, 4] }

[sweeps.taxels.set]
"array.rows" = 1
"array.cols" = 1
"training.learning_rate" = 0.01
"training.epochs" = 60
"""


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    data = tmp_path_factory.mktemp("array") / "one informative taxel"
    write_npy_folder(one_informative_taxel(), data)
    read = load_recordings(DatasetSpec(kind=DatasetKind.FOLDER, path=str(data)))
    assert read.n_taxels == N_TAXELS
    return data


def test_a_sweep_over_the_taxels_read_gives_their_accuracy_and_the_report(
    folder, suite_cluster, tmp_path
):
    grid = tmp_path / "grid.toml"
    grid.write_text(GRID)
    root = tmp_path / "run"
    args = ("--grid", str(grid), "--dataset", str(folder), "--root", str(root))
    proc = eskin("sweep", *args, *suite_cluster, "--report", "--json", env=hermetic_env(tmp_path))
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert json.loads(proc.stdout)["computed"] == 3
    cube = open_results(root)["taxels"]
    assert cube["taxels"].values.tolist() == [1, 2, 4]
    accuracy = cube["accuracy_mean"].sel(model="ffnn").values
    assert accuracy[0] >= 0.9  # the informative taxel alone (tests/real_array_helpers)
    # The address-event word grows with the taxels read: 1 bit, then 2, then 3.
    bits = cube["data_rate_bps"].values / cube["event_rate_hz"].values
    assert bits.round(12).tolist() == [1.0, 2.0, 3.0]
    report = (root / "report" / "report.md").read_text()
    assert "How many of the real array's taxels" in report
    assert "1 real taxel (columns of the recorded array)" in report


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            '"array.taxels" = [1, 2, 4]',
            '"array.taxels" = [5]',
            "sweeps.taxels[0]: 5 taxels asked by array.taxels of dataset "
            f"'one informative taxel', whose recordings hold {N_TAXELS} taxels",
        ),
        (
            '"array.rows" = 1',
            '"array.rows" = 3',
            "sweeps.taxels[0], sweeps.taxels[1], sweeps.taxels[2]: a 3x1 grid of time-shifted "
            "copies asked of dataset 'one informative taxel'",
        ),
    ],
)
def test_a_design_that_does_not_fit_the_array_is_refused_and_nothing_written(
    folder, tmp_path, old, new, message
):
    grid = tmp_path / "grid.toml"
    grid.write_text(GRID.replace(old, new))
    root = tmp_path / "run"
    args = ("--grid", str(grid), "--dataset", str(folder), "--root", str(root))
    proc = eskin("sweep", *args, env=hermetic_env(tmp_path))
    assert proc.returncode == 2
    assert message in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    assert not root.exists()
