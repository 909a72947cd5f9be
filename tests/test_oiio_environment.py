"""OpenImageIO's TextureSystem reads the lat-longs envconv writes in place (io/exr_header.py,
io/specs.py; docs/conventions.md, "What each reader assumes").

The truth is OIIO itself: ``TextureSystem.environment()`` looked up at known directions. The
maps are direction-coded: each texel holds its own centre's position, v in R and u as a phase
(G, B) = 2 + (cos 2πu, sin 2πu), so that a bilinear lookup returns the (u, v) that OIIO
sampled at, and the error is measured in texels. OIIO reads an OpenEXR ``envmap`` as samples
on the edges (``oiio:sampleborder`` 1) unless the header says otherwise: without envconv's
``oiio:sampleborder = 0``, rows are off by 0.44 of a row at 80° latitude on 64 rows.
"""

from __future__ import annotations

import numpy as np
import OpenEXR
import OpenImageIO as oiio
import pytest
from conftest import write_plain

import envconv
from envconv.io import exr_header, specs
from envconv.layouts.grids import sample_positions

H, W = 64, 128
LATS = (0.0, 30.0, -45.0, 60.0, 80.0, -80.0, 85.0, -87.0)
LONS = (0.0, 37.0, 90.0, -120.0, 179.0)


def coded(grid="centres", width=W, height=H):
    """(H, W, 3) float32: each sample's own (u, v) on ``grid`` (see the module docstring)."""
    u, v = sample_positions(grid, width, height)
    px = np.empty((height, width, 3), np.float32)
    px[..., 0] = v[:, None]
    px[..., 1] = 2 + np.cos(2 * np.pi * u)[None, :]
    px[..., 2] = 2 + np.sin(2 * np.pi * u)[None, :]
    return px


def direction(lat_deg, lon_deg):
    """envconv's (and OpenEXR's) direction of a latitude and longitude, and its (u, v)."""
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    d = (np.sin(lon) * np.cos(lat), np.sin(lat), np.cos(lon) * np.cos(lat))
    return d, (0.5 - lon / (2 * np.pi)) % 1.0, 0.5 - lat / np.pi


def oiio_lookup(path, d, channels=3):
    """OIIO's ``environment()`` at direction ``d``: bilinear, level 0, no blur."""
    ts = oiio.TextureSystem(False)
    opt = oiio.TextureOpt()
    opt.interpmode = oiio.InterpMode.Bilinear
    opt.mipmode = oiio.MipMode.NoMIP
    try:
        result = ts.environment(str(path), opt, tuple(d), (0, 0, 0), (0, 0, 0), channels)
        assert not ts.has_error(), ts.geterror()
    finally:
        ts.close_all()
    return np.asarray(result, np.float64)


def texel_errors(path, width=W, height=H):
    """(du, dv) in texels of OIIO's lookups of a direction-coded file, for every LATS × LONS."""
    errors = []
    for lat in LATS:
        for lon in LONS:
            d, u, v = direction(lat, lon)
            r = oiio_lookup(path, d)
            u_got = (np.arctan2(r[2] - 2, r[1] - 2) / (2 * np.pi)) % 1.0
            errors.append((((u_got - u + 0.5) % 1.0 - 0.5) * width, (r[0] - v) * height))
    return np.abs(np.array(errors))


@pytest.mark.parametrize(
    "name, kwargs",
    [
        ("sky.exr", {"bit_depth": "float"}),
        ("sky_half.exr", {"bit_depth": "half"}),
        ("sky.tif", {"bit_depth": "float"}),
    ],
)
def test_oiio_places_envconv_latlongs_within_a_tenth_of_a_texel(tmp_path, name, kwargs):
    path = tmp_path / name
    envconv.write(envconv.EnvMap(coded(), "latlong"), path, **kwargs)
    du, dv = texel_errors(path).max(axis=0)
    assert du < 0.1 and dv < 0.1, (du, dv)


def test_oiio_places_a_mip_mapped_latlong_within_a_tenth_of_a_texel(tmp_path):
    """A tiled MIP-mapped EXR (ROUND_DOWN), whose header OIIO wrote differently: level 0."""
    env = envconv.convert(envconv.EnvMap(coded(), "latlong"), "latlong", size=H, mips=True)
    path = tmp_path / "mips.exr"
    envconv.write(env, path, bit_depth="float")
    du, dv = texel_errors(path).max(axis=0)
    assert du < 0.1 and dv < 0.1, (du, dv)


def test_without_the_stored_attribute_oiio_is_half_a_row_off(tmp_path, monkeypatch):
    """What the attribute fixes: the same file without it reads 0.44 of a row off at 80°."""
    monkeypatch.setattr(specs, "PLACEHOLDER", "envconv:no-sampleborder")
    path = tmp_path / "plain.exr"
    envconv.write(envconv.EnvMap(coded(), "latlong"), path, bit_depth="float")
    errors = texel_errors(path).reshape(len(LATS), len(LONS), 2)
    # Row j read at v = j/(H - 1): off by 0.5 - v rows, i.e. |lat|/180 of a row.
    assert errors[LATS.index(80.0), :, 1] == pytest.approx(80 / 180, abs=0.01)
    assert errors[LATS.index(0.0), :, 1].max() < 0.01


