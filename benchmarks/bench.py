"""envconv benchmarks: kernel throughput, end-to-end conversion time and peak memory.

Run by hand and quote the figures; nothing here is a test.

    python benchmarks/bench.py              # kernel, e2e, batch, mips
    python benchmarks/bench.py kernel       # supersamples per second in envconv.convert
    python benchmarks/bench.py e2e          # whole-process lat-long 2048x1024 EXR -> cube-vcross 512
    python benchmarks/bench.py batch        # envconv batch of 20 such files, -j 1 and -j 2
    python benchmarks/bench.py mips         # a whole mip chain against level 0 alone
    python benchmarks/bench.py versus TREE  # e2e, interleaved, against another checkout
                                            # (pure-Python trees, put on PYTHONPATH)
    python benchmarks/bench.py targets --baseline PYTHON --peer PYTHON [--rows ...]
                                            # issue 14's table: this build, another build's
                                            # venv and py360convert + OpenCV, interleaved
                                            # (see benchmarks/targets.py, or targets --help)
    python benchmarks/bench.py ibl          # GGX chain + irradiance, whole process, and per level
    python benchmarks/bench.py ibl --baseline PYTHON
                                            # the same, interleaved with another venv's envconv
    python benchmarks/bench.py preview      # contact sheet and viewer page of a 16K lat-long, in process
    python benchmarks/bench.py filters [--rounds R] [--threads T] [--oneshot]
                                            # the area filter against the point kernel at
                                            # S = 1, 4 and auto, interleaved (benchmarks/filters.py);
                                            # --oneshot: the whole envconv convert, area against bilinear
    python benchmarks/bench.py memory       # peak RSS over (input + output arrays), per case,
                                            # beside envconv.engine.memory's estimate (docs/memory.md)

The envconv measured is the one the running interpreter imports (run this with a venv's python
in which envconv is installed); the first line printed names it. Kernel throughput counts output
supersamples (pixels × S²) per second of ``envconv.convert`` wall time, for an in-memory
lat-long 4096×2048 → cube-vcross 1024 on all cores, after one warm-up call. End-to-end time runs
``envconv convert`` as a fresh process (interpreter start to file written), takes the median of
several runs and excludes the first (which may compile). Peak memory is the child's max RSS.
"""

from __future__ import annotations

import compileall
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
try:
    import envconv
except ImportError:  # not installed: this checkout's (pure-Python builds only)
    sys.path.insert(0, ROOT)
    import envconv

from builds import EXAMPLES, batch_inputs  # noqa: E402

EXAMPLE = os.path.join(EXAMPLES, "park-latlong-512.exr")


def _latlong(height: int) -> envconv.EnvMap:
    """A lat-long of the park example upsampled to ``height`` rows, RGB float32."""
    park = envconv.read(EXAMPLE)
    return envconv.convert(park, "latlong", size=height, samples=1)


def bench_kernel(samples=(1, 2, 4, "auto"), repeats: int = 3) -> None:
    """``envconv.convert`` of an in-memory lat-long 4096×2048 → cube-vcross 1024 at fixed S and
    at samples="auto" (adaptive; reported as time only), the best of ``repeats`` after a warm-up.
    The time includes what convert does around the kernel (output allocation, rip-map for auto)."""
    src = _latlong(2048)
    face_pixels = 6 * 1024 * 1024
    for s in samples:
        times = []
        for _ in range(repeats + 1):  # the first run is a warm-up
            t = time.perf_counter()
            envconv.convert(src, "cube-vcross", size=1024, samples=s)
            times.append(time.perf_counter() - t)
        best = min(times[1:])
        if s == "auto":
            print(f"kernel latlong 4096x2048 -> cube-vcross 1024, S=auto: {best * 1e3:7.1f} ms")
            continue
        rate = face_pixels * s * s / best / 1e6
        print(
            f"kernel latlong 4096x2048 -> cube-vcross 1024, S={s}: {best * 1e3:7.1f} ms, {rate:6.1f} M supersamples/s (face pixels only)"
        )


def _run(cmd: list[str]) -> tuple[float, float]:
    t = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    elapsed = time.perf_counter() - t
    if proc.returncode:
        raise SystemExit(f"failed: {' '.join(cmd)}\n{proc.stderr}")
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    return elapsed, peak


def _compile_bytecode() -> None:
    """Write envconv's .pyc files, as installing the package does (an editable install under
    PYTHONDONTWRITEBYTECODE would otherwise compile every module at every start)."""
    compileall.compile_dir(os.path.dirname(envconv.__file__), quiet=1)


