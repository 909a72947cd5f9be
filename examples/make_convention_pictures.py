"""Make the pictures of docs/conventions.md with ``envconv pattern``.

Run from anywhere:  python examples/make_convention_pictures.py [OUTDIR]

Every picture is the labelled test pattern (envconv.views.pattern) drawn in one layout, either in
envconv's own convention or in another tool's (``--out-convention``), so the docs never drift
from the code. Each skybox face set (envconv.layouts.facesets) is drawn as its six files, side by side
in the program's own file order (``pattern-faceset-NAME.png``).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

__all__ = ["PICTURES", "FACE_SET_SIZE", "main", "face_set_strip"]

#: Face edge of the face-set pictures, and the gap between files, in pixels.
FACE_SET_SIZE, GAP = 64, 4

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
    ("envconv-eac", "eac", 80, None),
    ("envconv-fisheye", "fisheye", 200, None),
    ("envconv-perspective", "perspective", "240x180", None),
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
    from envconv.layouts.facesets import FACE_SETS

    for name in FACE_SETS:
        face_set_strip(name, out / f"pattern-faceset-{name}.png")


def face_set_strip(name: str, target: Path) -> None:
    """Draw face set ``name`` with ``envconv pattern`` and put its six files in one row."""
    import numpy as np
    import OpenImageIO as oiio

    from envconv.layouts.facesets import get_face_set

    n = FACE_SET_SIZE
    with tempfile.TemporaryDirectory() as tmp:
        template = str(Path(tmp) / "sky_{face}.png")
        subprocess.run([*_envconv(), "pattern", template, "--to", "cube-faces", "--size", str(n),
                        "--out-convention", name], check=True, stdout=subprocess.DEVNULL)  # fmt: skip
        order = get_face_set(name).order()
        strip = np.ones((n, len(order) * (n + GAP) - GAP, 3), np.uint8) * 255
        for k, face in enumerate(order):
            pixels = oiio.ImageBuf(template.replace("{face}", face)).get_pixels(oiio.UINT8)
            strip[:, k * (n + GAP) : k * (n + GAP) + n] = pixels[:, :, :3]
    spec = oiio.ImageSpec(strip.shape[1], strip.shape[0], 3, oiio.UINT8)
    out = oiio.ImageOutput.create(str(target))
    out.open(str(target), spec)
    out.write_image(strip)
    out.close()


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
