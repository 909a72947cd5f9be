"""Batch conversion from Python, as a saved script (docs/python.md): every lat-long of
examples/data to a 64-pixel cube cross, on two worker processes, with a report.

Usage: python examples/batch_api.py [OUT_DIR]
"""

import sys
from pathlib import Path

from envconv.engine.batch import expand_inputs, make_jobs, run_batch, write_report
from envconv.engine.pipeline import Pipeline, Resample, Write


def show(record: dict) -> None:
    print(record["status"], record["input"], record["outputs"])


def main(out: str) -> None:
    data = Path(__file__).resolve().parent / "data"
    recipe = Pipeline([Resample("cube-vcross", size=64), Write(f"{out}/{{stem}}_cross.exr")])
    jobs = make_jobs(expand_inputs([str(data / "*-latlong-512.exr")]), recipe)
    result = run_batch(jobs, workers=2, mode="update", on_record=show)
    print(result.counts)  # {'done': 4, 'skipped': 0, 'failed': 0}
    write_report(f"{out}/report.json", result)


# Each worker process starts by running this file again (multiprocessing's "spawn"), to find
# what the jobs refer to; the guard keeps the workers from starting the batch themselves.
if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "build/batch_api")