def bench_e2e(runs: int = 6) -> None:
    exe = os.path.join(os.path.dirname(sys.executable), "envconv")
    _compile_bytecode()
    with tempfile.TemporaryDirectory() as tmp:
        src_path = os.path.join(tmp, "latlong-2048.exr")
        envconv.write(_latlong(1024), src_path, bit_depth="float")
        big_path = os.path.join(tmp, "latlong-4096.exr")
        envconv.write(_latlong(2048), big_path, bit_depth="float")
        out_path = os.path.join(tmp, "cross.exr")
        cases = [
            ("latlong 4096x2048 float EXR -> cube-vcross 1024", [exe, "convert", big_path, os.path.join(tmp, "big.exr"), "--to", "cube-vcross", "--size", "1024"]),
            ("latlong 2048x1024 float EXR -> cube-vcross 512", [exe, "convert", src_path, out_path, "--to", "cube-vcross", "--size", "512"]),
            ("latlong 2048x1024 float EXR -> cube-vcross 512, --compression none", [exe, "convert", src_path, os.path.join(tmp, "raw.exr"), "--to", "cube-vcross", "--size", "512", "--compression", "none"]),
            ("cube-vcross 512 -> latlong 2048x1024", [exe, "convert", out_path, os.path.join(tmp, "back.exr"), "--to", "latlong", "--size", "1024"]),
        ]  # fmt: skip
        for label, cmd in cases:
            _run(cmd)  # first run: may compile
            times = [_run(cmd)[0] for _ in range(runs)]
            peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
            print(
                f"e2e {label}: median {statistics.median(times):.3f} s, best {min(times):.3f} s over {runs} runs (peak RSS of any child so far {peak:.0f} MB)"
            )
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", "import envconv.cli"], check=True)
        print(f"import envconv.cli: {time.perf_counter() - start:.3f} s (process start included)")


def bench_versus(other: str, runs: int = 12) -> None:
    """The e2e lat-long 2048x1024 -> cube-vcross 512 (zip and uncompressed) of this checkout and
    of ``other`` (another checkout of envconv, e.g. ``git worktree add /tmp/old <commit>``),
    run alternately so that the machine's drift hits both alike. Each tree's kernels are
    compiled by a first, unreported run. Both run in a scratch directory, so that neither
    imports the other's package from the working directory."""
    other = os.path.abspath(other)
    if not os.path.isfile(os.path.join(other, "envconv", "__init__.py")):
        raise SystemExit(f"{other} is not a checkout of envconv")
    runner = "import sys; from envconv.cli import main; sys.argv[0] = 'envconv'; main()"
    trees = {"this": ROOT, "other": other}
    for tree in trees.values():
        compileall.compile_dir(os.path.join(tree, "envconv"), quiet=1)
    cases = {"zip": [], "none": ["--compression", "none"]}
    with tempfile.TemporaryDirectory() as tmp:
        src_path = os.path.join(tmp, "latlong-2048.exr")
        envconv.write(_latlong(1024), src_path, bit_depth="float")

        def run(tree: str, case: str) -> float:
            env = {**os.environ, "PYTHONPATH": trees[tree]}
            out = os.path.join(tmp, f"{tree}-{case}.exr")
            cmd = [sys.executable, "-c", runner, "convert", src_path, out, "--to", "cube-vcross",
                   "--size", "512", *cases[case]]  # fmt: skip
            start = time.perf_counter()
            subprocess.run(cmd, check=True, cwd=tmp, env=env, stdout=subprocess.DEVNULL)
            return time.perf_counter() - start

        times = {(tree, case): [] for tree in trees for case in cases}
        for key in times:
            run(*key)  # may compile
        for _ in range(runs):
            for key in times:
                times[key].append(run(*key))
    for (tree, case), values in times.items():
        label = ROOT if tree == "this" else other
        print(
            f"versus {case:4s} {label}: median {statistics.median(values):.3f} s, best {min(values):.3f} s over {runs} runs"
        )


# --- batch (issue 5) ------------------------------------------------------------------------


