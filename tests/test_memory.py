"""The memory model and peak memory of real conversions (envconv.engine.memory, docs/memory.md).

Peak memory is measured in a fresh process as its ``VmHWM`` (the high-water mark of its own
address space, which exec resets; ``ru_maxrss`` would carry the RSS of the forking pytest
process), less the same process's mark after a warm-up on a tiny map (interpreter, numpy,
OpenImageIO, OpenEXR, OpenColorIO and the core loaded and run once): the figure the model and
issue 15's bound are about. Linux only.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from conftest import write_plain

import envconv
from envconv.color.quantize import quantize
from envconv.engine import memory
from envconv.errors import UsageError
from envconv.io import encode

linux = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/status")

#: Runs ``envconv convert`` in process after a warm-up; prints the warm and final high-water marks.
PROBE = textwrap.dedent("""
    import json, sys
    from envconv.engine.api import convert_file

    def hwm():
        with open("/proc/self/status") as handle:
            return next(int(l.split()[1]) * 1024 for l in handle if l.startswith("VmHWM:"))

    tiny, out_tiny, source, out, resample = sys.argv[1:6]
    resample = json.loads(resample)
    convert_file(tiny, out_tiny, resample={**resample, "size": 4})
    warm = hwm()
    convert_file(source, out, resample=resample)
    print(json.dumps([warm, hwm()]))
""")


def _smooth_latlong(height: int) -> np.ndarray:
    """A smooth RGB lat-long (compresses like a photo would not, but the arrays are the same)."""
    y, x = np.mgrid[0:height, 0 : 2 * height].astype(np.float32)
    pixels = np.stack([x / (2 * height), y / height, 0.5 + 0.25 * np.sin(x / 37.0)], axis=2)
    return pixels.astype(np.float32)


@pytest.fixture(scope="module")
def sources(tmp_path_factory):
    folder = tmp_path_factory.mktemp("memory")
    tiny, mid = folder / "tiny.exr", folder / "mid.exr"
    write_plain(tiny, _smooth_latlong(16))
    write_plain(mid, _smooth_latlong(2048))
    return folder, tiny, mid


def _measure(folder, tiny, source, out_name: str, resample: dict) -> tuple[int, int]:
    """(warm baseline, peak) bytes of converting ``source`` in a fresh process."""
    ext = out_name[out_name.rindex(".") :]
    done = subprocess.run(
        [sys.executable, "-c", PROBE, str(tiny), str(folder / f"tiny-out{ext}"), str(source),
         str(folder / out_name), json.dumps(resample)],
        capture_output=True, text=True, timeout=120, check=True,
    )  # fmt: skip
    warm, peak = json.loads(done.stdout.strip().splitlines()[-1])
    return warm, peak


def _array_bytes(source, out) -> tuple[int, int]:
    """(input, output) float32 array bytes: the source as read, every level written."""
    width, height, channels, _ = envconv.io.read_header(source)
    written = sum(w * h for w, h in envconv.io.mip_levels(out)) * len(
        envconv.io.read_header(out)[2]
    )
    return width * height * len(channels) * 4, written * 4


@linux
@pytest.mark.parametrize(
    "out_name, resample",
    [
        ("plain.exr", {"to": "cube-vcross", "size": 1024}),
        ("same.exr", {"to": "latlong", "size": 2048}),
        ("sdr.png", {"to": "cube-vcross", "size": 1024}),
        ("alpha.exr", {"to": "cube-vcross", "size": 1024, "alpha": True}),
        ("cross-alpha.png", {"to": "cube-vcross", "size": 1024, "alpha": True}),
    ],
)
def test_peak_is_within_issue_15_bound_and_the_estimate(sources, out_name, resample):
    """Peak RSS ≤ 1.25 × (input + output arrays) + the warm baseline (issue 15), for a
    4096 × 2048 RGB float source: 100 MB in, 150–200 MB out. No further tolerance. The model's
    estimate is at least that measured peak and at most twice it (it counts the write phase at
    a half-float copy, so it is an upper bound). One measurement serves both."""
    folder, tiny, mid = sources
    warm, peak = _measure(folder, tiny, mid, out_name, resample)
    read, written = _array_bytes(mid, folder / out_name)
    measured = peak - warm
    assert 0 < measured <= 1.25 * (read + written), (measured, read, written)
    source = envconv.read(mid)
    options = {k: v for k, v in resample.items() if k != "to"}
    estimate = envconv.resample.convert.memory_needed(source, resample["to"], **options)
    assert measured <= estimate <= 2 * measured, (measured, estimate)


@linux
def test_a_magnifying_conversion_is_within_the_bound_too(sources):
    """A conversion that magnifies (the 4096 × 2048 source into 3072 px cube faces: output
    pixels a third of a texel's solid angle) takes the area filter's linear reconstruction,
    whose slopes are made per texel in small per-thread tables, never as planes the size of the
    source (two such planes would be 2 × the input against the bound's 0.25 × (input +
    output) of room): its peak stays within issue 15's bound, and within the estimate."""
    folder, tiny, mid = sources
    source = envconv.read(mid)
    resample = {"to": "cube-vcross", "size": 1536}
    assert envconv.resample.options.magnifies(source, resample["to"], resample["size"])
    warm, peak = _measure(folder, tiny, mid, "magnify.exr", resample)
    read, written = _array_bytes(mid, folder / "magnify.exr")
    measured = peak - warm
    assert 0 < measured <= 1.25 * (read + written), (measured, read, written)
    estimate = envconv.resample.convert.memory_needed(source, "cube-vcross", size=1536)
    assert measured <= estimate <= 2 * measured, (measured, estimate)


