"""Security: nothing read from a dataset or a store is unpickled, servers listen on loopback,
and names and paths from scene and grid files cannot leave their root."""

import ast
import contextlib
import os
import socket
import ssl
import urllib.request
from pathlib import Path

import psutil
import pytest

from flows import server
from flows.cluster import dask_client
from flows.environment import hermetic_environment
from flows.planning import default_root
from pipeline.design.grid import Grid, load_grid
from pipeline.design.scene import Scene
from pipeline.errors import SceneError
from storage import SweepStore

REPO = Path(__file__).resolve().parents[2]
PACKAGES = ("pipeline", "storage", "flows", "benchmarks")
UNSAFE_MODULES = {"pickle", "cPickle", "marshal", "shelve", "dill", "cloudpickle", "joblib"}
# Calls that deserialize code or objects; np.load and read_array are fine with allow_pickle=False.
UNSAFE_CALLS = {"torch.load", "pd.read_pickle", "pandas.read_pickle", "yaml.load", "eval", "exec"}
NUMPY_LOADERS = {"np.load", "numpy.load", "np.lib.format.read_array", "read_array"}


def sources() -> list[Path]:
    files = [p for package in PACKAGES for p in (REPO / package).rglob("*.py")]
    assert len(files) > 20
    return files


def dotted(node: ast.AST) -> str:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return f"{dotted(node.value)}.{node.attr}"
    return ""


def unsafe_uses(tree: ast.AST) -> list[str]:
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import | ast.ImportFrom):
            names = [a.name for a in node.names] + [getattr(node, "module", None) or ""]
            found += [f"import {n}" for n in names if n.split(".")[0] in UNSAFE_MODULES]
        elif isinstance(node, ast.Call):
            name = dotted(node.func)
            keywords = {k.arg: k.value for k in node.keywords}
            if name in UNSAFE_CALLS:
                found.append(f"call {name}")
            pickle_kw = keywords.get("allow_pickle")
            if pickle_kw is not None and not (
                isinstance(pickle_kw, ast.Constant) and pickle_kw.value is False
            ):
                found.append(f"{name}(allow_pickle=...) not False")
            if name in NUMPY_LOADERS and pickle_kw is None:
                found.append(f"{name} without allow_pickle=False")
    return found


def test_the_scan_catches_what_it_looks_for():
    bad = ast.parse(
        "import pickle\nfrom dill import loads\nimport numpy as np\n"
        "np.load('x.npy')\nnp.load('y', allow_pickle=True)\ntorch.load('m')\n"
    )
    assert len(unsafe_uses(bad)) == 5
    assert unsafe_uses(ast.parse("np.load('x', allow_pickle=False)")) == []


def test_no_code_path_unpickles_data():
    found = {
        str(path.relative_to(REPO)): uses
        for path in sources()
        if (uses := unsafe_uses(ast.parse(path.read_text(), str(path))))
    }
    assert found == {}


def test_the_store_reads_only_zarr_v3_which_has_no_pickle_codec(tmp_path):
    import zarr

    from storage import batches, cube_files

    # Both readers of the store (entry batches and cubes) open Zarr v3 only.
    assert batches._OPEN_ZARR["zarr_format"] == 3
    assert cube_files._OPEN_ZARR["zarr_format"] == 3
    # A Zarr v2 store (whose object codecs may pickle) is not opened at all.
    zarr.open_group(str(tmp_path / "old" / "store.zarr"), mode="w", zarr_format=2)
    with pytest.raises(Exception, match="not a sweep store"):
        SweepStore.open(tmp_path / "old")


def listening(process: psutil.Process) -> list[str]:
    addresses = []
    for proc in [process, *process.children(recursive=True)]:
        try:
            for conn in proc.net_connections(kind="inet"):
                if conn.status == psutil.CONN_LISTEN:
                    addresses.append(conn.laddr.ip)
        except psutil.NoSuchProcess:
            continue
    return addresses


@pytest.mark.slow
def test_the_local_cluster_and_its_dashboard_listen_on_loopback_only(tmp_path, monkeypatch):
    monkeypatch.setenv("DASK_TEMPORARY_DIRECTORY", str(tmp_path))
    with dask_client(workers=1) as client:
        info = client.scheduler_info()
        assert info["address"].startswith("tls://127.0.0.1:")
        assert all(w.startswith("tls://127.0.0.1:") for w in info["workers"])
        assert client.dashboard_link.startswith("http://127.0.0.1:")
        # The dashboard serves its pages (it needs bokeh, which distributed does not require).
        with urllib.request.urlopen(client.dashboard_link, timeout=60) as response:
            assert response.status == 200 and b"bokeh" in response.read().lower()
        addresses = listening(psutil.Process())
    assert addresses and set(addresses) == {"127.0.0.1"}, addresses


@pytest.mark.slow
def test_a_running_sweeps_scheduler_refuses_clients_without_its_credentials(tmp_path, monkeypatch):
    """Another user who reaches the port cannot connect a client (and run code as the sweep's
    owner): not without TLS, not over plain TCP, not with credentials of their own."""
    from distributed import Client
    from distributed.security import Security

    monkeypatch.setenv("DASK_TEMPORARY_DIRECTORY", str(tmp_path))
    with dask_client(workers=1) as client:
        address = client.scheduler.address
        assert address.startswith("tls://127.0.0.1:")
        assert client.submit(lambda: __import__("torch").get_num_threads()).result() == 1
        # Refused by the scheduler: plain TCP; TLS with credentials of another CA; TLS that
        # trusts its certificate (which is no secret) but has no client certificate.
        for attempt, security in (
            (address.replace("tls://", "tcp://"), None),
            (address, Security.temporary()),
        ):
            with pytest.raises(OSError):
                Client(attempt, timeout=5, security=security).close()
        # Refused with an alert or a dropped connection; one let in would wait for a Dask
        # message (the read times out) or answer.
        with contextlib.suppress(ssl.SSLError):
            assert tls_without_certificate(address, client.security.tls_ca_file) == b""
        assert len(client.scheduler_info()["workers"]) == 1


