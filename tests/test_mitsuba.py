"""The ``mitsuba`` convention against Mitsuba 3 itself (docs/conventions.md, "Mitsuba 3").

Mitsuba's ``envmap`` emitter (``src/emitters/envmap.cpp``) looks up direction d at
u = atan2(d_x, −d_z)/2π (mod 1), v = acos(d_y)/π, and interpolates its texels at
(u·W − 0.5, v·(H − 1)): columns at pixel centres, rows on the edges (row 0 on +Y, row H − 1 on
−Y). Its frame is envconv's (Y up, right-handed, u = 0.5 at +Z, u = 0.25 at +X). The emitter
is evaluated here (``scalar_rgb``) for known directions on direction-coded maps: each texel
holds its own (u, v), v in R and u as the phase of (G, B) − 2.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import run_cli

import envconv
from envconv.errors import UsageError
from envconv.layouts.grids import sample_positions

mi = pytest.importorskip("mitsuba")
mi.set_variant("scalar_rgb")

H, W = 64, 128
LATS = (0.0, 30.0, -45.0, 60.0, 80.0, -80.0, 85.0, -87.0)
LONS = (0.0, 37.0, 90.0, -120.0, 179.0)


def coded(grid="centres"):
    """(H, W, 3) float32: each sample's own (u, v) on ``grid``."""
    u, v = sample_positions(grid, W, H)
    px = np.empty((H, W, 3), np.float32)
    px[..., 0] = v[:, None]
    px[..., 1] = 2 + np.cos(2 * np.pi * u)[None, :]
    px[..., 2] = 2 + np.sin(2 * np.pi * u)[None, :]
    return px


def direction(lat_deg, lon_deg):
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    d = np.array([np.sin(lon) * np.cos(lat), np.sin(lat), np.cos(lon) * np.cos(lat)])
    return d, (0.5 - lon / (2 * np.pi)) % 1.0, 0.5 - lat / np.pi


def mitsuba_eval(emitter, d):
    """The emitter's radiance arriving from direction ``d`` (a ray leaving along d)."""
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*(-np.asarray(d)))
    return np.array(emitter.eval(si), np.float64)


def texel_errors(emitter):
    errors = []
    for lat in LATS:
        for lon in LONS:
            d, u, v = direction(lat, lon)
            r = mitsuba_eval(emitter, d)
            u_got = (np.arctan2(r[2] - 2, r[1] - 2) / (2 * np.pi)) % 1.0
            errors.append((((u_got - u + 0.5) % 1.0 - 0.5) * W, (r[0] - v) * H))
    return np.abs(np.array(errors))


def test_mitsuba_reads_a_mitsuba_preset_file_within_a_tenth_of_a_texel(tmp_path):
    sky = envconv.EnvMap(coded(), "latlong")
    out = envconv.convert(sky, "latlong", size=H, out_convention="mitsuba")
    path = tmp_path / "mitsuba.exr"
    envconv.write(out, path, bit_depth="float")
    emitter = mi.load_dict({"type": "envmap", "filename": str(path)})
    du, dv = texel_errors(emitter).max(axis=0)
    assert du < 0.1 and dv < 0.1, (du, dv)
    assert envconv.read(path).metadata["envconv:grid"] == "edge-rows"


def test_mitsuba_reads_envconvs_own_grid_up_to_half_a_row_off(tmp_path):
    """Without the preset: rows off by |lat|/180 of a row (0.44 at 80°); columns in place."""
    emitter = mi.load_dict({"type": "envmap", "bitmap": mi.Bitmap(coded())})
    errors = texel_errors(emitter).reshape(len(LATS), len(LONS), 2)
    assert errors[..., 0].max() < 0.01  # the frame and the columns are envconv's
    assert errors[LATS.index(80.0), :, 1] == pytest.approx(80 / 180, abs=0.01)


