"""Build and run a pipeline from Python (docs/python.md).

Usage: python examples/pipeline_api.py [OUTDIR]
"""

import sys
from pathlib import Path

import numpy as np

import envconv
from envconv.engine.batch import expand_inputs, make_jobs, run_batch
from envconv.engine.pipeline import Exposure, Pipeline, Read, Resample, Rotate, Write

here = Path(__file__).resolve().parent
out = Path(sys.argv[1] if len(sys.argv) > 1 else "build/python")
source = here / "data" / "venice-latlong-512.exr"

# 1. One source, three outputs. Each resample starts from the source (rotated a quarter turn);
#    the exposure after the second resample darkens that output only.
pipeline = Pipeline(
    [
        Read(source),
        Rotate(yaw=90),
        Resample("cube-vcross", size=64),
        Write(out / "{stem}_{layout}.exr"),
        Resample("latlong", size=64),
        Exposure(-2),
        Write(out / "{stem}_preview.exr"),
        Resample("sphere", size=64, alpha=True),  # kept in memory, not written
    ]
)
for output in pipeline.plan():  # headers only: what would be written
    print("plan:", output.layout, output.size, f"{output.width}x{output.height}", output.files)
outputs = pipeline.run()
for output in outputs:
    print("ran: ", output.layout, output.size, output.files or "(in memory)")

# The cross equals a direct convert of the source with the same rotation, bit for bit.
direct = envconv.convert(envconv.read(source), "cube-vcross", size=64, rotate="90")
assert np.array_equal(outputs[0].envmap.pixels, direct.pixels)

# 2. The same steps as a recipe for many files: no path in the Read; each job binds one input.
recipe = Pipeline([Resample("cube-hcross", size=32), Write(out / "recipe" / "{stem}.exr")])
jobs = make_jobs(expand_inputs([str(here / "data")]), recipe)
result = run_batch(jobs, workers=1)
print("batch:", result.counts, f"{result.seconds:.2f} s")
assert result.ok