def test_blockwise_encoding_is_the_whole_image_encoding(monkeypatch):
    """Encoding a level in blocks of rows gives the codes and clip report of quantizing it
    whole (the dither noise follows the element index across blocks)."""
    rng = np.random.default_rng(5)
    pixels = rng.uniform(-0.2, 1.3, (37, 29, 4)).astype(np.float32)
    plan = encode.OutputPlan("png", "uint8", "lin_rec709_scene", "lin_rec709_scene",
                             "lin_rec709_scene", None)  # fmt: skip
    whole, report = quantize(pixels, "uint8", dither=True)
    monkeypatch.setattr(encode, "ENCODE_BLOCK_BYTES", 29 * 4 * 4 * 3)  # 3 rows a block
    codes, merged, _ = encode._encode_level(pixels, plan, envconv.color.ocio.config_for(None), True)
    np.testing.assert_array_equal(codes, whole)
    assert merged == report


@pytest.mark.parametrize("text, expected", [("2G", 2 << 30), ("512M", 512 << 20),
                                            ("1.5k", 1536), ("1000", 1000), ("3GiB", 3 << 30)])  # fmt: skip
def test_limit_variable_is_read_in_bytes(monkeypatch, text, expected):
    monkeypatch.setenv(memory.LIMIT_VARIABLE, text)
    assert memory.available() == (expected, True)


def test_bad_limit_variable_is_a_usage_error(monkeypatch):
    monkeypatch.setenv(memory.LIMIT_VARIABLE, "lots")
    with pytest.raises(UsageError, match=memory.LIMIT_VARIABLE):
        memory.available()


def test_convert_refuses_what_the_limit_cannot_hold(monkeypatch):
    """The library raises MemoryLimitError before allocating; under the limit it converts."""
    sky = envconv.EnvMap(np.ones((8, 16, 3), np.float32), "latlong")
    monkeypatch.setenv(memory.LIMIT_VARIABLE, "64M")
    with pytest.raises(memory.MemoryLimitError, match="cube-vcross at size 4000"):
        envconv.convert(sky, "cube-vcross", size=4000)  # 4000² × 12 cells × 12 bytes
    assert envconv.convert(sky, "cube-vcross", size=64).pixels.shape == (256, 192, 3)


