"""Convention presets against the pixel → direction formulas of the tools themselves.

Every synthesiser below transliterates a formula of ../shared/reference/conventions-in-the-wild.md
(tool pixel → direction in the tool's frame, then the tool's frame → envconv's by the standard
map of envconv.layouts.conventions). A file filled that way with an analytic environment, read with the
tool's preset, must equal the same environment sampled through envconv's own geometry.
"""

from __future__ import annotations

import numpy as np
import ports
import pytest
from click.testing import CliRunner

import envconv
from envconv.cli.main import cli
from envconv.errors import LayoutError, UsageError
from envconv.layouts.conventions import (
    PRESETS,
    apply_remap,
    environment_axes,
    parse_axes,
    resolve_convention,
)
from envconv.layouts.geometry import pixel_directions
from envconv.layouts.rotation import rotation_matrix

NL = 16  # lat-long height
NC = 8  # cube face edge
ND = 64  # disk diameter

# Tool frame → envconv frame (module docstring of envconv.layouts.conventions).
RH = lambda d: d  # noqa: E731
LH = lambda d: d * [-1.0, 1.0, 1.0]  # noqa: E731  Unity, cmft, D3D
BLENDER = lambda d: np.stack([d[..., 0], d[..., 2], -d[..., 1]], -1)  # noqa: E731
UNREAL = lambda d: np.stack([-d[..., 1], d[..., 2], d[..., 0]], -1)  # noqa: E731
FFMPEG = lambda d: d * [1.0, -1.0, -1.0]  # noqa: E731
# pbrt-v4 reads a lat-long at (atan2(y, x)/2π, acos(z)/π) (imgtool makeequiarea); by
# docs/geometry.md's lat-long formulas that point is (e_y, e_z, −e_x) (tests/test_octahedral.py).
PBRT = lambda e: np.stack([e[..., 1], e[..., 2], -e[..., 0]], -1)  # noqa: E731


def env(w):
    """Direction-coded, asymmetric analytic environment (RGB)."""
    w = np.asarray(w, np.float64)
    x, y, z = w[..., 0], w[..., 1], w[..., 2]
    return np.stack([0.5 + 0.5 * x, 0.5 + 0.4 * y + 0.1 * x * z, 0.5 + 0.45 * z - 0.05 * y], -1)


def _uv(width, height):
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    return np.meshgrid(u, v)


def _unit(d):
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


# ---- lat-long formulas --------------------------------------------------------------------------
def latlong_blender(n):
    u, v = _uv(2 * n, n)
    phi, theta = -2 * np.pi * u + np.pi, np.pi * v
    d = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)
    return BLENDER(d)


def latlong_unity(n):
    u, v = _uv(2 * n, n)
    phi, theta = 2 * np.pi * (0.5 - u), np.pi * v
    d = np.stack([np.sin(theta) * np.cos(phi), np.cos(theta), np.sin(theta) * np.sin(phi)], -1)
    return LH(d)


def latlong_unreal(n):
    u, v = _uv(2 * n, n)
    theta, phi = np.pi * (2 * u - 1), np.pi * v
    d = np.stack([np.sin(phi) * np.sin(theta), -np.sin(phi) * np.cos(theta), np.cos(phi)], -1)
    return UNREAL(d)


def latlong_skylibs(n):
    u, v = _uv(2 * n, n)
    theta, phi = np.pi * (2 * u - 1), np.pi * v
    return np.stack([np.sin(phi) * np.sin(theta), np.cos(phi), -np.sin(phi) * np.cos(theta)], -1)


def latlong_ffmpeg(n):
    u, v = _uv(2 * n, n)
    phi, theta = (2 * u - 1) * np.pi, (2 * v - 1) * np.pi / 2  # inverse of xyz_to_equirect
    d = np.stack([np.cos(theta) * np.sin(phi), np.sin(theta), np.cos(theta) * np.cos(phi)], -1)
    return FFMPEG(d)


def latlong_cmft(n):
    u, v = _uv(2 * n, n)
    phi, theta = 2 * np.pi * u, np.pi * v
    d = np.stack([-np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)], -1)
    return LH(d)


