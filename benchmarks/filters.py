"""The area filter's cost against the point kernel, in the same run, interleaved (issue 26).

    python benchmarks/bench.py filters [--rounds R] [--threads T]

Each case converts the same in-memory 2048 × 1024 lat-long (the park example upsampled) to
cube-vcross 512, the default one shot's resample, with ``envconv.convert``: the area filter
(the default: S = 1, each pixel integrated exactly), the area filter with ``samples=4`` (4 × 4
sub-pixels, each integrated exactly), and the bilinear point kernel at S = 1, S = 4 and
``auto`` (the default before the area filter). One more case converts a paraboloid made from
the same lat-long (bilinear, its default size, before the rounds) to the same cube: a source
whose area filter goes pixel by pixel through the density model rather than lat-long rows.
Rounds run every case once, in a rotating order, after one warm-up round; the table gives each
case's median and its ratio to the point kernel's S = 1 and auto medians of the same rounds,
so a machine that slows down during the run slows every case alike.
"""

from __future__ import annotations

import statistics
import time

import envconv

__all__ = ["CASES", "bench_filters", "ONESHOT_CASES", "bench_oneshot"]

#: (label, source layout, convert keyword arguments)
CASES = [
    ("area (default)", "latlong", {"filter": "area"}),
    ("area samples=4", "latlong", {"filter": "area", "samples": 4}),
    ("bilinear S=1", "latlong", {"filter": "bilinear", "samples": 1}),
    ("bilinear S=4", "latlong", {"filter": "bilinear", "samples": 4}),
    ("bilinear auto (old default)", "latlong", {"filter": "bilinear", "samples": "auto"}),
    ("area, paraboloid source", "paraboloid", {"filter": "area"}),
]


def bench_filters(source: envconv.EnvMap, rounds: int = 9, threads: int | None = None) -> None:
    """Print the median time of every case of CASES over ``rounds`` interleaved rounds."""
    sources = {
        "latlong": source,
        "paraboloid": envconv.convert(source, "paraboloid", filter="bilinear"),
    }
    times: dict[str, list[float]] = {label: [] for label, _, _ in CASES}
    for r in range(rounds + 1):
        order = CASES[r % len(CASES) :] + CASES[: r % len(CASES)]
        for label, layout, kwargs in order:
            start = time.perf_counter()
            envconv.convert(sources[layout], "cube-vcross", size=512, threads=threads, **kwargs)
            if r:  # round 0 warms up
                times[label].append(time.perf_counter() - start)
    medians = {label: statistics.median(t) for label, t in times.items()}
    s1, auto = medians["bilinear S=1"], medians["bilinear auto (old default)"]
    print(f"lat-long 2048x1024 (and a paraboloid of it) -> cube-vcross 512, {rounds} interleaved rounds, "
          f"threads={threads or 'all'}")  # fmt: skip
    for label, median in medians.items():
        print(f"  {label:28s} {median * 1e3:8.1f} ms   x{median / s1:5.2f} of bilinear S=1"
              f"   x{median / auto:5.2f} of the old default")  # fmt: skip


#: (label, extra ``envconv convert`` arguments) of the one-shot comparison.
ONESHOT_CASES = [
    ("default (area)", []),
    ("--filter area", ["--filter", "area"]),
    ("--filter bilinear (old default)", ["--filter", "bilinear"]),
]


def bench_oneshot(source: envconv.EnvMap, rounds: int = 24) -> None:
    """The whole one shot of issue 26: ``envconv convert`` of ``source`` written as a float zip
    EXR → cube-vcross 512 (zip), a fresh process each time, every case of ONESHOT_CASES once a
    round in a rotating order, the first round dropped. The two area labels run the same
    filter: the gap between their medians is the machine's noise. Besides the medians, each
    round's own ratio to the old default's run of that round: their median and quartiles."""
    import os
    import shutil
    import subprocess
    import sys
    import tempfile

    exe = shutil.which("envconv", path=os.path.dirname(sys.executable)) or "envconv"
    with tempfile.TemporaryDirectory() as folder:
        src = os.path.join(folder, "in.exr")
        envconv.write(source, src, bit_depth="float")
        times: dict[str, list[float]] = {label: [] for label, _ in ONESHOT_CASES}
        for r in range(rounds + 1):
            order = (
                ONESHOT_CASES[r % len(ONESHOT_CASES) :] + ONESHOT_CASES[: r % len(ONESHOT_CASES)]
            )
            for label, extra in order:
                out = os.path.join(folder, "out.exr")
                if os.path.exists(out):
                    os.remove(out)
                start = time.perf_counter()
                subprocess.run([exe, "convert", src, out, "--to", "cube-vcross", "--size", "512",
                                *extra], check=True, stdout=subprocess.DEVNULL)  # fmt: skip
                if r:
                    times[label].append(time.perf_counter() - start)
    medians = {label: statistics.median(t) for label, t in times.items()}
    base = times["--filter bilinear (old default)"]
    old = statistics.median(base)
    print(f"one shot: envconv convert lat-long 2048x1024 float EXR -> cube-vcross 512, "
          f"{rounds} interleaved rounds")  # fmt: skip
    for label, median in medians.items():
        # Each round's own ratio too: this project's machines drift in speed within minutes,
        # and a round's three runs follow each other within two seconds.
        ratios = sorted(t / b for t, b in zip(times[label], base, strict=True))
        q1, q3 = ratios[len(ratios) // 4], ratios[(3 * len(ratios)) // 4]
        print(
            f"  {label:32s} {median:7.3f} s   {100 * (median / old - 1):+6.1f} % over the old "
            f"default (rounds: median {100 * (statistics.median(ratios) - 1):+.1f} %, "
            f"quartiles {100 * (q1 - 1):+.1f} … {100 * (q3 - 1):+.1f} %)"
        )
