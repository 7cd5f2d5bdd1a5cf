"""A catalogue of bad input: scenes, grids, datasets, arguments and roots.

Every case runs ``eskin sweep`` (in process, and a few as a real subprocess) and must give a
non-zero exit, exactly one line on stderr naming the culprit (a file, a field, an argument),
nothing on stdout, and nothing written under the root (a root that did not exist is not
created). The object roots (``s3://``) that cannot be used are refused likewise against a
loopback S3 server, their bucket left empty. The ``eskin describe`` cases hold it to the same:
nothing written anywhere, an export folder that did not exist is not created.
"""

import os
import socket
import stat
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import zarr

import storage.layout as store_layout
from flows.cli import main
from tests.flows.helpers import eskin, hermetic_env
from tests.object_store import bucket, s3_env, s3_server  # noqa: F401  (fixtures)

# -- building blocks ----------------------------------------------------------------------------

SCENE = """\
name = "bad"
[dataset]
{dataset}
[array]
rows = 2
cols = 2
[readout]
threshold_v = 0.09
{readout}
[coding]
window_s = 0.1
{coding}
[training]
epochs = 2
folds = 2
{training}
"""
SYNTHETIC = 'kind = "synthetic"\nrecordings_per_class = 2\nduration_s = 1.0'


def write(path: Path, content: str | bytes) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)
    return path


def scene_file(tmp: Path, *, dataset=SYNTHETIC, readout="", coding="", training="") -> Path:
    text = SCENE.format(dataset=dataset, readout=readout, coding=coding, training=training)
    return write(tmp / "scene.toml", text)


#: Five axes of 100 values each.
HUGE_AXES = "".join(
    f'"{field}" = {[round(0.001 * (i + 1), 3) for i in range(100)]}\n'
    for field in (
        "readout.threshold_v",
        "coding.window_s",
        "readout.effects.threshold_mismatch.sigma_rel",
        "readout.effects.amplifier_noise.sigma_v",
        "readout.effects.comparator_noise.sigma_v",
    )
)


def grid_file(tmp: Path, base: str, sweeps: str | None = None, head: str = "") -> Path:
    sweeps = sweeps or '[sweeps.t]\naxes = { "readout.threshold_v" = [0.05, 0.09] }\n'
    return write(tmp / "grid.toml", f'{head}base = "{base}"\n{sweeps}')


def dataset(tmp: Path, *, toml="sampling_rate_hz = 200.0\n", files=None) -> Path:
    """A folder dataset of two classes x two good recordings, plus ``files`` (name -> content)."""
    root = tmp / "data"
    rng = np.random.default_rng(0)
    if toml is not None:
        write(root / "dataset.toml", toml)
    for label in ("rough", "smooth"):
        for i in range(2):
            values = rng.normal(size=300)
            write(root / label / f"r{i}.csv", "\n".join(f"{v:.6f}" for v in values) + "\n")
    for name, content in (files or {}).items():
        if isinstance(content, np.ndarray):
            (root / name).parent.mkdir(parents=True, exist_ok=True)
            np.save(root / name, content)
        else:
            write(root / name, content)
    return root


ARRAY_TOML = 'name = "array"\ntime_column = "ms"\ntime_unit = "ms"\n'


def array_csv(rows: int = 150, *, header: str = "ms,a,b", cell: str | None = None) -> str:
    """A recording of two taxels ``a``, ``b`` 28 ms apart; ``cell`` replaces row 5's ``b``."""
    rng = np.random.default_rng(rows)
    lines = [header]
    for i, (a, b) in enumerate(rng.normal(size=(rows, 2))):
        lines.append(f"{28 * i},{a:.6f},{cell if cell is not None and i == 5 else f'{b:.6f}'}")
    return "\n".join(lines) + "\n"


def array_folder(tmp: Path, *, toml: str = ARRAY_TOML, bad: dict[str, str]) -> Path:
    """A folder of two classes x two recordings of two taxels, plus (or replaced by) ``bad``."""
    files = {f"{label}/r{i}.csv": array_csv() for label in ("rough", "smooth") for i in range(2)}
    root = tmp / "array"
    for name, content in {"dataset.toml": toml, **files, **bad}.items():
        write(root / name, content)
    return root


def array_grid(tmp: Path, **kwargs) -> list[str]:
    root = array_folder(tmp, **kwargs)
    scene = scene_file(tmp, dataset=f'kind = "folder"\npath = "{root}"')
    return ["--grid", str(grid_file(tmp, scene.name))]


def dataset_grid(tmp: Path, **kwargs) -> list[str]:
    data = dataset(tmp, **kwargs)
    scene = scene_file(tmp, dataset=f'kind = "folder"\npath = "{data}"')
    return ["--grid", str(grid_file(tmp, scene.name))]