def threejs_uv(w):
    """three.js ``equirectUv`` (src/renderers/shaders/ShaderChunk/common.glsl.js), then flipY
    (v = 1 is the image's top row): the (u, v) of the image, v downward, world direction w."""
    w = np.asarray(w, np.float64)
    u = np.arctan2(w[..., 2], w[..., 0]) / (2 * np.pi) + 0.5
    v = np.arcsin(np.clip(w[..., 1], -1, 1)) / np.pi + 0.5
    return u, 1.0 - v


def latlong_threejs(n):
    """Inverse of threejs_uv at the pixel centres."""
    u, v = _uv(2 * n, n)
    phi, lat = 2 * np.pi * (u - 0.5), np.pi * (0.5 - v)
    return np.stack([np.cos(lat) * np.cos(phi), np.sin(lat), np.cos(lat) * np.sin(phi)], -1)


def latlong_openexr(n):
    u, v = _uv(2 * n, n)
    lon, lat = -2 * np.pi * (u - 0.5), -np.pi * (v - 0.5)
    return np.stack([np.sin(lon) * np.cos(lat), np.sin(lat), np.cos(lon) * np.cos(lat)], -1)


# ---- cube faces ---------------------------------------------------------------------------------
# GL/Vulkan/D3D table (§3), used by cmft and Unity: face texel (a, b) → direction in tool frame.
G_FACES = [
    lambda a, b: (1 + 0 * a, -b, -a),
    lambda a, b: (-1 + 0 * a, -b, a),
    lambda a, b: (a, 1 + 0 * a, b),
    lambda a, b: (a, -1 + 0 * a, -b),
    lambda a, b: (a, -b, 1 + 0 * a),
    lambda a, b: (-a, -b, -1 + 0 * a),
]
# OpenEXR ImfEnvmap closed form (§2.3), faces +X -X +Y -Y +Z -Z.
E_FACES = [
    lambda a, b: (1 + 0 * a, -b, a),
    lambda a, b: (-1 + 0 * a, -b, -a),
    lambda a, b: (a, 1 + 0 * a, -b),
    lambda a, b: (a, -1 + 0 * a, b),
    lambda a, b: (-a, -b, 1 + 0 * a),
    lambda a, b: (a, -b, -1 + 0 * a),
]
# ffmpeg v360 cube_to_xyz (§4.6), default order r l u d f b.
FF_FACES = [
    lambda a, b: (1 + 0 * a, b, -a),
    lambda a, b: (-1 + 0 * a, b, a),
    lambda a, b: (a, -1 + 0 * a, b),
    lambda a, b: (a, 1 + 0 * a, -b),
    lambda a, b: (a, b, 1 + 0 * a),
    lambda a, b: (-a, b, -1 + 0 * a),
]
# skylibs cube2world (§4.5), in cell-local coordinates (the 180° turn is in the formula).
SKYLIBS_CROSS = [
    (1, 0, lambda a, b: (a, 1 + 0 * a, -b)),
    (0, 1, lambda a, b: (-1 + 0 * a, -b, -a)),
    (1, 1, lambda a, b: (a, -b, -1 + 0 * a)),
    (2, 1, lambda a, b: (1 + 0 * a, -b, a)),
    (1, 2, lambda a, b: (a, -1 + 0 * a, b)),
    (1, 3, lambda a, b: (a, b, 1 + 0 * a)),
]
HDRSHOP_CROSS = [(2, 1, 0, 0), (0, 1, 1, 0), (1, 0, 2, 0), (1, 2, 3, 0), (1, 1, 4, 0), (1, 3, 5, 1)]
HCROSS = [(2, 1, 0, 0), (0, 1, 1, 0), (1, 0, 2, 0), (1, 2, 3, 0), (1, 1, 4, 0), (3, 1, 5, 0)]
HSTRIP = [(i, 0, i, 0) for i in range(6)]
VSTRIP = [(0, i, i, 0) for i in range(6)]


def mosaic(n, columns, rows, cells, frame):
    """Directions of a cube mosaic; cells are (col, row, fn(a, b)) in cell-local coordinates."""
    out = np.zeros((rows * n, columns * n, 3))
    a, b = _uv(n, n)
    a, b = 2 * a - 1, 2 * b - 1
    for col, row, fn in cells:
        out[row * n : (row + 1) * n, col * n : (col + 1) * n] = _unit(np.stack(fn(a, b), -1))
    return frame(out)