def bench_batch(files: int = 20) -> None:
    """``envconv batch`` over ``files`` float lat-longs 2048x1024 (zip EXR: the four examples,
    upsampled, each under several rotations) -> cube-vcross 512, with -j 1 and -j 2, writing
    zip (the default) and uncompressed EXRs. Prints the batch's own per-file figure (start-up
    included once, as a batch pays it) and the whole process's wall time per file."""
    exe = os.path.join(os.path.dirname(sys.executable), "envconv")
    _compile_bytecode()
    with tempfile.TemporaryDirectory() as tmp:
        inputs = batch_inputs(os.path.join(tmp, "in"), files)
        for jobs in (1, 2):
            for label, write in (("zip", ["--out", "o/{stem}_{layout}.exr"]), ("none", [])):
                out = os.path.join(tmp, f"o{jobs}{label}")
                steps = ["resample", "--to", "cube-vcross", "--size", "512"]
                if not write:
                    steps += [
                        "write",
                        os.path.join(out, "{stem}_{layout}.exr"),
                        "--compression",
                        "none",
                    ]
                else:
                    write = ["--out", os.path.join(out, "{stem}_{layout}.exr")]
                cmd = [exe, "batch", inputs, *write, "-j", str(jobs), *steps]
                for _ in range(2):  # the second run is reported; the first warms the caches
                    shutil.rmtree(out, ignore_errors=True)
                    start = time.perf_counter()
                    proc = subprocess.run(cmd, capture_output=True, text=True)
                    wall = time.perf_counter() - start
                if proc.returncode:
                    raise SystemExit(f"failed: {' '.join(cmd)}\n{proc.stderr}")
                output = (proc.stdout + proc.stderr).splitlines()
                summary = next(line for line in output if " files: " in line)
                print(
                    f"batch {files} x latlong 2048x1024 -> cube-vcross 512, -j {jobs}, {label}: {summary} | process {wall / files:.3f} s per file"
                )


# --- mip chains (issue 3) -------------------------------------------------------------------


def bench_mips(repeats: int = 7) -> None:
    """Whole mip chain vs level 0 alone: lat-long 2048x1024 -> cube-vcross 512, in process.

    Equivalent command: envconv convert latlong-2048.exr cross.exr --to cube-vcross --size 512 --mips
    """
    from envconv.resample.convert import auto_samples

    src = _latlong(1024)
    # A chain uses one S for every pixel (see envconv.resample.convert); level 0 alone is timed with the
    # same S, so that the ratio is the cost of the chain, not of a different sampling rule.
    s = auto_samples(src, "cube-vcross", 512)
    for mips in (None, True):
        envconv.convert(src, "cube-vcross", size=512, mips=mips, samples=s)  # warm-up / compile
    times = {None: [], True: []}
    for _ in range(repeats):
        for mips in (None, True):  # interleaved, so machine load hits both alike
            start = time.perf_counter()
            envconv.convert(src, "cube-vcross", size=512, mips=mips, samples=s)
            times[mips].append(time.perf_counter() - start)
    level0, chain = statistics.median(times[None]), statistics.median(times[True])
    print(
        f"mips latlong 2048x1024 -> cube-vcross 512, S={s}: level 0 {level0 * 1e3:.0f} ms, full chain (12 levels) {chain * 1e3:.0f} ms, ratio {chain / level0:.2f}"
    )


