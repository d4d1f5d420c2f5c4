"""Shards of `rtta dataset` on a distributed engine: each shard is one task that runs
`rtta dataset ARGV --shard I/N` in a fresh process on a worker (a process of its own, so each
has its own EGL context, whatever threads the engine runs tasks on). Written for
dask.distributed (`Client(LocalCluster(...))` or `Client("tcp://scheduler:8786")`), it needs
only `client.submit` and `client.gather`; dask itself is not imported here."""

from __future__ import annotations

import subprocess
import sys


def run_shard(argv: list[str], index: int, shards: int) -> tuple[int, str]:
    """On a worker: one shard; (exit code, the end of its stderr)."""
    # -P: the worker's current folder stays off sys.path (a source checkout there would shadow the install)
    cmd = [sys.executable, "-P", "-m", "rtta", "dataset", *argv, "--shard", f"{index}/{shards}", "--no-progress"]
    done = subprocess.run(cmd, capture_output=True, text=True)
    return done.returncode, done.stderr[-2000:]


def run_shards(client, argv: list[str], shards: int) -> list[tuple[int, str]]:
    """Run shards 0..N-1 of `rtta dataset ARGV` as tasks of `client` and wait for them all;
    per shard (exit code, stderr tail). Every shard must see the same scenes and --out (a
    shared folder: each writes annotations-shard-I-of-N.json there), or merge the folders
    afterwards with `rtta dataset merge`."""
    futures = [client.submit(run_shard, list(argv), i, shards, pure=False) for i in range(shards)]
    return client.gather(futures)