def short_class_dataset(tmp: Path) -> Path:
    """At 1 kHz: class ``a`` holds ten 50-sample recordings (shorter than the 0.1 s taxel delays
    of the paper's 3x3 array), classes ``b`` and ``c`` ten of 2000 samples; .csv and .npy."""
    root = write(tmp / "short" / "dataset.toml", "sampling_rate_hz = 1000.0\n").parent
    rng = np.random.default_rng(1)
    for label, n in (("a", 50), ("b", 2000), ("c", 2000)):
        for i in range(10):
            values = rng.normal(size=n)
            if i % 2:
                np.save(root / label / f"r{i}.npy", values)
            else:
                write(root / label / f"r{i}.csv", "\n".join(f"{v:.6f}" for v in values) + "\n")
    return root


def short_class_grid(tmp: Path) -> list[str]:
    data = short_class_dataset(tmp)
    sweeps = (
        f'[sweeps.t]\nset = {{ "dataset.kind" = "folder", "dataset.path" = "{data}" }}\n'
        'axes = { "readout.threshold_v" = [0.05, 0.09] }\n'
    )
    return ["--grid", str(grid_file(tmp, "paper", sweeps))]


def scene_grid(tmp: Path, **kwargs) -> list[str]:
    scene = scene_file(tmp, **kwargs)
    return ["--grid", str(grid_file(tmp, scene.name))]


def sweeps_grid(tmp: Path, sweeps: str, head: str = "") -> list[str]:
    return ["--grid", str(grid_file(tmp, "smoke", sweeps, head))]


CSV_LINES = "\n".join(["0.1", "0.2", "0.3"] * 50) + "\n"