def faces_in(table, placement):
    """Cells of ``placement`` (col, row, face, turned) filled from a face table."""

    def cell(fn, turned):
        return (lambda a, b: fn(-a, -b)) if turned else fn

    return [(col, row, cell(table[face], turned)) for col, row, face, turned in placement]


def cube_file(placement, columns, rows, table, frame):
    return lambda n: mosaic(n, columns, rows, faces_in(table, placement), frame)


# ---- disks --------------------------------------------------------------------------------------
def _disk(n):
    u, v = _uv(n, n)
    return 2 * u - 1, 2 * v - 1  # a right, b down


def sphere_gl(n):
    a, b = _disk(n)
    y = -b
    nz = np.sqrt(np.clip(1 - a * a - y * y, 0, None))
    return np.stack([2 * nz * a, 2 * nz * y, 2 * nz * nz - 1], -1)


def sphere_skylibs(n):
    a, b = _disk(n)
    r = np.clip(np.hypot(a, b), 0, 1)
    theta, phi = np.arctan2(a, -b), 2 * np.arcsin(r)
    return np.stack([np.sin(phi) * np.sin(theta), np.sin(phi) * np.cos(theta), -np.cos(phi)], -1)


def sphere_ffmpeg(n):
    a, b = _disk(n)
    s = np.sqrt(np.clip(1 - a * a - b * b, 0, None))
    return FFMPEG(np.stack([2 * a * s, 2 * b * s, 1 - 2 * (a * a + b * b)], -1))


def sphere_blender(n):
    a, b = _disk(n)
    y = -b  # Blender's v_b is upward
    s = np.sqrt(np.clip(1 - a * a - y * y, 0, None))
    return BLENDER(np.stack([2 * a * s, 2 * (a * a + y * y) - 1, 2 * y * s], -1))


def angular_debevec(n):
    a, b = _disk(n)
    y = -b
    rho = np.maximum(np.hypot(a, y), 1e-12)
    theta = np.pi * rho
    return np.stack([a * np.sin(theta) / rho, y * np.sin(theta) / rho, np.cos(theta)], -1)


def angular_skylibs(n):
    a, b = _disk(n)
    az, phi = np.arctan2(-b, a), np.pi * np.hypot(a, b)
    return np.stack([np.sin(phi) * np.cos(az), np.sin(phi) * np.sin(az), -np.cos(phi)], -1)


# ---- octahedral squares (tests/ports.py: RTXGI's and pbrt-v4's own functions) -----------------
def octahedral_ddgi(n):
    """Texel (i, j) holds DDGIGetOctahedralDirection of its normalized coordinates."""
    i, j = np.meshgrid(np.arange(n), np.arange(n))
    return ports.ddgi_direction(*ports.ddgi_normalized_coordinates(i, j, n))


def equal_area_pbrt(n):
    u, v = _uv(n, n)
    return PBRT(ports.equal_area_square_to_sphere(np.stack([u, v], -1)))


