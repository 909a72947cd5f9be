"""How much memory a conversion needs, and the guard that refuses one that cannot fit.

The model
---------
Every array envconv allocates is float32 (4 bytes per value) unless said otherwise. For a
source of ``I`` bytes (H × W × C float32, as read: an ``A`` added for holes included) and an
output of ``O`` bytes (every level of the chain, every channel, alpha included), a run's
peak above the interpreter's baseline is the largest of three phases:

read
    ``I`` + the decode buffer of a file that does not store float32 (half: ``I/2``;
    8/16-bit, decoded and then converted from sRGB: ``I + I/C``, the copy and its NaN mask)
    + ``I`` + ``I/C`` when the data window leaves holes (the image placed in its display window
    and ``valid``).
resample
    ``I`` + a copy of the source with ``valid`` as one more channel (holes only) + the rip-map
    of a lat-long read with adaptive bilinear sampling (levels 1 … K of the rows next to each
    pole that output pixels can read at that level, :func:`envconv.resample.convert.rip_rows`, at most
    a fifth of ``I``: :func:`envconv.resample.convert.rip_row_cap`)
    + the output levels + one coverage plane per level (alpha, same-grid copy, GGX and
    irradiance chains; an alpha channel appended to a single level is the kernel's coverage,
    written in place) + one plane of float32 sub-sample weights per level (mips) + the output
    levels again when alpha is appended to a chain (``np.concatenate`` per level) or holes' V
    channel is dropped. (GGX and irradiance chains' own buffers are not counted.)
write
    ``I`` + ``O`` + one block of rows being encoded (:data:`envconv.io.encode.ENCODE_BLOCK_BYTES`
    of float32 and its temporaries) and the band handed to OIIO. A single-file layout's levels
    are encoded a band at a time as they are written (:class:`envconv.io.encode.LazyLevel`).
    Cells of a multi-file layout, parts of a multi-part file and DDS/KTX2 containers are cut
    from one encoded copy of each level: half ``O/2``, 8-bit ``O/4``, 16-bit ``O/2``, float
    0 (``O`` when colour is converted); the estimate counts ``O/2`` for multi-file layouts,
    and :func:`envconv.io.encode.encode_output` checks again, knowing the format, before
    encoding.

A fixed ``SLACK`` of 32 MB (kernel thread buffers, OIIO and OpenEXR scratch) is added. The
estimate is meant as an upper bound within 1.5× of the measured peak (``tests/test_memory.py``
checks real conversions against it; docs/benchmarks.md lists measured ratios).

The guard
---------
:func:`check` compares an estimate with the memory available: ``ENVCONV_MEMORY_LIMIT`` (bytes,
or with a K, M, G or T suffix) when set, else 80% (:data:`USABLE_SHARE`) of the smallest of
Linux's ``MemAvailable``, the room left under the tightest memory limit of the process's
cgroup and its ancestors (v2's ``memory.max``, or v1's ``memory.limit_in_bytes`` and
``hierarchical_memory_limit``, less the usage that page cache cannot give back:
:func:`_cgroup_room`) and under ``ulimit -v``, else of ``sysconf(SC_AVPHYS_PAGES)`` (other
Unixes); with none of them nothing is checked. Memory the run already holds (the source, when resampling) counts as
available. A run that does not fit raises
:class:`MemoryLimitError` (an :class:`envconv.errors.EnvconvError`: one line, exit 1) before
allocating. :func:`envconv.io.read` checks the read phase from the header;
:func:`envconv.resample.convert.convert` checks the rest from the source in memory, and
:func:`envconv.io.encode.encode_output` the encoded copy.
"""

from __future__ import annotations

import os
import re
from typing import Any

from ..errors import EnvconvError, UsageError

__all__ = ["MemoryLimitError", "SLACK", "USABLE_SHARE", "LIMIT_VARIABLE", "estimate_read",
           "estimate_convert", "available", "check", "format_bytes"]  # fmt: skip