def test_exr_header_holds_oiio_sampleborder_zero(tmp_path):
    for layout, size in (("latlong", 8), ("cube-exr", 4)):
        path = tmp_path / f"{layout}.exr"
        shape = envconv.layouts.get_layout(layout).image_size(size, 0)[::-1]
        envconv.write(envconv.EnvMap(np.ones((*shape, 3), np.float32), layout), path)
        header = OpenEXR.File(str(path), header_only=True).header()
        assert header["oiio:sampleborder"] == 0 and "envmap" in header
        assert exr_header.PLACEHOLDER not in header


def test_formats_without_metadata_are_read_at_pixel_centres(tmp_path):
    """Radiance HDR and PNG carry no envmap attribute: OIIO's default (pixel centres, y up).
    Their codes are too coarse to decode a position, so OIIO's lookup is compared with the
    bilinear interpolation of the stored values at envconv's position of the direction."""
    for name in ("sky.hdr", "sky.png"):
        path = tmp_path / name
        envconv.write(envconv.EnvMap(coded() / 3, "latlong"), path)
        stored = np.asarray(oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT), np.float64)
        for lat in LATS:
            for lon in LONS:
                d, u, v = direction(lat, lon)
                want = _bilinear(stored, u * W - 0.5, v * H - 0.5)
                np.testing.assert_allclose(oiio_lookup(path, d), want, atol=2e-4)


def _bilinear(px, x, y):
    """Bilinear tap of ``px`` at pixel coordinates (x, y): columns wrap, rows clamp."""
    x0, y0 = int(np.floor(x)), int(np.floor(y))
    fx, fy = x - x0, y - y0
    rows = [min(max(y0, 0), H - 1), min(max(y0 + 1, 0), H - 1)]
    cols = [x0 % W, (x0 + 1) % W]
    top = px[rows[0], cols[0]] * (1 - fx) + px[rows[0], cols[1]] * fx
    bottom = px[rows[1], cols[0]] * (1 - fx) + px[rows[1], cols[1]] * fx
    return top * (1 - fy) + bottom * fy


def test_openexr_edges_preset_writes_what_oiio_reads_as_an_envmap(tmp_path):
    """``--out-convention openexr-edges``: samples on the edges, OIIO's sampleborder reading."""
    env = envconv.convert(envconv.EnvMap(coded(), "latlong"), "latlong", size=H,
                          out_convention="openexr-edges")  # fmt: skip
    path = tmp_path / "edges.exr"
    envconv.write(env, path, bit_depth="float")
    header = OpenEXR.File(str(path), header_only=True).header()
    assert "envmap" in header and "oiio:sampleborder" not in header
    assert header["envconv:grid"] == "edges"
    du, dv = texel_errors(path).max(axis=0)
    assert du < 0.1 and dv < 0.1, (du, dv)


def test_envconv_reads_a_maketx_envlatl_file_as_oiio_does(tmp_path):
    """OIIO's own maketx (ImageBufAlgo.make_texture, MakeTxEnvLatl) declares its input's samples
    on the edges. envconv reads the file onto pixel centres: each of its pixels equals OIIO's
    environment() at that pixel's centre direction."""
    source = oiio.ImageBuf(np.ascontiguousarray(coded("edges")))
    path = tmp_path / "maketx.exr"
    assert oiio.ImageBufAlgo.make_texture(oiio.MakeTxEnvLatl, source, str(path)), oiio.geterror()
    assert OpenEXR.File(str(path), header_only=True).header()["envmap"] is not None
    env = envconv.read(path)
    np.testing.assert_allclose(env.pixels[..., 0], coded()[..., 0], atol=1e-5)  # v: exact
    for j in (0, 3, 20, 32, 60, 63):
        for i in (0, 17, 64, 127):
            u, v = (i + 0.5) / W, (j + 0.5) / H
            d, _, _ = direction(90 - 180 * v, 180 - 360 * u)
            np.testing.assert_allclose(env.pixels[j, i], oiio_lookup(path, d), atol=2e-3)


def test_older_envconv_files_are_what_oiio_misplaced(tmp_path):
    """An envconv lat-long without the attribute (before it was stored): OIIO reads the
    envmap attribute as edges. envconv itself still reads it at pixel centres (its tag)."""
    path = tmp_path / "old.exr"
    tags = {"textureformat": "LatLong Environment", "envconv:layout": "latlong"}
    write_plain(path, coded(), tags)
    errors = texel_errors(path)
    assert errors[:, 1].max() > 0.4
    np.testing.assert_array_equal(envconv.read(path).pixels, coded())