def test_envconv_reads_a_mitsuba_map_as_mitsuba_does():
    """A map on Mitsuba's grid, read with --in-convention mitsuba: each envconv pixel is what
    Mitsuba's emitter gives at that pixel's centre direction (to the interpolation error)."""
    rng = np.random.default_rng(3)
    smooth = np.cumsum(np.cumsum(rng.random((H, W, 3)), axis=0), axis=1)
    smooth = (smooth / smooth.max() + 0.1).astype(np.float32)  # gently varying, positive
    emitter = mi.load_dict({"type": "envmap", "bitmap": mi.Bitmap(smooth)})
    ours = envconv.convert(envconv.EnvMap(smooth, "latlong"), "latlong", size=H,
                           in_convention="mitsuba").pixels  # fmt: skip
    plain = envconv.convert(envconv.EnvMap(smooth, "latlong"), "latlong", size=H).pixels
    worst = worst_plain = 0.0
    for j in (0, 2, 9, 31, 50, 61, 63):
        for i in (0, 30, 64, 127):
            d, _, _ = direction(90 - 180 * (j + 0.5) / H, 180 - 360 * (i + 0.5) / W)
            truth = mitsuba_eval(emitter, d)
            worst = max(worst, np.abs(ours[j, i] - truth).max())
            worst_plain = max(worst_plain, np.abs(plain[j, i] - truth).max())
    assert worst < 1e-5 < 1e-3 < worst_plain


def test_a_tagged_mitsuba_file_reads_back_on_envconvs_grid(tmp_path):
    """The envconv:grid tag says where the samples are: read back without the preset. (The
    tag travels as an EXR attribute, and in ImageDescription in a TIFF file.)"""
    sky = envconv.EnvMap(coded(), "latlong")
    mitsuba = envconv.convert(sky, "latlong", size=H, out_convention="mitsuba")
    for name in ("m.tif", "m.exr"):
        envconv.write(mitsuba, tmp_path / name)
        read = envconv.read(tmp_path / name)
        assert read.metadata["envconv:grid"] == "edge-rows"
        back = envconv.convert(read, "latlong", size=H)
        assert "envconv:grid" not in back.metadata
        as_preset = envconv.convert(read, "latlong", size=H, in_convention="mitsuba")
        np.testing.assert_array_equal(back.pixels, as_preset.pixels)
        as_ours = envconv.convert(read, "latlong", size=H, in_convention="envconv")
        assert np.abs(as_ours.pixels - back.pixels).max() > 0.003
    # Rows in place after the round trip (float EXR), away from the pole rows.
    assert np.abs(back.pixels[2:-2, :, 0] - sky.pixels[2:-2, :, 0]).max() * H < 0.05


def test_mitsuba_preset_limits():
    sky = envconv.EnvMap(coded(), "latlong")
    with pytest.raises(UsageError, match="mips"):
        envconv.convert(sky, "latlong", size=H, out_convention="mitsuba", mips=True)
    with pytest.raises(UsageError, match="guard"):
        envconv.convert(sky, "latlong", size=H, out_convention="mitsuba", guard=2)
    with pytest.raises(envconv.errors.LayoutError, match="applies to latlong"):
        envconv.convert(sky, "cube-vcross", size=16, out_convention="mitsuba")


def test_cli_out_convention_mitsuba(tmp_path):
    src, out = tmp_path / "sky.exr", tmp_path / "mitsuba.exr"
    envconv.write(envconv.EnvMap(coded(), "latlong"), src, bit_depth="float")
    args = ["convert", src, out, "--to", "latlong", "--out-convention", "mitsuba"]
    result = run_cli(args)
    assert result.exit_code == 0, result.output
    emitter = mi.load_dict({"type": "envmap", "filename": str(out)})
    assert texel_errors(emitter).max() < 0.1
    args[2] = tmp_path / "mips.exr"
    bad = run_cli([*args, "--mips"])
    assert bad.exit_code == 2 and "mips" in bad.output and "Traceback" not in bad.output