# Each case: (id, build(tmp) -> argv after "sweep", expected text naming the culprit).
Case = tuple[str, Callable[[Path], list[str]], str]
CASES: list[Case] = [
    # scenes (as the base of a grid)
    ("scene-unknown-key", lambda t: scene_grid(t, readout="treshold = 1"), "readout.treshold"),
    (
        "scene-negative-full-scale",
        lambda t: scene_grid(t, readout="full_scale_v = -1.0"),
        "readout.full_scale_v",
    ),
    (
        "scene-threshold-above-full-scale",
        lambda t: scene_grid(t, readout="full_scale_v = 0.05"),
        "readout.threshold_v",
    ),
    (
        "scene-unknown-effect",
        lambda t: scene_grid(t, readout="effects.warp = {}"),
        "readout.effects.warp",
    ),
    (
        "scene-absurd-window-count",
        lambda t: scene_grid(t, coding="n_windows = 1e300"),
        "coding.n_windows",
    ),
    ("scene-no-models", lambda t: scene_grid(t, training="models = []"), "training.models"),
    (
        "scene-folder-without-path",
        lambda t: scene_grid(t, dataset='kind = "folder"'),
        "dataset.path",
    ),
    ("scene-missing-file", lambda t: ["--grid", str(grid_file(t, "nowhere.toml"))], "nowhere.toml"),
    (
        "scene-binary-junk",
        lambda t: (
            write(t / "junk.toml", b"\x00\xff\xfe junk"),
            ["--grid", str(grid_file(t, "junk.toml"))],
        )[1],
        "junk.toml",
    ),
    # grids
    (
        "grid-unknown-field",
        lambda t: sweeps_grid(t, '[sweeps.a]\naxes = { "array.rowz" = [1] }\n'),
        "array.rowz",
    ),
    (
        "grid-empty-axis",
        lambda t: sweeps_grid(t, '[sweeps.a]\naxes = { "coding.window_s" = [] }\n'),
        "sweeps.a.axes.coding.window_s",
    ),
    (
        "grid-duplicate-values",
        lambda t: sweeps_grid(t, '[sweeps.a]\naxes = { "array.rows" = [2, 2] }\n'),
        "duplicate",
    ),
    (
        "grid-zip-unequal",
        lambda t: sweeps_grid(
            t, '[sweeps.a]\nmode = "zip"\naxes = { "array.rows" = [1, 2], "array.cols" = [1] }\n'
        ),
        "sweeps.a.axes",
    ),
    (
        "grid-window-too-long",
        lambda t: sweeps_grid(t, '[sweeps.a]\naxes = { "coding.window_s" = [0.1, 60.0] }\n'),
        "sweeps.a[1]",
    ),
    (
        "grid-sweep-name-escapes",
        lambda t: sweeps_grid(t, '[sweeps."../evil"]\naxes = { "array.rows" = [1] }\n'),
        "sweeps.../evil",
    ),
    ("grid-name-escapes", lambda t: sweeps_grid(t, "", head='name = "../../etc"\n'), "name"),
    (
        "grid-not-toml",
        lambda t: ["--grid", str(write(t / "g.toml", "base = [unclosed\n"))],
        "g.toml",
    ),
    (
        "grid-binary-junk",
        lambda t: ["--grid", str(write(t / "g.toml", os.urandom(64) + b"\xff"))],
        "g.toml",
    ),
    ("grid-unknown-name", lambda t: ["--grid", "papper"], "papper"),
    (
        "grid-no-sweeps",
        lambda t: ["--grid", str(write(t / "g.toml", 'base = "smoke"\n'))],
        "sweeps",
    ),
    # folder datasets
    (
        "dataset-nan",
        lambda t: dataset_grid(t, files={"rough/bad.csv": "0.1\nnan\n0.3\n"}),
        "rough/bad.csv",
    ),
    (
        "dataset-inf-npy",
        lambda t: dataset_grid(t, files={"smooth/bad.npy": np.array([0.0, np.inf, 1.0])}),
        "smooth/bad.npy",
    ),
    (
        "dataset-empty-file",
        lambda t: dataset_grid(t, files={"rough/empty.csv": ""}),
        "rough/empty.csv",
    ),
    (
        "dataset-two-columns",
        lambda t: dataset_grid(t, files={"rough/wide.csv": "1,2\n3,4\n"}),
        "rough/wide.csv",
    ),
    (
        "dataset-binary-junk",
        lambda t: dataset_grid(t, files={"rough/junk.csv": b"\x89PNG\r\n\x1a\n\x00\x00"}),
        "rough/junk.csv",
    ),
    (
        "dataset-pickled-npy",
        lambda t: dataset_grid(t, files={"rough/obj.npy": np.array([{"a": 1}], dtype=object)}),
        "rough/obj.npy",
    ),
    (
        "dataset-absurd-magnitude",
        lambda t: dataset_grid(t, files={"rough/huge.csv": "1e300\n-1e300\n" * 100}),
        "rough/huge.csv",
    ),
    (
        "dataset-no-sampling-rate",
        lambda t: dataset_grid(t, toml='name = "x"\n'),
        "sampling_rate_hz",
    ),
    (
        "dataset-wrong-sampling-rate",
        lambda t: dataset_grid(t, toml="sampling_rate_hz = -200\n"),
        "sampling_rate_hz",
    ),
    (
        "dataset-text-sampling-rate",
        lambda t: dataset_grid(t, toml='sampling_rate_hz = "fast"\n'),
        "sampling_rate_hz",
    ),
    ("dataset-missing-toml", lambda t: dataset_grid(t, toml=None), "dataset.toml"),
    (
        "dataset-missing-folder",
        lambda t: scene_grid(t, dataset=f'kind = "folder"\npath = "{t / "gone"}"'),
        "gone",
    ),
    ("dataset-shorter-than-taxel-delays", short_class_grid, "a/r0.csv"),
    # real taxel arrays
    (
        "dataset-array-different-taxels",
        lambda t: array_grid(t, bad={"smooth/r1.csv": array_csv(header="ms,a,c")}),
        "smooth/r1.csv: its taxels differ from rough/r0.csv's (lacks b; adds c)",
    ),
    (
        "dataset-array-text-in-a-taxel",
        lambda t: array_grid(t, bad={"rough/r1.csv": array_csv(cell="high")}),
        "rough/r1.csv: line 7, column b: 'high' is not a number",
    ),
    (
        "dataset-array-nan-in-a-taxel",
        lambda t: array_grid(t, bad={"rough/r1.csv": array_csv(cell="nan")}),
        "rough/r1.csv: column b: non-finite value nan at sample 5 (line 7)",
    ),
    (
        "dataset-array-positions-count",
        lambda t: array_grid(t, toml=ARRAY_TOML + "taxel_positions_mm = [[0, 0]]\n", bad={}),
        "dataset.toml: taxel_positions_mm gives 1 positions for 2 taxels",
    ),
    (
        "dataset-array-time-not-increasing",
        lambda t: array_grid(t, bad={"smooth/r0.csv": "ms,a,b\n0,1,2\n28,1,2\n20,1,2\n"}),
        "smooth/r0.csv: time column ms does not increase at sample 2 (line 4)",
    ),
    # command-line arguments
    ("args-zero-workers", lambda t: ["--grid", "smoke", "--workers", "0"], "--workers"),
    ("args-text-workers", lambda t: ["--grid", "smoke", "--workers", "two"], "--workers"),
    (
        "args-malformed-address",
        lambda t: ["--grid", "smoke", "--address", "localhost"],
        "--address",
    ),
    (
        "args-workers-and-address",
        lambda t: ["--grid", "smoke", "--workers", "3", "--address", "tcp://127.0.0.1:1"],
        "--address",
    ),
    (
        # 100 ** 5 points: refused from the axis sizes, in milliseconds, none built.
        "grid-too-large-to-plan",
        lambda t: [
            "--grid",
            str(grid_file(t, "paper", "[sweeps.huge.axes]\n" + HUGE_AXES)),
            "--dry-run",
        ],
        "10,000,000,000 points (sweeps.huge has 10,000,000,000) are more than this machine can "
        "plan",
    ),
    ("args-no-grid", lambda t: [], "--grid"),
    ("args-unknown-option", lambda t: ["--grid", "smoke", "--frobnicate"], "--frobnicate"),
]
# The encoder's fields: (id, [readout] lines of the base scene, or an axis, the culprit).
CASES += [
    (name, lambda t, r=readout: scene_grid(t, readout=r), culprit)
    for name, readout, culprit in [
        ("scene-unknown-encoder", 'encoder = "sigma-delta"', "readout.encoder"),
        ("scene-decay-zero-tau", "decay.tau_s = 0.0", "readout.decay.tau_s"),
        (
            "scene-decay-floor-above-threshold",
            'encoder = "decaying"\ndecay.theta_min_v = 0.5',
            "readout.decay.theta_min_v",
        ),
    ]
]
# The spiking decoder's fields: (id, [training] lines of the base scene, the culprit).
_SNN = 'models = ["ffnn", "snn"]\n'
CASES += [
    (name, lambda t, r=training: scene_grid(t, training=r), culprit)
    for name, training, culprit in [
        ("scene-snn-step-longer-than-window", _SNN + "snn.step_s = 0.2", "training.snn.step_s"),
        ("scene-snn-step-not-dividing-window", _SNN + "snn.step_s = 0.03", "training.snn.step_s"),
        ("scene-snn-no-neurons", _SNN + "snn.hidden_neurons = 0", "training.snn.hidden_neurons"),
        ("scene-snn-zero-tau", _SNN + "snn.tau_mem_s = 0.0", "training.snn.tau_mem_s"),
        ("scene-snn-negative-tau", _SNN + "snn.tau_mem_s = -0.1", "training.snn.tau_mem_s"),
        ("scene-unknown-model", 'models = ["ffnn", "lsnn"]', "training.models"),
    ]
]
CASES.append(
    (
        "grid-snn-step-not-dividing-swept-window",
        lambda t: sweeps_grid(
            t,
            '[sweeps.a]\nset = { "training.models" = ["snn"] }\n'
            'axes = { "coding.window_s" = [0.1, 0.125] }\n',
        ),
        "training.snn.step_s",
    )
)
CASES.append(
    (
        "grid-unknown-encoder",
        lambda t: sweeps_grid(t, '[sweeps.a]\naxes = { "readout.encoder" = ["lcs", "n-lcs"] }\n'),
        "readout.encoder",
    )
)

