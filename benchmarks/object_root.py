"""A warm re-run on an ``s3://`` root against the same re-run on a folder root.

Both roots hold the same grid (``smoke`` by default), computed by this suite in a temporary
folder: one a folder, the other a prefix of a bucket on a loopback S3 server (moto's standalone
server, on 127.0.0.1, as the tests use it: ``tests/object_store.py``). A warm re-run is
``eskin sweep --json`` on a root that holds every point already, as a user re-runs a finished
sweep to get its cubes and summary: it checks the root, takes its lock (a lease object on S3),
plans (lists the stored batches, finds every cube current), computes nothing and records the
flow run on the local Prefect server (started once by this suite, its state in the temporary
folder). The two run as subprocesses, interleaved (folder, s3, folder, ...) after one uncounted
round each; the row quotes their medians and their ratio.

What an object root costs beyond a folder is round trips: a loopback server answers in a few
milliseconds, a remote one in tens, so the ratio here is the floor of what a user sees.

``run(tiny=True)`` does the same on :data:`benchmarks.sweep.TINY_GRID` (filled on one worker),
one counted round and no uncounted one, on the local server ``$ESKIN_SERVER_DIR`` names if set
(the test suite's).
``python -m benchmarks.object_root [--grid smoke] [--repeat N]`` runs this suite alone and prints
its row.
"""

from __future__ import annotations

import argparse
import logging
import statistics
import tempfile
import uuid
from pathlib import Path

from benchmarks.sweep import local_server, local_sweep, tiny_grid

DEFAULT_GRID = "smoke"
WORKERS = 2
REPEAT = 5
TARGET_RATIO = 2.0
#: Any keys do for the loopback server.
S3_KEYS = {
    "AWS_ACCESS_KEY_ID": "bench",
    "AWS_SECRET_ACCESS_KEY": "bench",
    "AWS_REGION": "us-east-1",
}


def run(grid: str = DEFAULT_GRID, repeat: int = REPEAT, tiny: bool = False) -> list[dict]:
    """The row; ``tiny``: :data:`benchmarks.sweep.TINY_GRID` for ``grid``, one counted round and
    no uncounted one."""
    import boto3
    from moto.server import ThreadedMotoServer

    logging.getLogger("werkzeug").setLevel(logging.WARNING)  # its request log, on stderr
    server = ThreadedMotoServer(ip_address="127.0.0.1", port=0, verbose=False)
    server.start()
    try:
        host, port = server.get_host_and_port()
        endpoint = f"http://{host}:{port}"
        bucket = f"eskin-bench-{uuid.uuid4().hex[:12]}"
        client = boto3.client(
            "s3",
            endpoint_url=endpoint,
            aws_access_key_id=S3_KEYS["AWS_ACCESS_KEY_ID"],
            aws_secret_access_key=S3_KEYS["AWS_SECRET_ACCESS_KEY"],
            region_name=S3_KEYS["AWS_REGION"],
        )
        client.create_bucket(Bucket=bucket)
        with tempfile.TemporaryDirectory(prefix="eskin-bench-s3-") as name:
            tmp = Path(name)
            if tiny:
                grid, repeat = tiny_grid(tmp), 1
            s3 = {**S3_KEYS, "AWS_ENDPOINT_URL": endpoint, "AWS_ALLOW_HTTP": "true"}
            roots = {"folder": tmp / "folder", "s3": f"s3://{bucket}/{Path(grid).stem}"}
            with local_server(tmp, shared=tiny) as server_env:
                # An object root keeps the tool's own state in the user's cache: here, in tmp.
                env = server_env | s3 | {"XDG_CACHE_HOME": str(tmp / "cache")}
                for root in roots.values():
                    # Fills it (a tiny grid on one worker: a second would add only its start-up).
                    local_sweep(grid, root, 1 if tiny else WORKERS, env)
                    if not tiny:
                        local_sweep(grid, root, WORKERS, env)  # the uncounted warm round
                times: dict[str, list[float]] = {kind: [] for kind in roots}
                for _ in range(repeat):
                    for kind, root in roots.items():
                        warm = local_sweep(grid, root, WORKERS, env)
                        if warm.summary()["computed"]:
                            raise RuntimeError(f"a warm re-run of {root} computed points")
                        times[kind].append(warm.wall_s)
    finally:
        server.stop()
    folder_s, s3_s = (statistics.median(times[kind]) for kind in ("folder", "s3"))
    return [
        {
            "benchmark": f"{grid} grid warm re-run, s3 root / folder root",
            "ratio": s3_s / folder_s,
            "target": f"<= {TARGET_RATIO}",
            "detail": f"medians of {repeat}, interleaved: s3 {s3_s:.2f} s (loopback moto "
            f"server) vs folder {folder_s:.2f} s (eskin sweep --json, local server up, "
            "nothing computed)",
        }
    ]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.object_root",
        description="Benchmark a warm re-run on an s3:// root against one on a folder root.",
    )
    parser.add_argument("--grid", default=DEFAULT_GRID, help="a built-in grid or a grid TOML file")
    parser.add_argument("--repeat", type=int, default=REPEAT, help="counted runs of each")
    args = parser.parse_args(argv)
    for r in run(args.grid, args.repeat):
        print(f"{r['benchmark']}  {r['ratio']:.2f}  {r['target']}; {r['detail']}")


if __name__ == "__main__":
    main()
