"""Run a batch on a Dask cluster (docs/cluster.md).

A real cluster is started with ``dask scheduler`` and ``dask worker`` on the machines; here a
LocalCluster with two worker processes stands in for it, and envconv is pointed at its address.

Usage: python examples/cluster.py [OUTDIR]
"""

import os
import subprocess
import sys
from pathlib import Path

from dask.distributed import LocalCluster

here = Path(__file__).resolve().parent
out = Path(sys.argv[1] if len(sys.argv) > 1 else "build/cluster").resolve()
envconv = [sys.executable, "-c", "from envconv.cli import main; main()"]

if __name__ == "__main__":
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster:
        command = envconv + [
            "batch", str(here / "data"), "--out", str(out / "{stem}_{layout}.exr"),
            "--dask", cluster.scheduler_address, "--report", str(out / "report.json"),
            "resample", "--to", "cube-vcross", "--size", "64",
        ]  # fmt: skip
        print(" ".join(command))
        sys.exit(subprocess.call(command, env={**os.environ, "PYTHONUNBUFFERED": "1"}))
