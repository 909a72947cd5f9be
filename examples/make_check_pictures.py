"""Make the pictures of docs/check-a-map.md with ``envconv preview``, ``convert --preview``
and ``envconv view`` (screenshot in headless Chromium, when one is installed).

Run from anywhere:  python examples/make_check_pictures.py [OUTDIR]

OUTDIR defaults to docs/img. The pictures are made by the commands the page documents, from
examples/data and the test pattern, so the page never drifts from the code.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

__all__ = ["main", "CHROMIUM_FLAGS"]

HERE = Path(__file__).resolve().parent
VENICE = HERE / "data" / "venice-latlong-512.exr"
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
                  "--enable-unsafe-swiftshader", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--no-first-run",
                  "--virtual-time-budget=5000"]  # fmt: skip


def envconv(*args: str) -> None:
    """Run one envconv command (the one beside this Python), stopping on failure."""
    exe = Path(sys.executable).with_name("envconv")
    subprocess.run([str(exe), *args], check=True, stdout=subprocess.DEVNULL)


def screenshot(page: Path, fragment: str, out: Path, size: str = "800,450") -> bool:
    """Screenshot ``page#fragment`` into ``out``; False when no Chromium is installed."""
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        print("no chromium: skipping the viewer picture", file=sys.stderr)
        return False
    with tempfile.TemporaryDirectory() as profile:
        subprocess.run([browser, *CHROMIUM_FLAGS, f"--user-data-dir={profile}",
                        f"--screenshot={out}", f"--window-size={size}",
                        f"file://{page}#{fragment}"], check=True, capture_output=True)  # fmt: skip
    return True


def main(outdir: Path) -> None:
    outdir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        # a contact sheet of a real map
        envconv("preview", str(VENICE), "-o", str(outdir / "check-sheet-venice.png"))
        # a convert with a tone-mapped preview beside it, and the same 8 bits clipped
        envconv("convert", str(VENICE), str(tmp / "cross.exr"), "--to", "cube-hcross",
                "--size", "128", "--preview", str(outdir / "check-preview-cross.png"))  # fmt: skip
        envconv("convert", str(VENICE), str(outdir / "check-clipped-cross.png"), "--to",
                "cube-hcross", "--size", "128", "--exposure", "-1")  # fmt: skip
        # a map mirrored by another tool, read as envconv's: the labels read backwards
        envconv("pattern", str(tmp / "mirrored.exr"), "--to", "latlong", "--size", "256",
                "--out-convention=-x,y,z")  # fmt: skip
        envconv(
            "preview", str(tmp / "mirrored.exr"), "-o", str(outdir / "check-sheet-mirrored.png")
        )
        # a lat-long written as Blender writes one, seen in Blender's axes
        envconv("pattern", str(tmp / "blender.exr"), "--to", "latlong", "--size", "256",
                "--out-convention", "blender")  # fmt: skip
        envconv("preview", str(tmp / "blender.exr"), "-o", str(outdir / "check-sheet-blender.png"),
                "--in-convention", "blender", "--convention", "blender")  # fmt: skip
        # the viewer page, looking towards -X with the horizon grid on
        envconv("view", str(VENICE), "-o", str(tmp / "venice.html"))
        screenshot(tmp / "venice.html", "view=-X&grid=1", outdir / "check-view-venice.png")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE.parent / "docs" / "img")