#: Bytes added to every estimate for what does not scale with the images: kernel thread
#: buffers, OIIO and OpenEXR scratch, memory the allocator keeps after a decode.
SLACK = 32 << 20

#: Share of the memory the system reports available that a run may plan to use: the kernel's
#: OOM killer strikes before MemAvailable is spent (page cache that cannot be dropped, other
#: processes growing meanwhile); a 20.8 GB run with 21 GB "available" was killed.
USABLE_SHARE = 0.8

#: Name of the environment variable that sets the memory available to a run (tests, CI).
LIMIT_VARIABLE = "ENVCONV_MEMORY_LIMIT"

_UNITS = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}


class MemoryLimitError(EnvconvError):
    """A run whose estimated peak memory exceeds the memory available."""


def estimate_read(width: int, height: int, channels: int, pixel_type: str = "float",
                  holes: bool = False) -> int:  # fmt: skip
    """Peak bytes of reading a ``width`` × ``height`` image of ``channels`` channels stored as
    ``pixel_type`` (``channels`` counts an ``A`` added for holes); see the module docstring."""
    plane = int(width) * int(height) * 4
    source = plane * int(channels)
    decode = {"float": 0, "double": source, "half": source // 2}.get(pixel_type, source + plane)
    placed = source + plane if holes else 0
    return source + decode + placed + SLACK


def estimate_convert(envmap, to, size: int, guard: int = 0, mips: Any = None,
                     alpha: bool = False, rips: int = 0, scratch: int = 0) -> int:  # fmt: skip
    """Peak bytes of resampling ``envmap`` (an :class:`envconv.EnvMap`) into layout ``to`` at
    ``size`` and writing the result; see the module docstring. ``mips`` as
    :func:`envconv.convert` takes it after ``box:``/``ggx:`` are stripped; ``rips`` the
    rip-map's resident bytes (:func:`envconv.resample.convert.memory_needed` works them out),
    ``scratch`` the kernel's working buffers (the area filter's per-thread tables)."""
    from ..layouts import get_layout
    from ..resample.mips import mip_sizes

    to = get_layout(to)
    height, width, nch = envmap.pixels.shape
    source = height * width * nch * 4
    holes = envmap.valid is not None
    carrier = source + height * width * 4 if holes else 0
    out_ch = nch + int(holes) + int(alpha and envmap.alpha_index is None)
    sizes = mip_sizes(to, size, guard, mips if mips else 1)
    planes = [w * h * 4 for w, h in sizes]
    output = sum(planes) * out_ch
    appends = alpha and envmap.alpha_index is None
    in_place = appends and not mips  # the kernel writes coverage into the alpha channel
    coverage = sum(planes) if ((alpha and not in_place) or to.name == envmap.layout.name) else 0
    weights = sum(planes) if mips else 0
    appended = output if (holes or (appends and mips)) else 0  # np.concatenate, V dropped
    rips = 0 if mips else rips
    resample = source + carrier + rips + output + coverage + weights + appended + scratch
    # Single-file layouts are encoded a band at a time as written; the cells of a multi-file
    # layout from one encoded copy of each level (counted as half float).
    write = source + output + (output // 2 if to.multi_file else 0) + (8 << 20)
    return max(resample, write) + SLACK


def _parse_bytes(text: str) -> int:
    match = re.fullmatch(r"\s*(\d+(?:\.\d+)?)\s*([KMGT]?)i?B?\s*", text, re.IGNORECASE)
    if not match:
        raise UsageError(f"{LIMIT_VARIABLE}={text!r}: expected bytes, e.g. 2G or 512M")
    return int(float(match.group(1)) * _UNITS[match.group(2).upper()])


#: Where the system's files (/proc, /sys/fs/cgroup) are read: "/" on a real machine; tests
#: point it at a tree of their own.
SYSTEM_ROOT = "/"
#: A v1 memory limit at or above this is "no limit" (the kernel reports PAGE_COUNTER_MAX
#: pages, 9223372036854771712 bytes on 64-bit Linux).
_NO_LIMIT = 1 << 60


def _system_path(path: str, root: str | None = None) -> str:
    return os.path.join(root or SYSTEM_ROOT, path.lstrip("/"))


def _meminfo_available(root: str | None = None) -> int | None:
    try:
        with open(_system_path("/proc/meminfo", root)) as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def _cgroup_room(root: str | None = None) -> int | None:
    """Bytes left under the tightest memory limit over this process's cgroup and the
    ancestors it can see, in cgroup v2 and in the v1 memory controller (a hybrid system has
    both); None when no limit applies or there are no cgroups.

    A level's room is its limit less what it holds that the kernel cannot reclaim before the
    OOM killer strikes: usage less the inactive page cache, as Docker and the kubelet count a
    container's working set. v2 reads ``memory.max``, ``memory.current`` and ``memory.stat``'s
    ``inactive_file``; v1 ``memory.limit_in_bytes``, ``memory.usage_in_bytes`` and
    ``memory.stat``'s ``total_inactive_file`` and ``hierarchical_memory_limit`` (the limit of
    ancestors hidden from a container).
    """
    rooms = []
    for version, folder, top in _memory_cgroups(root):
        for level in _ancestors(folder, top):
            room = _level_room(version, level, leaf=level == folder)
            if room is not None:
                rooms.append(room)
    return min(rooms) if rooms else None


def _memory_cgroups(root: str | None) -> list[tuple[int, str, str]]:
    """(version, folder of this process's cgroup, folder of the hierarchy's mount) for the
    v2 hierarchy and the v1 memory controller, from /proc/self/cgroup and mountinfo."""
    try:
        with open(_system_path("/proc/self/cgroup", root)) as handle:
            lines = handle.read().splitlines()
    except OSError:
        return []
    mounts = _cgroup_mounts(root)
    found = []
    for line in lines:
        number, _, rest = line.partition(":")
        controllers, _, path = rest.partition(":")
        if number == "0" and not controllers:
            version = 2
        elif "memory" in controllers.split(","):
            version = 1
        else:
            continue
        default = "/sys/fs/cgroup" if version == 2 else "/sys/fs/cgroup/memory"
        mount_root, mount_point = mounts.get(version, ("/", default))
        inside = path[len(mount_root) :] if path.startswith(mount_root) else path
        top = _system_path(mount_point, root)
        folder = os.path.join(top, inside.lstrip("/"))
        found.append((version, folder if os.path.isdir(folder) else top, top))
    return found


def _cgroup_mounts(root: str | None) -> dict[int, tuple[str, str]]:
    """{version: (root of the hierarchy mounted, mount point)} from /proc/self/mountinfo."""
    mounts: dict[int, tuple[str, str]] = {}
    try:
        with open(_system_path("/proc/self/mountinfo", root)) as handle:
            lines = handle.read().splitlines()
    except OSError:
        return mounts
    for (
        line
    ) in lines:  # ID PARENT MAJ:MIN ROOT MOUNT-POINT OPTIONS [OPTIONAL...] - TYPE SOURCE SUPER
        fields = [f.replace("\\040", " ") for f in line.split()]
        dash = fields.index("-", 6) if "-" in fields[6:] else len(fields)
        after = fields[dash + 1 :] + ["", "", ""]
        kind, super_options = after[0], after[2]
        if kind == "cgroup2":
            mounts.setdefault(2, (fields[3], fields[4]))
        elif kind == "cgroup" and "memory" in super_options.split(","):
            mounts.setdefault(1, (fields[3], fields[4]))
    return mounts


def _ancestors(folder: str, top: str) -> list[str]:
    """``folder`` and its parents up to ``top``, the mount point, included."""
    chain, top = [folder], os.path.normpath(top)
    while os.path.normpath(chain[-1]) != top and os.path.dirname(chain[-1]) != chain[-1]:
        chain.append(os.path.dirname(os.path.normpath(chain[-1])))
    return chain


def _level_room(version: int, folder: str, leaf: bool) -> int | None:
    """Bytes left under one cgroup's own limit (see :func:`_cgroup_room`); None: no limit."""
    if version == 2:
        limit = _read_number(os.path.join(folder, "memory.max"))
        usage = _read_number(os.path.join(folder, "memory.current"))
    else:
        limit = _read_number(os.path.join(folder, "memory.limit_in_bytes"))
        usage = _read_number(os.path.join(folder, "memory.usage_in_bytes"))
    stat = _read_stat(os.path.join(folder, "memory.stat"))
    hierarchical = stat.get("hierarchical_memory_limit") if version == 1 and leaf else None
    if hierarchical is not None:
        limit = hierarchical if limit is None else min(limit, hierarchical)
    if limit is None or usage is None or limit >= _NO_LIMIT:
        return None
    cache = stat.get("inactive_file" if version == 2 else "total_inactive_file", 0)
    return max(limit - max(usage - cache, 0), 0)


def _read_number(path: str) -> int | None:
    """The integer in a cgroup file; None for ``max`` (no limit) or a file that is not there."""
    try:
        with open(path) as handle:
            text = handle.read().strip()
        return None if text == "max" else int(text)
    except (OSError, ValueError):
        return None


def _read_stat(path: str) -> dict[str, int]:
    try:
        with open(path) as handle:
            pairs = (line.split() for line in handle)
            return {p[0]: int(p[1]) for p in pairs if len(p) == 2 and p[1].isdigit()}
    except OSError:
        return {}


def _address_space_room() -> int | None:
    """Bytes left under ``ulimit -v`` (RLIMIT_AS), less the address space already mapped."""
    try:
        import resource

        limit = resource.getrlimit(resource.RLIMIT_AS)[0]
        if limit == resource.RLIM_INFINITY:
            return None
        with open("/proc/self/status") as handle:
            size = next(
                int(line.split()[1]) * 1024 for line in handle if line.startswith("VmSize:")
            )
        return max(limit - size, 0)
    except (ImportError, OSError, ValueError, StopIteration):
        return None


def available() -> tuple[int | None, bool]:
    """(bytes a run may use, True when they come from ``ENVCONV_MEMORY_LIMIT``): the variable,
    else USABLE_SHARE of what the system reports available; None when it says nothing (see
    the module docstring)."""
    text = os.environ.get(LIMIT_VARIABLE, "").strip()
    if text:
        return _parse_bytes(text), True
    found = [
        v for v in (_meminfo_available(), _cgroup_room(), _address_space_room()) if v is not None
    ]
    if not found:
        try:
            found = [os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")]
        except (AttributeError, ValueError, OSError):
            return None, False
    return int(USABLE_SHARE * min(found)), False


def format_bytes(count: float) -> str:
    """``count`` bytes as a short figure: 512 KB, 21.4 MB, 1.2 GB."""
    for unit in ("KB", "MB", "GB"):
        count /= 1024
        if count < 1000 or unit == "GB":
            return f"{count:.3g} {unit}" if count < 100 else f"{count:.0f} {unit}"
    return f"{count:.0f} GB"


def check(need: int, what: str, held: int = 0, advice: str = "lower --size") -> None:
    """Raise :class:`MemoryLimitError` when ``need`` bytes (``held`` of them already
    allocated) exceed the memory available; ``what`` names the work (``"this conversion"``)."""
    free, from_variable = available()
    if free is None:
        return
    room = free if from_variable else free + held
    if need <= room:
        return
    source = f" ({LIMIT_VARIABLE})" if from_variable else ""
    raise MemoryLimitError(f"{what} needs about {format_bytes(need)} of memory and "
                           f"{format_bytes(room)} is available{source}; {advice}")  # fmt: skip