# The chips of a design: (id, [chips] lines of the base scene, [readout] lines, the culprit).
CASES += [
    (
        name,
        lambda t, c=chips, r=readout: scene_grid(t, readout=r, training=f"[chips]\n{c}"),
        culprit,
    )
    for name, chips, readout, culprit in [
        ("scene-chip-count-zero", "count = 0", "", "chips.count"),
        ("scene-chip-count-fraction", "count = 2.5", "", "chips.count"),
        ("scene-chip-count-above-maximum", "count = 1001", "", "chips.count"),
        ("scene-shared-chips-all-alike", 'deployment = "shared"', "", "chips.deployment"),
        (
            "scene-robust-chips-only-noise",
            'deployment = "robust"\ncount = 4',
            "effects.amplifier_noise = {}",
            "chips.deployment",
        ),
        ("scene-yield-target-one", "yield_target = 1.0", "", "chips.yield_target"),
        ("scene-yield-target-zero", "yield_target = 0", "", "chips.yield_target"),
    ]
]
CASES.append(
    (
        "grid-chip-count-negative",
        lambda t: sweeps_grid(t, '[sweeps.a]\naxes = { "chips.count" = [1, -3] }\n'),
        "chips.count",
    )
)
# A sweep's set is checked with its axes at every point: shared chips need an effect drawn per
# chip, which no point of this sweep names (the culprit: the sweep, every point, the field).
CASES.append(
    (
        "grid-shared-chips-without-an-effect-at-any-point",
        lambda t: sweeps_grid(
            t,
            '[sweeps.a]\nset = { "chips.count" = 4, "chips.deployment" = "shared" }\n'
            'axes = { "readout.threshold_v" = [0.05, 0.09] }\n',
        ),
        "sweeps.a at every point: chips.deployment: 'shared' needs a readout effect",
    )
)


def tree(path: Path):
    """Everything at and below ``path`` (names, sizes, modes), or None if it does not exist."""
    if not path.exists() and not path.is_symlink():
        return None
    if path.is_file():
        return ("file", path.read_bytes())
    return sorted(
        (str(p.relative_to(path)), p.stat().st_size if p.is_file() else -1, p.stat().st_mode)
        for p in path.rglob("*")
    )


def run_cli(argv: list[str]) -> int:
    try:
        return main(argv)
    except SystemExit as exc:  # argparse exits on bad arguments
        return exc.code


def assert_refused(capsys, argv: list[str], root: Path, expected: str) -> str:
    before = tree(root)
    code = run_cli(["sweep", *argv, "--root", str(root)])
    out, err = capsys.readouterr()
    assert code not in (0, None), f"accepted: {argv}"
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("eskin: error: "), err
    assert expected in lines[0], lines[0]
    assert tree(root) == before, "something was written under the root"
    return lines[0]