# (preset, layout, synthesiser, N, exact): exact cases are pixel-aligned (no interpolation).
CASES = [
    ("blender", "latlong", latlong_blender, NL, True),
    ("unity", "latlong", latlong_unity, NL, True),
    ("unreal", "latlong", latlong_unreal, NL, True),
    ("skylibs", "latlong", latlong_skylibs, NL, True),
    ("ffmpeg", "latlong", latlong_ffmpeg, NL, True),
    ("cmft", "latlong", latlong_cmft, NL, True),
    ("openexr", "latlong", latlong_openexr, NL, True),
    ("threejs", "latlong", latlong_threejs, NL, True),
    # three.js samples a CubeTexture at (−x, y, z) (flipEnvMap = −1): GL faces, left-handed
    ("threejs", "cube-faces", cube_file(HSTRIP, 6, 1, G_FACES, LH), NC, True),
    ("threejs", "cube-vcross", cube_file(HDRSHOP_CROSS, 3, 4, G_FACES, LH), NC, True),
    ("cmft", "cube-vcross", cube_file(HDRSHOP_CROSS, 3, 4, G_FACES, LH), NC, True),
    ("cmft", "cube-hcross", cube_file(HCROSS, 4, 3, G_FACES, LH), NC, True),
    ("unity", "cube-vcross", cube_file(HDRSHOP_CROSS, 3, 4, G_FACES, LH), NC, True),
    ("unity", "cube-hstrip", cube_file(HSTRIP, 6, 1, G_FACES, LH), NC, True),
    ("unity", "cube-vstrip", cube_file(VSTRIP, 1, 6, G_FACES, LH), NC, True),
    ("unity", "cube-faces", cube_file(HSTRIP, 6, 1, G_FACES, LH), NC, True),
    ("skylibs", "cube-vcross", lambda n: mosaic(n, 3, 4, SKYLIBS_CROSS, RH), NC, True),
    ("ffmpeg", "cube-hstrip", cube_file(HSTRIP, 6, 1, FF_FACES, FFMPEG), NC, True),
    ("ffmpeg", "cube-vstrip", cube_file(VSTRIP, 1, 6, FF_FACES, FFMPEG), NC, True),
    ("openexr", "cube-faces", cube_file(HSTRIP, 6, 1, E_FACES, RH), NC, True),
    ("openexr", "cube-vstrip", cube_file(VSTRIP, 1, 6, E_FACES, RH), NC, True),
    ("blender", "sphere", sphere_blender, ND, True),
    ("probe-back", "sphere", sphere_gl, ND, True),
    ("probe-back", "angular", angular_debevec, ND, True),
    ("skylibs", "sphere", sphere_skylibs, ND, False),
    ("skylibs", "angular", angular_skylibs, ND, False),
    ("ffmpeg", "sphere", sphere_ffmpeg, ND, False),
    ("probe-forward", "sphere", sphere_skylibs, ND, False),
    ("probe-forward", "angular", angular_skylibs, ND, False),
    ("ddgi", "octahedral", octahedral_ddgi, ND, False),  # Y-up RH: centre +Z
    ("ddgi-z-up", "octahedral", lambda n: BLENDER(octahedral_ddgi(n)), NC, True),
    ("unreal", "octahedral", lambda n: UNREAL(octahedral_ddgi(n)), NC, True),
    ("pbrt", "equal-area", equal_area_pbrt, NC, True),
]
IDS = [f"{p}-{lay}" for p, lay, *_ in CASES]


def _compare_mask(layout, n, exact):
    """Pixels to compare: valid ones; for mirrored disks, away from the singular rim."""
    dirs, flags = pixel_directions(layout, n)
    mask = flags == 2
    if not exact:
        mask &= np.abs(dirs[..., 2]) < 0.8  # both this point and its mirror well inside
    return dirs, mask


def _tool_file(layout, synth, n):
    dirs = synth(n)
    _, flags = pixel_directions(layout, n)
    pixels = np.where((flags == 2)[..., None], env(dirs), 0.0)
    return envconv.EnvMap(pixels.astype(np.float32), layout)


@pytest.mark.parametrize("preset, layout, synth, n, exact", CASES, ids=IDS)
def test_preset_reads_tool_file(preset, layout, synth, n, exact):
    tool = _tool_file(layout, synth, n)
    ours, mask = _compare_mask(layout, n, exact)
    got = envconv.convert(
        tool, layout, size=n, samples=1, filter="bilinear", in_convention=preset
    ).pixels
    err = np.abs(got - env(ours))[mask].max()
    assert err < (1e-5 if exact else 2e-2)
    convention = resolve_convention(preset, layout)
    if not convention.is_identity:
        # The test discriminates: read without the preset, the same file is far off.
        plain = envconv.convert(tool, layout, size=n, samples=1, filter="bilinear").pixels
        assert np.abs(plain - env(ours))[mask].max() > 0.3


@pytest.mark.parametrize("preset, layout, synth, n, exact", CASES, ids=IDS)
def test_preset_writes_tool_file(preset, layout, synth, n, exact):
    ours_dirs, _ = pixel_directions(layout, n)
    ours = envconv.EnvMap(env(ours_dirs).astype(np.float32), layout)
    got = envconv.convert(
        ours, layout, size=n, samples=1, filter="bilinear", out_convention=preset
    ).pixels
    _, mask = _compare_mask(layout, n, exact)
    err = np.abs(got - env(synth(n)))[mask].max()
    assert err < (1e-5 if exact else 2e-2)


