"""A root keeps every search made in it: each search's ``trials`` and ``front`` cubes under its
own name, read back by ``open_results`` and ``open_tree``, both in the report; a root written
before searches were named is read as if they had been."""

import tomllib

import pytest
import xarray as xr

from flows.report import write_run_report
from pipeline.design.space import Space
from pipeline.report.trials import front_cube, trial_cube
from storage import SweepStore, open_results, open_tree
from storage.search_log import named_search_cubes, search_cube_name
from tests.flows.test_optimize import SPACE
from tests.report_helpers import make_cubes

THRESHOLDS = {"tiny": [0.03, 0.09, 0.2], "wide": [0.05, 0.1, 0.3, 0.4]}
WINDOWS_S = [0.05, 0.1, 0.15, 0.2]


def search_cubes(name: str) -> dict[str, xr.Dataset]:
    """The ``trials`` and ``front`` cubes a search of the test space named ``name`` writes, its
    trials at :data:`THRESHOLDS` and :data:`WINDOWS_S` (made up results, no training)."""
    space = Space.from_dict(tomllib.loads(SPACE.replace('name = "tiny"', f'name = "{name}"', 1)))
    thresholds = THRESHOLDS[name]
    axes = {"readout.threshold_v": thresholds, "coding.window_s": WINDOWS_S[: len(thresholds)]}
    sweep = {"trials": {"mode": "zip", "axes": axes}}
    (cube,) = make_cubes(sweep, models=("ffnn",)).values()
    cube.attrs["grid"] = space.name  # a search's trial grid is named after its space
    trials = trial_cube(cube, list(range(len(thresholds))), space.name)
    return {"trials": trials, "front": front_cube(trials, space.objectives)}


@pytest.fixture(scope="module")
def searches() -> dict[str, dict[str, xr.Dataset]]:
    return {name: search_cubes(name) for name in THRESHOLDS}


def test_two_searches_in_one_root_keep_their_cubes_and_are_both_in_the_report(searches, tmp_path):
    root = tmp_path / "run"
    store = SweepStore.open_or_create(root)
    for name, cubes in searches.items():
        for kind, cube in cubes.items():
            store.write_cube(search_cube_name(name, kind), cube)
    read = open_results(root)
    assert list(read) == ["tiny.front", "tiny.trials", "wide.front", "wide.trials"]
    for name, cubes in searches.items():
        for kind, cube in cubes.items():
            xr.testing.assert_identical(read[f"{name}.{kind}"], cube)
    tree = open_tree(root)
    assert list(tree.children) == list(read)
    xr.testing.assert_identical(tree["wide.trials"].to_dataset(), searches["wide"]["trials"])

    page = write_run_report(root, tmp_path / "report")
    markdown = (tmp_path / "report" / "report.md").read_text()
    assert "Grid(s) tiny, wide on synthetic data" in markdown
    for name in searches:
        for kind in ("trials", "front"):
            assert f"(sweep {name}.{kind})" in markdown
            assert (tmp_path / "report" / "figures" / f"sweep_{name}.{kind}.png").is_file()
    assert page.read_text().count("<svg") == len(
        list((tmp_path / "report" / "figures").glob("*.svg"))
    )
    searches_part = markdown.split("## Searches")[1].split("\n## ")[0]
    for name, cubes in searches.items():
        front = cubes["front"]
        on = int(front["on_front"].sum())
        told = f"{cubes['trials'].sizes['trial']} trials told; {on} on the front, "
        assert f"### Search {name}\n\n{told}{len(front['trial']) - on} beside it" in searches_part
        for trial in front["trial"].values:
            assert f"| {trial} | " in searches_part.split(f"### Search {name}")[1]


def test_a_root_written_before_searches_were_named_reads_as_if_they_had_been(searches, tmp_path):
    root = tmp_path / "run"
    store = SweepStore.open_or_create(root)
    store.write_cube("threshold", make_cubes()["threshold"])
    for kind, cube in searches["tiny"].items():
        store.write_cube(kind, cube)  # as searches wrote them: one search per root
    assert store.cube_names() == ["front", "threshold", "trials"]
    read = open_results(root)
    assert list(read) == ["threshold", "tiny.front", "tiny.trials"]
    xr.testing.assert_identical(read["tiny.trials"], searches["tiny"]["trials"])
    assert list(open_tree(root).children) == list(read)

    # A search of the same space run since writes its cubes under its name: the old ones are
    # no longer read; another search's are kept beside them.
    for kind, cube in searches["wide"].items():
        store.write_cube(search_cube_name("wide", kind), cube)
    newer = searches["tiny"]["trials"].isel(trial=[0])
    store.write_cube(search_cube_name("tiny", "trials"), newer)
    read = open_results(root, lazy=True)
    assert list(read) == ["threshold", "tiny.front", "tiny.trials", "wide.front", "wide.trials"]
    xr.testing.assert_identical(read["tiny.trials"].compute(), newer)


def test_only_a_searchs_cubes_are_renamed():
    plain = xr.Dataset(attrs={"space": "x"})
    assert list(named_search_cubes({"trials": plain.assign_attrs(space="a.b")})) == ["trials"]
    assert list(named_search_cubes({"grid": plain, "front": xr.Dataset()})) == ["front", "grid"]
    assert list(named_search_cubes({"trials": plain})) == ["x.trials"]
    with pytest.raises(ValueError, match="unknown cube of a search"):
        search_cube_name("x", "grid")