def _run_cpu(cmd: list[str]) -> tuple[float, float]:
    """Wall time and CPU time (user + system, all threads) of one child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    elapsed = _run(cmd)[0]
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return elapsed, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime


def bench_ibl(runs: int = 5, baseline: str | None = None) -> None:
    """Image-based lighting: lat-long 2048x1024 -> GGX chain of a cube 256 (DDS) and a 32
    irradiance cube (DDS), one process (wall and CPU time); then the prefilter's time per level,
    in process. With ``baseline`` (another venv's python), that venv's ``envconv`` runs the same
    command alternately with this one, and the ratios are printed."""
    exes = {"this": os.path.join(os.path.dirname(sys.executable), "envconv")}
    if baseline:
        exes["baseline"] = os.path.join(os.path.dirname(os.path.abspath(baseline)), "envconv")
    _compile_bytecode()
    with tempfile.TemporaryDirectory() as tmp:
        src_path = os.path.join(tmp, "latlong-2048.exr")
        envconv.write(_latlong(1024), src_path, bit_depth="float")

        def cmd(exe):
            return [exe, "read", src_path, "resample", "--to", "cube-faces", "--size", "256",
                    "--mips", "ggx", "write", os.path.join(tmp, "spec.dds"), "resample", "--to",
                    "cube-faces", "--size", "32", "--irradiance", "write",
                    os.path.join(tmp, "irr.dds")]  # fmt: skip

        for exe in exes.values():
            _run(cmd(exe))  # first run: may compile
        spent = {name: [] for name in exes}
        for _ in range(runs):
            for name, exe in exes.items():
                spent[name].append(_run_cpu(cmd(exe)))
    for name, exe in exes.items():
        wall, cpu = [w for w, _ in spent[name]], [c for _, c in spent[name]]
        print(f"ibl {name} ({exe}) {' '.join(cmd('envconv')[1:])}: median "
              f"{statistics.median(wall):.3f} s, best {min(wall):.3f} s, CPU median "
              f"{statistics.median(cpu):.3f} s over {runs} runs")  # fmt: skip
    if baseline:
        ratio = [b[0] / t[0] for t, b in zip(spent["this"], spent["baseline"], strict=True)]
        cpu_ratio = [b[1] / t[1] for t, b in zip(spent["this"], spent["baseline"], strict=True)]
        print(f"ibl baseline/this, run by run: wall median {statistics.median(ratio):.2f}x, "
              f"CPU median {statistics.median(cpu_ratio):.2f}x")  # fmt: skip
    from envconv.resample.convert import ibl

    source = _latlong(1024)
    spent = []
    original = ibl._prefilter

    def timed(*args, **kwargs):
        start = time.perf_counter()
        result = original(*args, **kwargs)
        spent.append((result.shape, args[7], time.perf_counter() - start))
        return result

    ibl._prefilter = timed
    try:
        envconv.convert(source, "cube-faces", size=256, mips="ggx")
    finally:
        ibl._prefilter = original
    for shape, alpha, seconds in spent:
        print(f"ibl level {shape[1]}x{shape[0]} alpha {alpha:.4f}: {seconds * 1e3:.0f} ms")


def bench_preview(repeats: int = 3) -> None:
    """Contact sheet and viewer page of an in-memory 16K lat-long (16384x8192), in process.

    Equivalent commands: envconv preview latlong-16k.exr -o sheet.png; envconv view latlong-16k.exr
    (reading the file comes on top)."""
    from envconv.views.preview import contact_sheet
    from envconv.views.viewer import build_page

    src = _latlong(8192)
    for name, make in (("contact sheet", contact_sheet), ("viewer page", build_page)):
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            make(src)
            times.append(time.perf_counter() - start)
        print(f"preview 16384x8192 lat-long, {name}: median {statistics.median(times):.2f} s, "
              f"best {min(times):.2f} s over {repeats} runs")  # fmt: skip


def peak_rss(argv: list[str]) -> int:
    """Peak RSS in bytes of the process ``argv`` (its own, from ``os.wait4``); raises on failure."""
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    error = proc.stderr.read().decode()
    proc.stderr.close()
    if proc.returncode:
        raise SystemExit(f"failed ({proc.returncode}): {' '.join(argv)}\n{error}")
    return usage.ru_maxrss * 1024  # Linux reports kB


def memory_cases(tmp: str) -> list[tuple[str, str, list[str]]]:
    """(label, input, convert arguments) of the memory row; inputs are written into ``tmp``
    by child processes (a child forked from a big parent would report the parent's RSS)."""
    exe = os.path.join(os.path.dirname(sys.executable), "envconv")
    inputs = {}
    for height in (1024, 2048):
        inputs[height] = os.path.join(tmp, f"latlong-{2 * height}.exr")
        subprocess.run([exe, "convert", EXAMPLE, inputs[height], "--to", "latlong", "--size",
                        str(height), "--samples", "1", "--bit-depth", "float"], check=True)  # fmt: skip
    small, big = inputs[1024], inputs[2048]
    return [
        ("latlong 2048x1024 -> cube-vcross 512, EXR", small, ["--to", "cube-vcross", "--size", "512"]),
        ("latlong 4096x2048 -> cube-vcross 1024, EXR", big, ["--to", "cube-vcross", "--size", "1024"]),
        ("latlong 4096x2048 -> latlong 4096x2048, EXR", big, ["--to", "latlong", "--size", "2048"]),
        ("latlong 4096x2048 -> cube-vcross 64 (rip-map), EXR", big, ["--to", "cube-vcross", "--size", "64"]),
        ("latlong 4096x2048 -> cube-vcross 1024 --mips, EXR", big, ["--to", "cube-vcross", "--size", "1024", "--mips"]),
        ("latlong 4096x2048 -> cube-vcross 1024 --alpha, EXR", big, ["--to", "cube-vcross", "--size", "1024", "--alpha"]),
        ("latlong 4096x2048 -> cube-vcross 1024, PNG", big, ["--to", "cube-vcross", "--size", "1024", ".png"]),
        ("latlong 4096x2048 -> latlong 4096x2048, PNG", big, ["--to", "latlong", "--size", "2048", ".png"]),
    ]  # fmt: skip


def array_bytes(source: str, out: str) -> tuple[int, int]:
    """(input, output) array bytes of a conversion: the float32 source as read and every
    float32 level of the output as written, channels included (what issue 15's bound counts)."""
    src = envconv.io.read_header(source)
    read = src[0] * src[1] * len(src[2]) * 4
    written = 0
    for path in [out]:
        for width, height in envconv.io.mip_levels(path):
            written += width * height * len(envconv.io.read_header(path)[2]) * 4
    return read, written


def bench_memory() -> None:
    """Peak RSS of ``envconv convert`` per case, less the baseline: the peak of the same command
    on a 32×16 source at size 4 (interpreter, numpy, OIIO, OpenEXR, OCIO and the core loaded, a
    conversion run; about 100 MB), over the input and output array bytes."""
    exe = os.path.join(os.path.dirname(sys.executable), "envconv")
    with tempfile.TemporaryDirectory() as tmp:
        tiny = os.path.join(tmp, "tiny.exr")
        subprocess.run([exe, "convert", EXAMPLE, tiny, "--to", "latlong", "--size", "16",
                        "--bit-depth", "float"], check=True)  # fmt: skip
        for label, source, args in memory_cases(tmp):
            ext = args.pop() if args[-1].startswith(".") else ".exr"
            out = os.path.join(tmp, f"out{ext}")
            base = peak_rss([exe, "convert", tiny, os.path.join(tmp, f"tiny-out{ext}"), *args[:2],
                             "--size", "4", *args[4:]])  # fmt: skip
            peak = peak_rss([exe, "convert", source, out, *args])
            read, written = array_bytes(source, out)
            ratio = (peak - base) / (read + written)
            guess = _estimate(source, args)
            print(f"memory {label}: peak {peak / 2**20:.0f} MB - baseline {base / 2**20:.0f} MB "
                  f"= {(peak - base) / 2**20:.0f} MB over in {read / 2**20:.0f} MB + out "
                  f"{written / 2**20:.0f} MB: {ratio:.2f}; estimate {guess / 2**20:.0f} MB "
                  f"({guess / (peak - base):.2f}x)")  # fmt: skip


def _estimate(source: str, args: list[str]) -> int:
    """envconv.engine.memory's estimate for ``convert SOURCE --to L --size N [--mips|--alpha]``,
    worked out in a child process (reading the source here would swell later children)."""
    options = {"mips": "--mips" in args, "alpha": "--alpha" in args}
    code = ("import sys, envconv; print(envconv.resample.convert.memory_needed(envconv.read(sys.argv[1]),"
            f" {args[1]!r}, size={int(args[3])}, **{options!r}))")  # fmt: skip
    done = subprocess.run([sys.executable, "-c", code, source], capture_output=True, text=True,
                          check=True)  # fmt: skip
    return int(done.stdout.split()[-1])


def main(argv: list[str]) -> None:
    which = argv[1:] or ["kernel", "e2e", "batch", "mips"]
    if which[0] in ("-h", "--help"):
        print(__doc__)
        return
    print(
        f"envconv {envconv.__version__} ({os.path.dirname(envconv.__file__)}), numpy {np.__version__}, {os.cpu_count()} cores"
    )
    if which[0] == "targets":
        import targets

        targets.main(which[1:])
        return
    if which[0] == "filters":
        import filters

        rounds = int(which[which.index("--rounds") + 1]) if "--rounds" in which else 9
        threads = int(which[which.index("--threads") + 1]) if "--threads" in which else None
        if "--oneshot" in which:
            filters.bench_oneshot(_latlong(1024), rounds)
        else:
            filters.bench_filters(_latlong(1024), rounds, threads)
        return
    if which[0] == "versus":
        if len(which) != 2:
            raise SystemExit("usage: python benchmarks/bench.py versus OTHER_CHECKOUT")
        bench_versus(which[1])
        return
    baseline = None
    if "--baseline" in which:
        at = which.index("--baseline")
        if at + 1 >= len(which):
            raise SystemExit("usage: python benchmarks/bench.py ibl --baseline PYTHON")
        baseline = which[at + 1]
        which = which[:at] + which[at + 2 :]
    unknown = set(which) - {"kernel", "e2e", "batch", "mips", "ibl", "preview", "memory"}
    if unknown:
        raise SystemExit(f"unknown benchmark {', '.join(sorted(unknown))}; see --help")
    if "kernel" in which:
        bench_kernel()
    if "e2e" in which:
        bench_e2e()
    if "batch" in which:
        bench_batch()
    if "mips" in which:
        bench_mips()
    if "ibl" in which:
        bench_ibl(baseline=baseline)
    if "preview" in which:
        bench_preview()
    if "memory" in which:
        bench_memory()


if __name__ == "__main__":
    main(sys.argv)