@pytest.mark.parametrize("preset, layout, synth, n, exact", CASES, ids=IDS)
def test_round_trip_through_preset(preset, layout, synth, n, exact):
    dirs, _ = pixel_directions(layout, n)
    ours = envconv.EnvMap(env(dirs).astype(np.float32), layout)
    theirs = envconv.convert(
        ours, layout, size=n, samples=1, filter="bilinear", out_convention=preset
    )
    back = envconv.convert(
        theirs, layout, size=n, samples=1, filter="bilinear", in_convention=preset
    ).pixels
    _, mask = _compare_mask(layout, n, exact)
    assert np.abs(back - env(dirs))[mask].max() < (1e-5 if exact else 3e-2)


def test_cross_layout_conversion_with_two_presets():
    """A Blender lat-long written as a Unity vertical cross: both tools' formulas agree."""
    blender = _tool_file("latlong", latlong_blender, 64)
    n = 12
    cross = envconv.convert(
        blender,
        "cube-vcross",
        size=n,
        samples=1,
        filter="bilinear",
        in_convention="blender",
        out_convention="unity",
    )
    _, flags = pixel_directions("cube-vcross", n)
    truth = env(cube_file(HDRSHOP_CROSS, 3, 4, G_FACES, LH)(n))
    assert np.abs(cross.pixels - truth)[flags == 2].max() < 1e-2


def test_conventions_compose_with_rotation():
    tool = _tool_file("latlong", latlong_skylibs, NL)
    both = envconv.convert(
        tool, "latlong", size=NL, samples=1, filter="bilinear", in_convention="skylibs", rotate="90"
    )
    dirs, _ = pixel_directions("latlong", NL)
    # The rotated environment is L(Rᵀ d).
    truth = env(dirs @ rotation_matrix(90, 0, 0))
    assert np.abs(both.pixels - truth).max() < 1e-5


def test_up_z_turns_z_up_world_to_y_up():
    """A cube whose raw directions are a Z-up world (sky on +Z) gets its sky at +Y."""
    dirs, _ = pixel_directions("cube-hcross", NC)
    sky = lambda t: env(t) + 3.0 * (t[..., 2:3] > 0.9)  # noqa: E731  bright zenith in Z-up
    zup = envconv.EnvMap(sky(dirs).astype(np.float32), "cube-hcross")
    got = envconv.convert(zup, "cube-hcross", size=NC, samples=1, filter="bilinear", up="z").pixels
    # envconv direction w is the Z-up direction t = (w_x, -w_z, w_y).
    truth = sky(np.stack([dirs[..., 0], -dirs[..., 2], dirs[..., 1]], -1))
    valid = pixel_directions("cube-hcross", NC)[1] == 2
    assert np.abs(got - truth)[valid].max() < 1e-5
    same = envconv.convert(
        zup, "cube-hcross", size=NC, samples=1, filter="bilinear", axes="x,z,-y"
    ).pixels
    np.testing.assert_array_equal(got, same)


def test_axes_as_convention_mirrors():
    dirs, _ = pixel_directions("latlong", NL)
    ours = envconv.EnvMap(env(dirs).astype(np.float32), "latlong")
    got = envconv.convert(
        ours, "latlong", size=NL, samples=1, filter="bilinear", in_convention="-x,y,z"
    ).pixels
    assert np.abs(got - env(dirs * [-1, 1, 1])).max() < 1e-5


def test_parse_axes_and_errors():
    np.testing.assert_array_equal(parse_axes("-x,z,y") @ [1, 2, 3], [-1, 3, 2])
    np.testing.assert_array_equal(environment_axes("z"), parse_axes("x,z,-y"))
    np.testing.assert_array_equal(environment_axes("y"), np.eye(3))
    for bad in ("x,y", "x,x,z", "x,y,w", "--x,y,z"):
        with pytest.raises(UsageError):
            parse_axes(bad)
    with pytest.raises(UsageError, match="did you mean blender"):
        resolve_convention("blendr", "latlong")
    with pytest.raises(LayoutError, match="applies to latlong"):
        resolve_convention("unreal", "cube-vcross")
    with pytest.raises(UsageError, match="orthogonal"):
        resolve_convention(np.ones((3, 3)), "latlong")
    with pytest.raises(UsageError):
        environment_axes("z", "x,y,z")