def test_estimate_grows_with_every_array():
    """Each array of the model adds to the estimate: alpha, a chain, holes."""
    sky = envconv.EnvMap(np.ones((64, 128, 3), np.float32), "latlong")
    base = envconv.resample.convert.memory_needed(sky, "cube-vcross", size=256, samples=2)
    plane = 4 * 256 * 3 * 256 * 4  # one float32 plane of the 3N × 4N cross
    alpha = envconv.resample.convert.memory_needed(
        sky, "cube-vcross", size=256, samples=2, alpha=True
    )
    assert alpha - base >= plane  # the alpha channel in the output
    chain = envconv.resample.convert.memory_needed(
        sky, "cube-vcross", size=256, samples=2, mips=True
    )
    assert chain - base > 0.9 * plane  # a third more output and the float32 weights of each level
    holes = envconv.EnvMap(sky.pixels, "latlong", valid=np.ones((64, 128), np.float32))
    assert envconv.resample.convert.memory_needed(holes, "cube-vcross", size=256, samples=2) > base


def test_system_memory_is_used_at_80_percent(monkeypatch):
    """Without the variable, a run may plan on USABLE_SHARE of the least the system reports:
    MemAvailable, the cgroup's room and ulimit -v's room."""
    monkeypatch.delenv(memory.LIMIT_VARIABLE, raising=False)
    monkeypatch.setattr(memory, "_meminfo_available", lambda: 10 << 30)
    monkeypatch.setattr(memory, "_cgroup_room", lambda: None)
    monkeypatch.setattr(memory, "_address_space_room", lambda: None)
    assert memory.available() == (8 << 30, False)
    monkeypatch.setattr(memory, "_cgroup_room", lambda: 5 << 30)
    assert memory.available() == (4 << 30, False)
    with pytest.raises(memory.MemoryLimitError, match="needs about 6 GB of memory and 4 GB"):
        memory.check(6 << 30, "this conversion")
    memory.check(3 << 30, "this conversion")  # fits: no error


@linux
def test_half_source_to_a_small_map_is_within_the_bound(sources):
    """A half-float EXR shrunk to a small cube: reading must not hold a half copy of the whole
    image beside the float32 one (it peaked at 1.5 × the arrays, all of it the read)."""
    folder, tiny, mid = sources
    half = folder / "half.exr"
    write_plain(half, _smooth_latlong(2048), pixel_type="half")
    warm, peak = _measure(folder, tiny, half, "small.exr", {"to": "cube-vcross", "size": 64})
    read, written = _array_bytes(half, folder / "small.exr")
    assert peak - warm <= 1.25 * (read + written), (peak - warm, read, written)


# --- the memory cgroups: v1 and v2, nested limits, read from a fake /proc and /sys tree -----

_MIB = 1 << 20
_V1_UNLIMITED = 9223372036854771712  # what the kernel reports for "no limit" (PAGE_COUNTER_MAX)


def cgroup_tree(root, cgroup: str, mountinfo: str | None, files: dict[str, str]) -> str:
    """A fake system under ``root``: /proc/self/cgroup, /proc/self/mountinfo (None: none,
    the default mount points are used) and each ``files`` path (under /sys/fs/cgroup)."""
    (root / "proc" / "self").mkdir(parents=True)
    (root / "proc" / "self" / "cgroup").write_text(cgroup)
    if mountinfo is not None:
        (root / "proc" / "self" / "mountinfo").write_text(mountinfo)
    (root / "proc" / "meminfo").write_text(f"MemTotal: 67108864 kB\nMemAvailable: {64 << 20} kB\n")
    for path, text in files.items():
        target = root / path.lstrip("/")
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text)
    return str(root)


_V1_MOUNTS = (
    "31 23 0:28 / /sys/fs/cgroup rw,relatime - tmpfs tmpfs rw,mode=755\n"
    "32 31 0:29 / /sys/fs/cgroup/cpu rw,relatime - cgroup cgroup rw,cpu\n"
    "35 31 0:32 {root} /sys/fs/cgroup/memory rw,relatime - cgroup cgroup rw,memory\n"
    "41 31 0:38 / /sys/fs/cgroup/unified rw,relatime - cgroup2 cgroup2 rw\n"
)


