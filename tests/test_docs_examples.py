"""The documentation's examples are code: its TOML files load and its Python session runs."""

import doctest
import json
import re
import shlex
import subprocess
import tomllib
from pathlib import Path

import pytest

from pipeline.design.grid import Grid
from pipeline.design.scene import Scene
from pipeline.design.space import Space, load_space
from pipeline.results.hardware_constants import DECLARED, Constants, read_constants

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PAGES = sorted(p for p in DOCS.rglob("*.md") if not {"_build", "jupyter_execute"} & set(p.parts))


def blocks(page: Path, language: str) -> list[str]:
    """The fenced code blocks of one language on a page, in order."""
    return re.findall(rf"```{language}\n(.*?)```", page.read_text(), flags=re.S)


def block_with(page: str, marker: str) -> str:
    """The one TOML block of a page that contains ``marker``."""
    [block] = [b for b in blocks(DOCS / page, "toml") if marker in b]
    return block


def load_toml_example(text: str) -> Scene | Grid | Space | Constants:
    """A TOML example as what it shows: a constants file, a design space, a grid or a scene."""
    table = tomllib.loads(text)
    if table and set(table) <= set(DECLARED):
        problems: list[str] = []
        constants = read_constants(table, "a documented constants file", problems)
        if problems:
            raise ValueError("; ".join(problems))
        return constants
    if "objectives" in table:
        return Space.from_dict(table)
    if "sweeps" in table:
        return Grid.from_dict(table)
    return Scene.from_dict(table)


def test_the_scene_example_is_the_paper_scene():
    scene = Scene.from_dict(tomllib.loads(block_with("scenes.md", "[training]")))
    assert scene.canonical() == Scene.paper().canonical()


def test_the_grid_example_loads():
    grid = Grid.from_dict(tomllib.loads(block_with("how-to/grid.md", "[sweeps.")))
    assert [s.name for s in grid.sweeps] == ["threshold", "mismatch_by_size", "noise"]
    assert grid.sweeps[1].shape == (3, 2)


def test_the_space_example_is_the_example_space_file():
    shown = Space.from_dict(tomllib.loads(block_with("how-to/search.md", "[objectives]")))
    example = load_space(ROOT / "examples" / "design_space.toml")
    assert shown.fingerprint() == example.fingerprint()


@pytest.mark.parametrize(
    ("page", "index"),
    [
        (page.relative_to(DOCS).as_posix(), i)
        for page in PAGES
        for i in range(len(blocks(page, "toml")))
    ],
)
def test_every_toml_example_loads(page, index):
    load_toml_example(blocks(DOCS / page, "toml")[index])


@pytest.mark.slow
def test_the_python_api_session_runs_as_shown(tmp_path, monkeypatch):
    page = DOCS / "how-to" / "python.md"
    session = "".join(blocks(page, "pycon"))
    assert session.count(">>>") >= 10
    monkeypatch.chdir(tmp_path)  # the examples write runs/api relative to where they run
    test = doctest.DocTestParser().get_doctest(session, {}, "Python API", str(page), 0)
    runner = doctest.DocTestRunner(optionflags=doctest.NORMALIZE_WHITESPACE)
    report: list[str] = []
    runner.run(test, out=report.append)
    assert runner.summarize(verbose=False).failed == 0, "".join(report)
    assert (tmp_path / "runs" / "api" / "report" / "report.html").is_file()


def shell_commands(block: str) -> list[list[str]]:
    """A shell block's commands as argument lists: continued lines joined, comments and a
    trailing ``&`` left out."""
    text = re.sub(r"\\\n\s*", " ", block)
    lines = [line.split(" #")[0].strip() for line in text.splitlines()]
    return [shlex.split(line.removesuffix("&")) for line in lines if line and line[0] != "#"]


@pytest.mark.slow
def test_the_tls_section_makes_credentials_that_a_cluster_and_a_sweep_accept(tmp_path):
    """The cluster page's TLS commands, run as a reader runs them: the ``openssl`` block makes
    the CA, certificates and keys in an empty folder; the scheduler and a worker start with
    them on 127.0.0.1 (without their dashboards, on a free port); ``eskin sweep`` connects with
    the client's files and computes a one-point grid. Every process is stopped by PID."""
    from tests.flows.helpers import BIN, eskin, hermetic_env, stop, wait_for

    shown = blocks(DOCS / "how-to" / "cluster.md", "sh")
    [make] = [b for b in shown if "openssl" in b]
    [start] = [b for b in shown if "dask scheduler --protocol tls" in b]
    folder = tmp_path / "credentials"
    folder.mkdir()
    made = subprocess.run(
        ["bash", "-euo", "pipefail", "-c", make], cwd=folder, capture_output=True, text=True
    )
    assert made.returncode == 0, made.stderr[-2000:]
    for name in ("ca.pem", "cluster.pem", "cluster-key.pem", "client.pem", "client-key.pem"):
        assert (folder / name).is_file(), name
    assert (folder / "client-key.pem").stat().st_mode & 0o077 == 0

    scheduler_cmd, worker_cmd, sweep_cmd = shell_commands(start)
    assert [c[:2] for c in (scheduler_cmd, worker_cmd, sweep_cmd)] == [
        [".venv/bin/dask", "scheduler"],
        [".venv/bin/dask", "worker"],
        [".venv/bin/eskin", "sweep"],
    ]
    env = hermetic_env(tmp_path)

    def started(*command: str | Path) -> None:
        processes.append(
            subprocess.Popen(
                command, cwd=folder, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
            )
        )

    processes: list[subprocess.Popen] = []
    scheduler_file = tmp_path / "scheduler.json"
    scheduler_args = " ".join(scheduler_cmd[2:]).replace("HOST", "127.0.0.1")
    scheduler_args = scheduler_args.replace("--port 8786", "--port 0").split()
    try:
        scheduler_args += ["--no-dashboard", "--scheduler-file", str(scheduler_file)]
        started(BIN / "dask", "scheduler", *scheduler_args)
        wait_for(
            lambda: scheduler_file.exists() and "address" in scheduler_file.read_text(),
            120,
            "the scheduler file",
        )
        address = json.loads(scheduler_file.read_text())["address"]
        assert address.startswith("tls://127.0.0.1:")

        def at(args: list[str]) -> list[str]:
            return [address if a == "tls://HOST:8786" else a for a in args]

        worker_args = [*at(worker_cmd[2:]), "--no-dashboard", "--host", "127.0.0.1"]
        started(BIN / "dask", "worker", *worker_args)
        grid = tmp_path / "one.toml"
        grid.write_text(
            'base = "smoke"\n[sweeps.one]\nset = { "training.epochs" = 1 }\n'
            'axes = { "readout.threshold_v" = [0.09] }\n'
        )
        args = at(sweep_cmd[1:])  # "sweep" and its options
        args[args.index("paper")] = str(grid)
        files = [a for a in args if a.endswith(".pem")]
        args = [str(folder / a) if a in files else a for a in args]
        proc = eskin(*args, "--root", str(tmp_path / "run"), "--json", env=env, timeout=600)
    finally:
        stop(*reversed(processes))
    assert files == ["ca.pem", "client.pem", "client-key.pem"]
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert json.loads(proc.stdout)["computed"] == 1
