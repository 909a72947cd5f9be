"""One-off accuracy comparison of two envconv builds (e.g. numba kernels against C++ kernels).

Each build writes an .npz of its outputs for every layout pair (every layout of
``envconv.layouts.LAYOUTS`` as source × every one as target; multi-file layouts are in-memory
mosaics) under every option set of ``OPTION_SETS``; then ``compare`` reads two such files::

    /work/venv-baseline/bin/python benchmarks/compare_builds.py dump /tmp/numba.npz
    .venv/bin/python benchmarks/compare_builds.py dump /tmp/cpp.npz --sources /tmp/numba.npz
    python benchmarks/compare_builds.py compare /tmp/cpp.npz /tmp/numba.npz

Run it as a script with the build's own python: it imports whatever envconv that interpreter
has installed (the first line printed and the file's ``meta`` say which). The sources are a
small real map (``--input``, default the venice example, whose range is -0.36 … 8.6; the park
map's sun and negative lobes reach ±10⁴, where float32 rounding alone exceeds 1e-5 relative),
resized to a lat-long of N = ``--source-size`` and then converted into each source layout by
the same build. ``--sources OTHER.npz`` takes the sources from another dump instead, so that two
builds resample the very same pixels (``compare`` also compares the sources of the two files).

``compare A B`` reports, per case, the largest relative difference |a - b| / max(|b|, floor)
(``--floor``, default 0.01: below it values are dark noise, and the venice map's 1st percentile
is 0.017) over every pixel, channel and mip level, and the largest absolute difference; then the
worst case per option set and overall, and whether every case agrees within ``--tolerance``
(default 1e-5). A case that fails in one build and not the other, or whose shapes differ, counts
as a disagreement. Exit status 0 when all agree, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

__all__ = ["OPTION_SETS", "dump", "compare", "main"]

#: Keyword arguments of ``envconv.convert`` per option set (on top of ``size``).
OPTION_SETS = {
    "bilinear": {"filter": "bilinear"},  # with samples="auto": the defaults
    "nearest": {"filter": "nearest"},
    "bicubic": {"filter": "bicubic"},
    "samples1": {"samples": 1},
    "samples3": {"samples": 3},
    "alpha": {"alpha": True},
    "guard2": {"guard": 2},
    "guard-fill": {"guard": "fill"},
    "mips": {"mips": True},
    "rotate": {"rotate": (30.0, -20.0, 10.0)},
}

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_INPUT = os.path.join(os.path.dirname(HERE), "examples", "data", "venice-latlong-512.exr")


def _sources(envconv, input_path: str, size: int, sources: str | None) -> dict:
    """EnvMaps by layout name: the input resized and converted by this build, or from a dump."""
    if sources:  # layouts the other build has (a newer build may have more)
        with np.load(sources) as data:
            return {name: envconv.EnvMap(data[f"src/{name}"], name)
                    for name in envconv.layouts.LAYOUTS if f"src/{name}" in data.files}  # fmt: skip
    latlong = envconv.convert(envconv.read(input_path), "latlong", size=size)
    return {name: envconv.convert(latlong, name, size=size) for name in envconv.layouts.LAYOUTS}


def dump(path: str, input_path: str, source_size: int, size: int, sources: str | None) -> None:
    """Write every case's output of the envconv this interpreter imports to ``path`` (.npz)."""
    import envconv

    print(f"envconv {envconv.__version__} from {os.path.dirname(envconv.__file__)}", flush=True)
    start = time.perf_counter()
    maps = _sources(envconv, input_path, source_size, sources)
    arrays = {f"src/{name}": m.pixels for name, m in maps.items()}
    errors = {}
    for source_name, source in maps.items():
        for target in maps:
            for option_name, options in OPTION_SETS.items():
                case = f"{source_name}>{target}/{option_name}"
                try:
                    out = envconv.convert(source, target, size=size, **options)
                except envconv.EnvconvError as exc:
                    errors[case] = f"{type(exc).__name__}: {exc}"
                    continue
                for k, level in enumerate(out.levels or [out.pixels]):
                    arrays[f"{case}/{k}"] = level
    meta = {"envconv": os.path.dirname(envconv.__file__), "version": envconv.__version__,
            "input": os.path.abspath(input_path), "source_size": source_size, "size": size,
            "sources": sources, "errors": errors}  # fmt: skip
    np.savez_compressed(path, meta=np.array(json.dumps(meta)), **arrays)
    cases = len(maps) * len(maps) * len(OPTION_SETS)
    print(
        f"{cases} cases ({len(errors)} refused by the library) in {time.perf_counter() - start:.1f} s -> {path}"
    )


