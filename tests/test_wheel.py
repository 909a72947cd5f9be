"""The wheel: ``pip wheel .`` builds one that installs into a fresh venv and converts a file.

The fresh venv sees this test venv's packages (numpy, OpenImageIO…) through a ``.pth`` line, so
the wheel installs with ``--no-deps`` and no network; envconv itself comes only from the wheel.
The build reuses the build folder of the development install, so this takes seconds when the
core is already compiled.
"""

from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
import venv
from pathlib import Path

import numpy as np
import pytest
from conftest import write_plain

import envconv

ROOT = Path(__file__).resolve().parent.parent


def _run(*args, **kwargs):
    done = subprocess.run(args, capture_output=True, text=True, timeout=600, **kwargs)
    assert done.returncode == 0, f"{args[:3]} failed:\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}"
    return done


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    if not (ROOT / "pyproject.toml").exists():
        pytest.skip("not run from a source checkout")
    out = tmp_path_factory.mktemp("wheel")
    _run(sys.executable, "-m", "pip", "wheel", str(ROOT), "--no-deps", "--no-build-isolation",
         "--quiet", "-w", str(out))  # fmt: skip
    wheels = list(out.glob("envconv-*.whl"))
    assert len(wheels) == 1, wheels
    return wheels[0]


def test_the_wheel_installs_into_a_fresh_venv_and_converts(wheel, tmp_path):
    env_dir = tmp_path / "venv"
    # No pip of its own (ensurepip: 5 s): this venv's pip installs into it (``--python``).
    venv.create(env_dir, with_pip=False)
    python = env_dir / "bin" / "python"
    purelib = _run(str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))")
    site = Path(purelib.stdout.strip())
    (site / "test-venv.pth").write_text(sysconfig.get_path("purelib") + "\n")
    _run(sys.executable, "-m", "pip", "--python", str(python), "install", "--quiet", "--no-deps",
         "--no-index", str(wheel))  # fmt: skip
    # envconv comes from the wheel, with its compiled core, not from the checkout.
    where = _run(str(python), "-c", "import envconv, envconv._core as c; print(envconv.__file__, c.__file__)",
                 cwd=tmp_path)  # fmt: skip
    assert all(str(site) in p for p in where.stdout.split()), where.stdout
    src = tmp_path / "sky.exr"
    rows = np.linspace(0.0, 4.0, 16, dtype=np.float32)
    write_plain(src, np.repeat(np.repeat(rows[:, None, None], 32, axis=1), 3, axis=2))
    out = tmp_path / "cross.exr"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = _run(str(env_dir / "bin" / "envconv"), "convert", str(src), str(out), "--to",
                "cube-vcross", "--size", "8", cwd=tmp_path, env=env)  # fmt: skip
    assert done.stdout.strip() == str(out)
    back = envconv.read(out)
    assert back.layout.name == "cube-vcross" and back.pixels.shape == (32, 24, 3)
    # The mean radiance of the faces matches the source's solid-angle mean (a smooth map).
    from envconv.layouts.geometry import pixel_solid_angles

    omega = pixel_solid_angles("cube-vcross", 8)
    got = (back.pixels[..., 0] * omega).sum() / omega.sum()
    omega_in = pixel_solid_angles("latlong", 16)
    want = (np.repeat(rows[:, None], 32, axis=1) * omega_in).sum() / omega_in.sum()
    assert abs(got - want) < 0.02 * want