def test_every_preset_is_a_signed_permutation():
    for preset in PRESETS.values():
        for layout in preset.layouts:
            m = resolve_convention(preset.name, layout).matrix
            assert np.allclose(np.abs(m).sum(0), 1) and np.allclose(m @ m.T, np.eye(3))


def test_remap_inverse():
    rng = np.random.default_rng(1)
    pixels = rng.random((10, 60, 2)).astype(np.float32)  # cube-hstrip N=6 with G=2
    remap = resolve_convention("openexr", "cube-hstrip").remap
    there = apply_remap("cube-hstrip", pixels, 2, remap)
    assert not np.array_equal(there, pixels)
    np.testing.assert_array_equal(apply_remap("cube-hstrip", there, 2, remap, inverse=True), pixels)


def test_cli_conventions(tmp_path):
    src = tmp_path / "blender.exr"
    envconv.write(_tool_file("latlong", latlong_blender, NL), str(src))
    out = tmp_path / "ours.exr"
    runner = CliRunner()
    args = ["convert", str(src), str(out), "--to", "latlong", "--size", str(NL), "--samples", "1"]
    result = runner.invoke(cli, [*args, "--in-convention", "blender"])
    assert result.exit_code == 0, result.output
    dirs, _ = pixel_directions("latlong", NL)
    assert np.abs(envconv.read(str(out)).pixels - env(dirs)).max() < 1e-3
    result = runner.invoke(cli, [*args, "--axes=-x,z,y", "--up", "y"])
    assert result.exit_code == 0, result.output
    bad = runner.invoke(cli, [*args, "--in-convention", "blender", "--from", "sphere"])
    assert bad.exit_code != 0
    bad = runner.invoke(cli, [*args, "--out-convention", "nope"])
    assert bad.exit_code == 2 and "unknown convention" in bad.output  # a bad option value: usage
    assert "Traceback" not in bad.output


def test_out_axes_inverts_up_z():
    dirs, _ = pixel_directions("cube-vcross", NC)
    ours = envconv.EnvMap(env(dirs).astype(np.float32), "cube-vcross")
    zup = envconv.convert(
        ours, "cube-vcross", size=NC, samples=1, filter="bilinear", out_convention="x,z,-y"
    )
    back = envconv.convert(zup, "cube-vcross", size=NC, samples=1, filter="bilinear", up="z").pixels
    valid = pixel_directions("cube-vcross", NC)[1] == 2
    assert np.abs(back - env(dirs))[valid].max() < 1e-5


# docs/geometry.md, "Where known directions land": envconv's lat-long (u, v) of ±X, ±Z and q.
LATLONG_TABLE = {(1, 0, 0): (0.25, 0.5), (-1, 0, 0): (0.75, 0.5), (0, 0, 1): (0.5, 0.5),
                 (0, 0, -1): (0.0, 0.5), (0.48, 0.6, 0.64): (0.3976, 0.2952)}  # fmt: skip


def test_threejs_latlong_is_the_cited_formula_on_the_known_directions():
    """A three.js equirect pixel at the (u, v) its formula gives world w is the pixel where
    envconv's table puts direction e; the preset must say w = M·e for every table row."""
    m = resolve_convention("threejs", "latlong").matrix
    for e, (u_e, v_e) in LATLONG_TABLE.items():
        e = np.array(e, float) / np.linalg.norm(e)
        # the world direction three.js reads at envconv's (u_e, v_e): search the sphere
        grid = pixel_directions("latlong", 720)[0].reshape(-1, 3)
        u_t, v_t = threejs_uv(grid)
        du = np.abs((u_t - u_e + 0.5) % 1.0 - 0.5)
        w = grid[np.argmin(du + np.abs(v_t - v_e))]
        assert np.degrees(np.arccos(np.clip(w @ (m @ e), -1, 1))) < 0.5, (e, w, m @ e)
    # and the three.js image centre (0.5, 0.5) is +X, u = 0.75 is +Z (formula, by hand)
    assert np.allclose(threejs_uv([1.0, 0.0, 0.0]), (0.5, 0.5))
    assert np.allclose(threejs_uv([0.0, 0.0, 1.0]), (0.75, 0.5))
    assert np.allclose(m @ [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])  # envconv's centre is +Z