def test_the_catalogue_is_large():
    assert len(CASES) + len(ROOT_CASES) + len(OBJECT_ROOT_CASES) >= 25
    assert len({case[0] for case in OBJECT_ROOT_CASES}) == len(OBJECT_ROOT_CASES)
    assert len({case[0] for case in CASES}) == len(CASES)
    assert len({case[0] for case in DESCRIBE_CASES}) == len(DESCRIBE_CASES)


@pytest.mark.parametrize(("build", "expected"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_input_is_refused(capsys, tmp_path, build, expected):
    argv = build(tmp_path / "inputs")
    assert_refused(capsys, argv, tmp_path / "root", expected)


# -- roots ---------------------------------------------------------------------------------------


def file_root(tmp: Path) -> Path:
    return write(tmp / "notes.txt", "mine")


def under_a_file(tmp: Path) -> Path:
    return write(tmp / "notes.txt", "mine") / "run"


def read_only(tmp: Path) -> Path:
    root = tmp / "ro"
    root.mkdir()
    root.chmod(stat.S_IRUSR | stat.S_IXUSR)
    return root


def foreign_zarr(tmp: Path) -> Path:
    zarr.open_group(str(tmp / "foreign" / "store.zarr"), mode="w", zarr_format=3)
    return tmp / "foreign"


def foreign_zarr_v2(tmp: Path) -> Path:
    zarr.open_group(str(tmp / "old" / "store.zarr"), mode="w", zarr_format=2)
    return tmp / "old"


def not_empty(tmp: Path) -> Path:
    return write(tmp / "thesis" / "chapter1.tex", "precious").parent


ROOT_CASES = [
    ("root-is-a-file", file_root, "is a file"),
    ("root-under-a-file", under_a_file, "cannot create run root"),
    ("root-read-only", read_only, "not writable"),
    ("root-foreign-zarr", foreign_zarr, "foreign store"),
    ("root-foreign-zarr-v2", foreign_zarr_v2, "not a sweep store"),
    ("root-not-empty", not_empty, "not empty"),
]


@pytest.mark.parametrize(
    ("make", "expected"), [c[1:] for c in ROOT_CASES], ids=[c[0] for c in ROOT_CASES]
)
def test_bad_roots_are_refused(capsys, tmp_path, monkeypatch, make, expected):
    root = make(tmp_path)
    if make is read_only and os.geteuid() == 0:
        # root ignores mode bits; make the store's write probe fail as it would for a user.
        def denied(*args, **kwargs):
            raise PermissionError(13, "Permission denied")

        monkeypatch.setattr(store_layout.tempfile, "mkstemp", denied)
    try:
        line = assert_refused(capsys, ["--grid", "smoke"], root, expected)
    finally:
        if make is read_only:
            root.chmod(stat.S_IRWXU)
    assert str(root) in line


# -- object roots ----------------------------------------------------------------------------------


def dead_endpoint() -> str:
    """``http://127.0.0.1:<port>`` where nothing listens (a port just given up)."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    return f"http://127.0.0.1:{port}"


def plain_http(url: str, monkeypatch) -> str:
    monkeypatch.delenv("AWS_ALLOW_HTTP")
    return f"{url}/run"


def no_credentials(url: str, monkeypatch) -> str:
    monkeypatch.delenv("AWS_ACCESS_KEY_ID")
    monkeypatch.delenv("AWS_SECRET_ACCESS_KEY")
    # Where a client without keys asks for an instance role's: nothing answers here either.
    monkeypatch.setenv("AWS_METADATA_ENDPOINT", dead_endpoint())
    return f"{url}/run"


def refused_credentials(url: str, monkeypatch) -> str:
    import moto.settings

    # The server now checks every request's signature: these keys are in no account of it.
    monkeypatch.setattr(moto.settings, "INITIAL_NO_AUTH_ACTION_COUNT", 0)
    return f"{url}/run"


def no_bucket(url: str, monkeypatch) -> str:
    return f"{url}-missing/run"


def endpoint_down(url: str, monkeypatch) -> str:
    monkeypatch.setenv("AWS_ENDPOINT_URL", dead_endpoint())
    return f"{url}/run"


OBJECT_ROOT_CASES = [
    ("s3-plain-http", plain_http, "is plain http, which needs AWS_ALLOW_HTTP=true: set it"),
    (
        "s3-no-credentials",
        no_credentials,
        "no credentials for the object store at http://127.0.0.1:{port}: AWS_ACCESS_KEY_ID and "
        "AWS_SECRET_ACCESS_KEY are not set",
    ),
    (
        "s3-refused-credentials",
        refused_credentials,
        "the object store at http://127.0.0.1:{port} refused the credentials "
        "(InvalidAccessKeyId): check AWS_ACCESS_KEY_ID and AWS_SECRET_ACCESS_KEY",
    ),
    ("s3-no-bucket", no_bucket, "at http://127.0.0.1:{port} has no bucket '{bucket}-missing'"),
    ("s3-endpoint-down", endpoint_down, "does not answer (error sending request): check AWS_END"),
]


def bucket_objects(url: str, server: str) -> list[str]:
    import boto3
    import moto.settings

    moto.settings.INITIAL_NO_AUTH_ACTION_COUNT = float("inf")  # the test's monkeypatch restores
    client = boto3.client("s3", endpoint_url=server, **boto3_keys(server))
    found = client.list_objects_v2(Bucket=url.removeprefix("s3://"))
    return [o["Key"] for o in found.get("Contents", [])]


def boto3_keys(server: str) -> dict[str, str]:
    env = s3_env(server)
    return {
        "aws_access_key_id": env["AWS_ACCESS_KEY_ID"],
        "aws_secret_access_key": env["AWS_SECRET_ACCESS_KEY"],
        "region_name": env["AWS_REGION"],
    }


@pytest.mark.parametrize(
    ("make", "expected"),
    [c[1:] for c in OBJECT_ROOT_CASES],
    ids=[c[0] for c in OBJECT_ROOT_CASES],
)
def test_object_roots_that_cannot_be_used_are_refused_in_one_line(
    capsys,
    monkeypatch,
    bucket,  # noqa: F811
    s3_server,  # noqa: F811
    make,
    expected,
):
    root = make(bucket, monkeypatch)
    port = s3_server.rsplit(":", 1)[1]
    code = run_cli(["sweep", "--grid", "smoke", "--root", root])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"eskin: error: run root {root}: "), lines[0]
    assert expected.format(port=port, bucket=bucket.removeprefix("s3://")) in lines[0]
    assert bucket_objects(bucket, s3_server) == []


@pytest.mark.slow
def test_a_plain_http_endpoint_through_the_installed_command(tmp_path, bucket, s3_server):  # noqa: F811
    env = hermetic_env(tmp_path, **s3_env(s3_server))
    del env["AWS_ALLOW_HTTP"]
    proc = eskin("sweep", "--grid", "smoke", "--root", f"{bucket}/run", env=env, timeout=120)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.splitlines() == [
        f"eskin: error: run root {bucket}/run: the endpoint {s3_server} is plain http, which "
        "needs AWS_ALLOW_HTTP=true: set it, or give an https endpoint"
    ]
    assert bucket_objects(bucket, s3_server) == []


# -- the real exit path ----------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize(
    ("case_id"), ["dataset-nan", "args-text-workers", "grid-sweep-name-escapes"]
)
def test_bad_input_through_the_installed_command(tmp_path, case_id):
    build, expected = next(c[1:] for c in CASES if c[0] == case_id)
    argv = build(tmp_path / "inputs")
    root = tmp_path / "root"
    proc = eskin("sweep", *argv, "--root", str(root), env=hermetic_env(tmp_path), timeout=120)
    assert proc.returncode == 2 and proc.stdout == ""
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("eskin: error: ") and expected in lines[0]
    assert not root.exists()


# -- eskin run -------------------------------------------------------------------------------------

SHORT_CLASS_MESSAGE = ("a/r0.csv", "the delays of a 3x3 array", "0.1 s", "50 samples")


def test_run_refuses_a_recording_shorter_than_the_taxel_delays(capsys, tmp_path):
    data = short_class_dataset(tmp_path)
    before = tree(data)
    code = run_cli(["run", "--scene", "paper", "--dataset", str(data)])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("eskin: error: "), err
    for expected in SHORT_CLASS_MESSAGE:
        assert expected in lines[0], lines[0]
    assert tree(data) == before


def test_optimize_refuses_an_unknown_sampler(capsys, tmp_path):
    space = write(
        tmp_path / "space.toml",
        'base = "smoke"\nsampler = "bayes"\n[space]\n"array.rows" = { low = 1, high = 2 }\n'
        '[objectives]\n"accuracy.ffnn" = "max"\n"data_rate_bps" = "min"\n',
    )
    code = run_cli(["optimize", "--space", str(space), "--root", str(tmp_path / "root")])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("eskin: error: "), err
    for expected in ("space.toml", "sampler: 'bayes' is not one of", "'gp', 'auto'"):
        assert expected in lines[0], lines[0]
    assert not (tmp_path / "root").exists()


def test_optimize_refuses_a_journal_of_another_search_before_any_work(capsys, tmp_path):
    from storage import SweepStore
    from storage.search_log import SearchJournal

    text = (
        'name = "design"\nbase = "smoke"\n[space]\n"array.rows" = { low = 1, high = 2 }\n'
        '[objectives]\n"accuracy.ffnn" = "max"\n"data_rate_bps" = "min"\n'
    )
    space = write(tmp_path / "space.toml", text)
    root = SweepStore.open_or_create(tmp_path / "root").root
    SearchJournal.open(root, "design", "0123456789abcdef").asked(0, {"array.rows": 2})
    before = tree(root)
    code = run_cli(["optimize", "--space", str(space), "--root", str(root)])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.splitlines() == [
        f"eskin: error: {root}/search-design.jsonl holds a search of another space named "
        "'design' (its base, ranges, objectives, seed or sampler differ): give another --root "
        "or name"
    ]
    assert tree(root) == before


def test_sweep_refuses_a_recording_shorter_than_the_taxel_delays(capsys, tmp_path):
    line = assert_refused(capsys, short_class_grid(tmp_path), tmp_path / "root", "sweeps.t[0]")
    for expected in SHORT_CLASS_MESSAGE:
        assert expected in line, line
    assert not (tmp_path / "root").exists()


@pytest.mark.slow
@pytest.mark.parametrize("command", ["run", "sweep"])
def test_short_recordings_through_the_installed_command(tmp_path, command):
    root = tmp_path / "root"
    if command == "run":
        argv = ["run", "--scene", "paper", "--dataset", str(short_class_dataset(tmp_path))]
    else:
        argv = ["sweep", *short_class_grid(tmp_path), "--root", str(root)]
    proc = eskin(*argv, env=hermetic_env(tmp_path), timeout=300)
    assert proc.returncode == 2 and proc.stdout == ""
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("eskin: error: "), proc.stderr[-3000:]
    assert "a/r0.csv" in lines[0]
    assert not root.exists()


# -- eskin describe --------------------------------------------------------------------------------


def describe_dataset(tmp: Path, **kwargs) -> list[str]:
    return ["--dataset", str(dataset(tmp, **kwargs))]


def describe_export(tmp: Path, make: Callable[[Path], Path]) -> list[str]:
    return ["--dataset", str(dataset(tmp)), "--export", str(make(tmp))]


# Each case: (id, build(tmp) -> argv after "describe", expected text naming the culprit).
DESCRIBE_CASES: list[Case] = [
    ("describe-missing-path", lambda t: ["--dataset", str(t / "gone")], "gone"),
    ("describe-bare-vibtac12", lambda t: ["--dataset", "vibtac12"], "--dataset vibtac12"),
    (
        "describe-not-a-dataset",
        lambda t: ["--dataset", str(write(t / "plain" / "notes.txt", "x").parent)],
        "plain",
    ),
    (
        "describe-dataset-nan",
        lambda t: describe_dataset(t, files={"rough/bad.csv": "0.1\nnan\n0.3\n"}),
        "rough/bad.csv",
    ),
    (
        "describe-dataset-no-sampling-rate",
        lambda t: describe_dataset(t, toml='name = "x"\n'),
        "sampling_rate_hz",
    ),
    (
        "describe-array-different-taxels",
        lambda t: [
            "--dataset",
            str(array_folder(t, bad={"smooth/r1.csv": array_csv(header="ms,a,c")})),
        ],
        "smooth/r1.csv",
    ),
    (
        "describe-dataset-stray-file",
        lambda t: describe_dataset(t, files={"rough/notes.txt": "x"}),
        "rough/notes.txt",
    ),
    ("describe-export-not-empty", lambda t: describe_export(t, not_empty), "not empty"),
    ("describe-export-is-a-file", lambda t: describe_export(t, file_root), "not a directory"),
    (
        "describe-export-under-a-missing-folder",
        lambda t: describe_export(t, lambda u: u / "nowhere" / "out"),
        "nowhere",
    ),
    (
        "describe-export-inside-the-dataset",
        lambda t: describe_export(t, lambda u: u / "data" / "copy"),
        "inside the dataset folder",
    ),
    ("describe-unknown-option", lambda t: ["--frobnicate"], "--frobnicate"),
]


@pytest.mark.parametrize(
    ("build", "expected"), [c[1:] for c in DESCRIBE_CASES], ids=[c[0] for c in DESCRIBE_CASES]
)
def test_describe_refuses_bad_input(capsys, tmp_path, build, expected):
    argv = build(tmp_path)
    before = tree(tmp_path)
    assert_one_line_exit_2(capsys, ["describe", *argv], expected)
    assert tree(tmp_path) == before, "something was written"


def assert_one_line_exit_2(capsys, argv: list[str], expected: str) -> None:
    """``eskin argv`` exits 2 with one ``eskin: error:`` line holding ``expected``, no output."""
    code = run_cli(argv)
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("eskin: error: "), err
    assert expected in lines[0], lines[0]


def test_describe_refuses_an_unwritable_export_folder(capsys, tmp_path, monkeypatch):
    import flows.describe

    argv = describe_export(tmp_path, lambda t: read_only(t) / "out")
    if os.geteuid() == 0:  # root ignores mode bits; fail the write as it would for a user

        def denied(*args, **kwargs):
            raise PermissionError(13, "Permission denied")

        monkeypatch.setattr(flows.describe.tempfile, "mkdtemp", denied)
    before = tree(tmp_path)
    try:
        code = run_cli(["describe", *argv])
        after = tree(tmp_path)
    finally:
        (tmp_path / "ro").chmod(stat.S_IRWXU)
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    lines = err.splitlines()
    assert len(lines) == 1 and "cannot write folder" in lines[0] and "Permission denied" in lines[0]
    assert after == before


# -- eskin power -----------------------------------------------------------------------------------

POWER = ["--taxels", "9", "--event-rate-hz", "100"]
POWER_CASES: list[tuple[str, list[str], str]] = [
    ("power-no-taxels", ["--event-rate-hz", "100"], "--taxels"),
    ("power-zero-taxels", ["--taxels", "0", "--event-rate-hz", "1"], "argument --taxels: 0"),
    ("power-half-taxel", ["--taxels", "2.5", "--event-rate-hz", "1"], "whole number >= 1"),
    ("power-negative-rate", ["--taxels", "9", "--event-rate-hz", "-1"], "--event-rate-hz: -1"),
    ("power-nan-rate", ["--taxels", "9", "--event-rate-hz", "nan"], "--event-rate-hz: nan"),
    ("power-text-rate", ["--taxels", "9", "--event-rate-hz", "many"], "'many' is not a number"),
    ("power-bits-too-many", [*POWER, "--bits", "65"], "--bits: 65: need at most 64"),
    ("power-zero-sampling", [*POWER, "--sampling-rate-hz", "0"], "--sampling-rate-hz: 0"),
    ("power-inf-sampling", [*POWER, "--sampling-rate-hz", "inf"], "--sampling-rate-hz: inf"),
    ("power-negative-bias", [*POWER, "--front-end-nw", "-1"], "--front-end-nw: -1"),
    ("power-zero-adc-share", [*POWER, "--taxels-per-adc", "0"], "--taxels-per-adc: 0"),
    ("power-text-energy", [*POWER, "--event-energy-pj", "ten"], "--event-energy-pj: 'ten'"),
]


@pytest.mark.parametrize(
    ("argv", "expected"), [c[1:] for c in POWER_CASES], ids=[c[0] for c in POWER_CASES]
)
def test_power_refuses_bad_values_in_one_line(capsys, tmp_path, monkeypatch, argv, expected):
    monkeypatch.chdir(tmp_path)
    assert_one_line_exit_2(capsys, ["power", *argv], expected)
    assert list(tmp_path.iterdir()) == []


# -- hardware constants (eskin report and eskin power --constants FILE) -------------------------

A_VT = 'unit = "mV um", source = "foundry X"'
CONSTANTS_CASES: list[tuple[str, str, str]] = [
    ("constants-unknown-name", f"pelgrom = {{ value = 3, {A_VT} }}\n", "pelgrom: unknown constant"),
    (
        "constants-wrong-unit",
        'a_vt_v_m = { value = 3, unit = "V m", source = "x" }\n',
        "a_vt_v_m.unit: 'V m' is not its unit (give it in mV um)",
    ),
    (
        "constants-not-a-number",
        f'a_vt_v_m = {{ value = "three", {A_VT} }}\n',
        "a_vt_v_m.value 'three': need a number",
    ),
    (
        "constants-negative",
        'event_energy_j = { value = -1.0, unit = "pJ per event", source = "x" }\n',
        "event_energy_j.value -1: need a finite number >= 0",
    ),
    ("constants-zero-a-vt", f"a_vt_v_m = {{ value = 0, {A_VT} }}\n", "a_vt_v_m.value 0"),
    ("constants-no-source", 'a_vt_v_m = { value = 3, unit = "mV um" }\n', "a_vt_v_m: needs source"),
    ("constants-bare-number", "a_vt_v_m = 3\n", "a_vt_v_m: expected a table"),
    (
        "constants-band-upside-down",
        'ac_low_j = { value = 30.0, unit = "pJ per operation", source = "x" }\n',
        "ac_low_j: 30 pJ per operation is above ac_high_j",
    ),
    ("constants-not-toml", "a_vt_v_m = {\n", "not valid TOML"),
]


@pytest.mark.parametrize(
    ("text", "expected"), [c[1:] for c in CONSTANTS_CASES], ids=[c[0] for c in CONSTANTS_CASES]
)
@pytest.mark.parametrize("command", ["report", "power"])
def test_a_bad_constants_file_is_one_line_naming_file_and_key(
    capsys, tmp_path, monkeypatch, command, text, expected
):
    mine = write(tmp_path / "mine.toml", text)
    root = tmp_path / "root"
    root.mkdir()
    monkeypatch.chdir(tmp_path)
    argv = ["--root", str(root)] if command == "report" else POWER
    assert_one_line_exit_2(capsys, [command, *argv, "--constants", str(mine)], expected)
    out, err = capsys.readouterr()
    assert (out, err) == ("", "")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.toml", "root"]
    assert list(root.iterdir()) == []


def test_a_missing_constants_file_is_one_line_naming_it(capsys, tmp_path):
    gone = tmp_path / "gone.toml"
    assert_one_line_exit_2(
        capsys, ["power", *POWER, "--constants", str(gone)], f"invalid constants file {gone}"
    )