def tls_without_certificate(address: str, ca_pem: str) -> bytes:
    """Open a TLS connection to ``address`` that trusts ``ca_pem`` and shows no certificate;
    return the first byte the server sends (none if it closes the connection)."""
    host, port = address.removeprefix("tls://").rsplit(":", 1)
    context = ssl.create_default_context(cadata=ca_pem)
    context.check_hostname = False
    with (
        socket.create_connection((host, int(port)), timeout=10) as raw,
        context.wrap_socket(raw) as tls,
    ):
        tls.sendall(b"\0" * 8)
        return tls.recv(1)


@pytest.mark.slow
def test_an_external_tls_scheduler_needs_matching_credentials(tmp_path):
    """The right files connect; another CA's are one line from ``eskin sweep --address``."""
    import dask
    from distributed import LocalCluster
    from distributed.security import Security

    from flows.cluster import probe_scheduler, tls_config
    from tests.flows.helpers import eskin, hermetic_env, write_credentials

    security = Security.temporary()
    with LocalCluster(
        n_workers=0,
        processes=False,
        host="127.0.0.1",
        protocol="tls",
        security=security,
        dashboard_address=None,
    ) as cluster:
        address = cluster.scheduler_address
        with dask.config.set(tls_config(address, write_credentials(tmp_path / "own", security))):
            probe_scheduler(address, timeout_s=30)
        wrong = write_credentials(tmp_path / "other", Security.temporary())
        proc = eskin(
            "sweep",
            "--grid",
            "smoke",
            "--root",
            str(tmp_path / "run"),
            "--address",
            address,
            *(part for option, path in wrong.items() for part in (option, path)),
            env=hermetic_env(tmp_path),
            timeout=300,
        )
    assert proc.returncode == 2 and proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith(
        f"eskin: error: the Dask scheduler at {address} and this client do not accept each "
        "other's TLS credentials ("
    )
    assert not (tmp_path / "run").exists()


@pytest.mark.slow
def test_prefect_servers_we_start_bind_to_loopback(tmp_path, monkeypatch):
    # hermetic_environment writes os.environ: give it a copy without the user's Prefect settings.
    environ = {k: v for k, v in os.environ.items() if not k.startswith("PREFECT_")}
    monkeypatch.setattr(os, "environ", environ)
    hermetic_environment(tmp_path)
    assert os.environ["PREFECT_SERVER_API_HOST"] == "127.0.0.1"
    from prefect.settings import get_current_settings

    runner = get_current_settings().runner.server  # eskin serve's own web server, if enabled
    assert not runner.enable and runner.host in ("localhost", "127.0.0.1")
    # The local Prefect server that sweeps start (the suite's, started here if no test has yet;
    # it serves later tests too): API and UI on loopback only.
    with server.prefect_server(show_progress=False) as url:
        assert url.startswith("http://127.0.0.1:")
        addresses = listening(psutil.Process(server.status().pid))
    assert addresses and set(addresses) == {"127.0.0.1"}, addresses


@pytest.mark.parametrize("name", ["..", "../x", "a/b", "a\\b", ".", "/etc", "x" * 65, ""])
def test_grid_and_sweep_names_cannot_leave_the_root(name):
    with pytest.raises(SceneError, match="not a valid"):
        Grid.from_dict({"name": name, "base": "smoke", "sweeps": {"a": {"axes": {"seed": [1]}}}})
    with pytest.raises(SceneError, match="not a valid sweep name"):
        Grid.from_dict({"base": "smoke", "sweeps": {name: {"axes": {"seed": [1]}}}})


def test_the_default_root_is_inside_runs():
    grid = load_grid("smoke")
    root = default_root(grid)
    assert root.parent == Path("runs") and root.name == "smoke"


@pytest.mark.parametrize("key", ["../" + "0" * 29, "0" * 31 + "/", "..", "/tmp/x"])
def test_store_names_cannot_leave_the_store(tmp_path, key):
    store = SweepStore.open_or_create(tmp_path / "run")
    with pytest.raises(ValueError, match="invalid"):
        store.has("spikes", key)
    with pytest.raises(ValueError, match="invalid cube name"):
        store.read_cube(key)


def test_relative_dataset_paths_are_taken_from_the_scene_files_folder(tmp_path, monkeypatch):
    folder = tmp_path / "project"
    folder.mkdir()
    (folder / "scene.toml").write_text('[dataset]\nkind = "folder"\npath = "data"\n')
    (folder / "grid.toml").write_text(
        'base = { dataset = { kind = "folder", path = "../elsewhere" } }\n'
        "[sweeps.a]\naxes = { seed = [1] }\n"
    )
    monkeypatch.chdir(tmp_path)  # not the files' folder
    assert Scene.from_toml("project/scene.toml").dataset.path == str(folder / "data")
    grid = load_grid("project/grid.toml")
    assert grid.base.dataset.path == str(folder / "../elsewhere")
    absolute = Scene.from_dict({"dataset": {"kind": "folder", "path": "/data/x"}})
    assert absolute.dataset.path == "/data/x"
