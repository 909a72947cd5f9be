"""Make the pictures of docs/conventions.md with ``envconv pattern``.

Run from anywhere:  python examples/make_convention_pictures.py [OUTDIR]

Every picture is the labelled test pattern (envconv.pattern) drawn in one layout, either in
envconv's own convention or in another tool's (``--out-convention``), so the docs never drift
from the code.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

__all__ = ["PICTURES", "main"]

#: (file stem, layout, size N, convention or None).
PICTURES = [
    ("envconv-latlong", "latlong", 160, None),
    ("envconv-cube-hcross", "cube-hcross", 80, None),
    ("envconv-cube-vcross", "cube-vcross", 80, None),
    ("envconv-cube-hstrip", "cube-hstrip", 64, None),
    ("envconv-cube-exr", "cube-exr", 64, None),
    ("envconv-sphere", "sphere", 200, None),
    ("envconv-angular", "angular", 200, None),
    ("envconv-octahedral", "octahedral", 200, None),
    ("envconv-equal-area", "equal-area", 200, None),
    ("blender-latlong", "latlong", 160, "blender"),
    ("skylibs-latlong", "latlong", 160, "skylibs"),
    ("skylibs-cube-vcross", "cube-vcross", 80, "skylibs"),
    ("skylibs-sphere", "sphere", 200, "skylibs"),
    ("skylibs-angular", "angular", 200, "skylibs"),
    ("unity-latlong", "latlong", 160, "unity"),
    ("unreal-latlong", "latlong", 160, "unreal"),
    ("ffmpeg-latlong", "latlong", 160, "ffmpeg"),
    ("ffmpeg-cube-hstrip", "cube-hstrip", 64, "ffmpeg"),
    ("openexr-cube-hstrip", "cube-hstrip", 64, "openexr"),
    ("pbrt-equal-area", "equal-area", 200, "pbrt"),
    ("ddgi-octahedral", "octahedral", 200, "ddgi"),
]


def _envconv() -> list[str]:
    script = Path(sys.executable).with_name("envconv")
    if script.exists():
        return [str(script)]
    found = shutil.which("envconv")
    if found is None:
        raise SystemExit("envconv is not installed (pip install -e .)")
    return [found]


def main(outdir: str | None = None) -> None:
    out = Path(outdir) if outdir else Path(__file__).resolve().parent.parent / "docs" / "img"
    out.mkdir(parents=True, exist_ok=True)
    for stem, layout, size, convention in PICTURES:
        args = [*_envconv(), "pattern", str(out / f"pattern-{stem}.png"), "--to", layout]
        args += ["--size", str(size)]
        if convention:
            args += ["--out-convention", convention]
        subprocess.run(args, check=True)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
