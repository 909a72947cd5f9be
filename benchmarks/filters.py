"""The area filter's cost against the point kernel, in the same run, interleaved (issue 26).

    python benchmarks/bench.py filters [--rounds R] [--threads T]

Each case converts the same in-memory 2048 × 1024 lat-long (the park example upsampled) to
cube-vcross 512, the default one shot's resample, with ``envconv.convert``: the area filter
(the default: S = 1, each pixel integrated exactly), the area filter with ``samples=4`` (4 × 4
sub-pixels, each integrated exactly), and the bilinear point kernel at S = 1, S = 4 and
``auto`` (the default before the area filter). Rounds run every case once, in a rotating order,
after one warm-up round; the table gives each case's median and its ratio to the point
kernel's S = 1 and auto medians of the same rounds, so a machine that slows down during the
run slows every case alike.
"""

from __future__ import annotations

import statistics
import time

import envconv

__all__ = ["CASES", "bench_filters"]

#: (label, convert keyword arguments)
CASES = [
    ("area (default)", {"filter": "area"}),
    ("area samples=4", {"filter": "area", "samples": 4}),
    ("bilinear S=1", {"filter": "bilinear", "samples": 1}),
    ("bilinear S=4", {"filter": "bilinear", "samples": 4}),
    ("bilinear auto (old default)", {"filter": "bilinear", "samples": "auto"}),
]


def bench_filters(source: envconv.EnvMap, rounds: int = 9, threads: int | None = None) -> None:
    """Print the median time of every case of CASES over ``rounds`` interleaved rounds."""
    times: dict[str, list[float]] = {label: [] for label, _ in CASES}
    for r in range(rounds + 1):
        order = CASES[r % len(CASES) :] + CASES[: r % len(CASES)]
        for label, kwargs in order:
            start = time.perf_counter()
            envconv.convert(source, "cube-vcross", size=512, threads=threads, **kwargs)
            if r:  # round 0 warms up
                times[label].append(time.perf_counter() - start)
    medians = {label: statistics.median(t) for label, t in times.items()}
    s1, auto = medians["bilinear S=1"], medians["bilinear auto (old default)"]
    print(f"lat-long 2048x1024 -> cube-vcross 512, {rounds} interleaved rounds, "
          f"threads={threads or 'all'}")  # fmt: skip
    for label, median in medians.items():
        print(f"  {label:28s} {median * 1e3:8.1f} ms   x{median / s1:5.2f} of bilinear S=1"
              f"   x{median / auto:5.2f} of the old default")  # fmt: skip