def _relative(a: np.ndarray, b: np.ndarray, floor: float) -> tuple[float, float]:
    """Largest |a - b| / max(|b|, floor) and largest |a - b|; NaN equals NaN, else is infinite."""
    if a.shape != b.shape:
        return float("inf"), float("inf")
    a, b = a.astype(np.float64), b.astype(np.float64)
    same = (a == b) | (np.isnan(a) & np.isnan(b))
    diff = np.where(same, 0.0, np.abs(a - b))
    diff = np.where(np.isnan(diff), np.inf, diff)
    if diff.size == 0:
        return 0.0, 0.0
    return float(np.max(diff / np.maximum(np.abs(b), floor))), float(np.max(diff))


def _cases(data) -> dict[str, list[str]]:
    """Array keys grouped by case (``src/...`` and ``case/level``)."""
    cases: dict[str, list[str]] = {}
    for key in data.files:
        if key != "meta":
            cases.setdefault(
                key.rsplit("/", 1)[0] if not key.startswith("src/") else key, []
            ).append(key)
    return cases


def compare(path_a: str, path_b: str, floor: float, tolerance: float, show_all: bool) -> bool:
    """Print the differences of dump ``path_a`` from dump ``path_b``; True when all agree."""
    with np.load(path_a) as a, np.load(path_b) as b:
        meta_a, meta_b = json.loads(str(a["meta"])), json.loads(str(b["meta"]))
        print(
            f"A: {path_a} (envconv at {meta_a['envconv']})\nB: {path_b} (envconv at {meta_b['envconv']})"
        )
        cases_a, cases_b = _cases(a), _cases(b)
        results = {}
        for case in sorted(
            set(cases_a) | set(cases_b) | set(meta_a["errors"]) | set(meta_b["errors"])
        ):
            err_a, err_b = meta_a["errors"].get(case), meta_b["errors"].get(case)
            if err_a or err_b:
                same = bool(err_a) == bool(err_b)
                results[case] = (
                    0.0 if same else float("inf"),
                    0.0 if same else float("inf"),
                    f"A: {err_a} | B: {err_b}",
                )
                continue
            keys_a, keys_b = sorted(cases_a.get(case, [])), sorted(cases_b.get(case, []))
            if keys_a != keys_b:
                results[case] = (
                    float("inf"),
                    float("inf"),
                    f"levels differ: {len(keys_a)} vs {len(keys_b)}",
                )
                continue
            worst = [_relative(a[k], b[k], floor) for k in keys_a]
            shapes = [f"{a[k].shape} vs {b[k].shape}" for k in keys_a if a[k].shape != b[k].shape]
            note = f"shapes differ: {shapes[0]}" if shapes else ""
            results[case] = (max(w[0] for w in worst), max(w[1] for w in worst), note)
    bad = {case: r for case, r in results.items() if not r[0] <= tolerance}
    for case, (rel, absolute, note) in results.items():
        if show_all or case in bad:
            print(f"{case:50s} rel {rel:.3g}  abs {absolute:.3g}  {note}")
    groups: dict[str, list[float]] = {}
    for case, (rel, _, _) in results.items():
        groups.setdefault(
            "sources" if case.startswith("src/") else case.rsplit("/", 1)[1], []
        ).append(rel)
    for group, values in groups.items():
        print(
            f"{group:12s} {len(values):4d} cases, worst rel {max(values):.3g}, {sum(not v <= tolerance for v in values)} over {tolerance:g}"
        )
    overall = max(r[0] for r in results.values())
    agree = not bad
    print(f"overall: {len(results)} cases, worst rel {overall:.3g} (floor {floor:g}); "
          + ("all agree" if agree else f"{len(bad)} disagree") + f" within {tolerance:g} relative")  # fmt: skip
    return agree


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sub = parser.add_subparsers(dest="command", required=True)
    d = sub.add_parser("dump", help="write this build's outputs to an .npz")
    d.add_argument("output")
    d.add_argument(
        "--input", default=DEFAULT_INPUT, help="a lat-long map (default: venice example)"
    )
    d.add_argument("--source-size", type=int, default=48, help="N of every source layout (48)")
    d.add_argument("--size", type=int, default=32, help="N of every output (32)")
    d.add_argument("--sources", metavar="DUMP.npz", help="take the sources from another dump")
    c = sub.add_parser("compare", help="compare two dumps: A against B")
    c.add_argument("a")
    c.add_argument("b")
    c.add_argument("--floor", type=float, default=0.01)
    c.add_argument("--tolerance", type=float, default=1e-5)
    c.add_argument("--all", action="store_true", help="print every case, not only disagreements")
    args = parser.parse_args(argv)
    if args.command == "dump":
        dump(args.output, args.input, args.source_size, args.size, args.sources)
        return 0
    return 0 if compare(args.a, args.b, args.floor, args.tolerance, args.all) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