def test_cgroup_v1_limit_less_the_working_set(tmp_path):
    """A v1 memory cgroup (a host's service, an older Docker): limit 1 GiB, 600 MiB used of
    which 100 MiB inactive page cache: 524 MiB left. The v2 hierarchy of the hybrid system
    has no memory controller and says nothing."""
    group = "/sys/fs/cgroup/memory/jobs/run7/"
    root = cgroup_tree(tmp_path, "4:memory:/jobs/run7\n1:cpu:/\n0::/\n", _V1_MOUNTS.format(root="/"), {
        group + "memory.limit_in_bytes": f"{1024 * _MIB}\n",
        group + "memory.usage_in_bytes": f"{600 * _MIB}\n",
        group + "memory.stat": f"cache 0\ntotal_inactive_file {100 * _MIB}\n"
                               f"hierarchical_memory_limit {1024 * _MIB}\n",
        "/sys/fs/cgroup/memory/memory.limit_in_bytes": f"{_V1_UNLIMITED}\n",
        "/sys/fs/cgroup/memory/memory.usage_in_bytes": f"{5000 * _MIB}\n",
    })  # fmt: skip
    assert memory._cgroup_room(root) == 524 * _MIB


def test_cgroup_v1_hierarchical_limits(tmp_path):
    """The process's own group sets no limit; a visible parent does (1.5 GiB, 1.2 GiB used:
    300 MiB left) and a hidden ancestor too (hierarchical_memory_limit 2 GiB over the leaf's
    1 GiB used): the tightest, 300 MiB, counts. In a container the mount's root is the
    container's group (no cgroup namespace), so the mount point is the process's group."""
    base = "/sys/fs/cgroup/memory/"
    root = cgroup_tree(tmp_path, "4:memory:/docker/abc/job\n", _V1_MOUNTS.format(root="/docker"), {
        base + "abc/job/memory.limit_in_bytes": f"{_V1_UNLIMITED}\n",
        base + "abc/job/memory.usage_in_bytes": f"{1024 * _MIB}\n",
        base + "abc/job/memory.stat": f"hierarchical_memory_limit {2048 * _MIB}\n",
        base + "abc/memory.limit_in_bytes": f"{1536 * _MIB}\n",
        base + "abc/memory.usage_in_bytes": f"{1236 * _MIB}\n",
    })  # fmt: skip
    assert memory._cgroup_room(root) == 300 * _MIB
    (tmp_path / "sys/fs/cgroup/memory/abc/memory.limit_in_bytes").write_text(f"{_V1_UNLIMITED}\n")
    assert memory._cgroup_room(root) == 1024 * _MIB  # the hidden ancestor's limit alone


def test_cgroup_v2_nested_and_default_mount(tmp_path):
    """v2, no mountinfo (the default /sys/fs/cgroup): the group's memory.max is 'max', its
    parent's 1 GiB with 200 MiB used, 50 MiB of it inactive page cache: 874 MiB left."""
    base = "/sys/fs/cgroup/"
    root = cgroup_tree(tmp_path, "0::/user.slice/app\n", None, {
        base + "user.slice/app/memory.max": "max\n",
        base + "user.slice/app/memory.current": f"{100 * _MIB}\n",
        base + "user.slice/memory.max": f"{1024 * _MIB}\n",
        base + "user.slice/memory.current": f"{200 * _MIB}\n",
        base + "user.slice/memory.stat": f"anon 0\ninactive_file {50 * _MIB}\n",
    })  # fmt: skip
    assert memory._cgroup_room(root) == 874 * _MIB
    (tmp_path / "sys/fs/cgroup/user.slice/memory.max").write_text("max\n")
    assert memory._cgroup_room(root) is None  # no limit anywhere
    assert memory._cgroup_room(str(tmp_path / "nowhere")) is None  # no cgroups at all


def test_cgroup_room_of_this_machine():
    """The real files, where this machine has them: None or the bytes left under a limit
    that really is there (v2's memory.max or v1's limit_in_bytes of the process's group)."""
    room = memory._cgroup_room()
    limits = []
    for version, folder, _ in memory._memory_cgroups(None):
        name = "memory.max" if version == 2 else "memory.limit_in_bytes"
        value = memory._read_number(f"{folder}/{name}")
        if value is not None and value < 1 << 60:
            limits.append(value)
    if room is None:
        assert not limits
    else:
        assert 0 <= room <= max(limits)
