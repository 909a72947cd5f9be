"""Skybox face sets (envconv.layouts.facesets, --in-convention/--out-convention on {face} paths).

The truth here is not envconv's: for every face set a small function below follows the cited
program's own formula for where a file's pixel shows up in its world (Quake's ``st_to_vec`` and
``MakeSkyVec``, Sauerbraten's ``draw_envbox`` quads, the OpenGL cube-map table as each engine
samples it, Unreal's importer swizzle), then the program's world is taken to docs/geometry.md's by
the standard frame map. Six files rendered that way from an analytic sky must read as the
analytic sky, and envconv must write exactly those files. A seam check needs no formula of
envconv's at all: assembled by the program's formula, neighbouring pixels across each of the
12 cube edges of a real sky must agree about as well as neighbours inside a face.
"""

from __future__ import annotations

import os

import analytic
import naive
import numpy as np
import pytest
from conftest import run_cli, stderr_lines, write_plain

import envconv
from envconv.errors import ImageIOError, LayoutError, UsageError

N = 16
DATA = "/work/shared/data/park-latlong-512.exr"


def zup(v):
    """Z-up right-handed world (Quake, Sauerbraten) to envconv's: (x, y, z) -> (x, z, -y)."""
    return np.stack([v[0], v[2], -v[1]], -1)


# --- Quake II ref_gl/gl_warp.c (same tables in ioquake3 tr_sky.c, GoldSrc, Source) ----------
ST_TO_VEC = [(3, -1, 2), (-3, 1, 2), (1, 3, 2), (-1, -3, 2), (-2, -1, 3), (2, -1, -3)]
SUF = ("rt", "bk", "lf", "ft", "up", "dn")
SKYTEXORDER = (0, 2, 1, 3, 4, 5)


def quake_faces():
    def axis_fn(axis):
        def fn(a, b):
            # MakeSkyVec: b = (s, t, 1) permuted by st_to_vec; texcoord t' = 1 - (t + 1) / 2 is
            # 0 at the image's top row, so image-down b is -t.
            st1 = (a, -b, np.ones_like(a))
            return zup([st1[k - 1] if k > 0 else -st1[-k - 1] for k in ST_TO_VEC[axis]])

        return fn

    return {SUF[SKYTEXORDER[axis]]: axis_fn(axis) for axis in range(6)}


# --- Cube 2: Sauerbraten src/engine/sky.cpp draw_envbox (z1clip 0, z2clip 1), texture.cpp ----
SAUER_QUADS = {  # four (s, t, x, y, z) corners per sky[i]; sky[] in cubemapsides order
    "lf": [(0, 0, -1, -1, 1), (1, 0, -1, 1, 1), (1, 1, -1, 1, -1), (0, 1, -1, -1, -1)],
    "rt": [(1, 1, 1, -1, -1), (0, 1, 1, 1, -1), (0, 0, 1, 1, 1), (1, 0, 1, -1, 1)],
    "ft": [(1, 1, -1, -1, -1), (0, 1, 1, -1, -1), (0, 0, 1, -1, 1), (1, 0, -1, -1, 1)],
    "bk": [(1, 1, 1, 1, -1), (0, 1, -1, 1, -1), (0, 0, -1, 1, 1), (1, 0, 1, 1, 1)],
    "dn": [(0, 1, -1, 1, -1), (0, 0, 1, 1, -1), (1, 0, 1, -1, -1), (1, 1, -1, -1, -1)],
    "up": [(0, 1, 1, 1, 1), (0, 0, -1, 1, 1), (1, 0, -1, -1, 1), (1, 1, 1, -1, 1)],
}


def sauer_faces():
    def quad_fn(corners):
        at = {(c[0], c[1]): np.array(c[2:], float) for c in corners}

        def fn(a, b):
            s, t = (a + 1) / 2, (b + 1) / 2  # GL texcoords, t = 0 at the top row
            p = sum(at[(i, j)][:, None] * (s if i else 1 - s).ravel() * (t if j else 1 - t).ravel()
                    for i in (0, 1) for j in (0, 1))  # fmt: skip
            return zup(p.reshape((3, *np.shape(a))))

        return fn

    return {name: quad_fn(corners) for name, corners in SAUER_QUADS.items()}


# --- The OpenGL cube-map table (GL spec "cube map texture selection"), first row at t = 0 ----
GL = {
    "+X": lambda a, b, one: (one, -b, -a),
    "-X": lambda a, b, one: (-one, -b, a),
    "+Y": lambda a, b, one: (a, one, b),
    "-Y": lambda a, b, one: (a, -one, -b),
    "+Z": lambda a, b, one: (a, -b, one),
    "-Z": lambda a, b, one: (-a, -b, -one),
}


def gl_faces(names, to_world):
    """Six files given as GL faces +X -X +Y -Y +Z -Z, sampled with the vector c; ``to_world``
    turns c into envconv's world direction."""

    def face_fn(key):
        return lambda a, b: np.stack(to_world(GL[key](a, b, np.ones_like(a))), -1)

    return {name: face_fn(key) for name, key in zip(names, GL, strict=True)}


FORMULAS = {
    # docs/geometry.md: envconv's own table is the GL table read in the left-handed c = (-x, y, z).
    "envconv": lambda: gl_faces(
        ("px", "nx", "py", "ny", "pz", "nz"), lambda c: (-c[0], c[1], c[2])
    ),
    "quake": quake_faces,
    "cube2": sauer_faces,
    # three.js backgroundCube.glsl.js: textureCube(envMap, vec3(flipEnvMap * dir.x, dir.yz)),
    # flipEnvMap = -1 for a CubeTexture; its world is Y-up right-handed like envconv's.
    "threejs": lambda: gl_faces(
        ("px", "nx", "py", "ny", "pz", "nz"), lambda c: (-c[0], c[1], c[2])
    ),
    # Unity: Skybox/6 Sided Left [+X] ... Front [+Z]; Unity's world is left-handed Y-up.
    "unity-6sided": lambda: gl_faces(
        ("left", "right", "up", "down", "front", "back"), lambda c: (-c[0], c[1], c[2])
    ),  # fmt: skip
    # Godot Cubemap docs: X+ X- Y+ Y- Z+ Z- sampled with texture(cube, EYEDIR); Y-up RH world.
    "godot": lambda: gl_faces(("x+", "x-", "y+", "y-", "z+", "z-"), lambda c: c),
    # Unreal: the D3D face vector is the Z-up LH world vector L (CalcCubeFaceViewRotationMatrix
    # renders +X with up +Y; the long-lat importer swizzles L only to feed a Y-up formula);
    # L to envconv by (x, y, z) -> (-y, z, x).
    "unreal": lambda: gl_faces(
        ("posx", "negx", "posy", "negy", "posz", "negz"), lambda c: (-c[1], c[2], c[0])
    ),  # fmt: skip
}
SETS = list(FORMULAS)


def centres(n):
    a = (2 * np.arange(n) + 1) / n - 1
    aa, bb = np.meshgrid(a, a)
    return aa, bb


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def render_files(formulas, n, radiance=analytic.radiance):
    aa, bb = centres(n)
    return {name: radiance(unit(fn(aa, bb))).astype(np.float32) for name, fn in formulas.items()}


def envconv_truth(n, radiance=analytic.radiance):
    aa, bb = centres(n)
    faces = [radiance(naive.face_to_dir("cube", np.full_like(aa, k, dtype=int), aa, bb))
             for k in range(6)]  # fmt: skip
    return np.concatenate(faces, axis=1).astype(np.float32)


def write_files(tmp_path, images, ext="exr", stem="sky"):
    for name, image in images.items():
        write_plain(tmp_path / f"{stem}_{name}.{ext}", image)
    return str(tmp_path / f"{stem}_{{face}}.{ext}")


def read_files(template, names):
    import OpenImageIO as oiio

    out = {}
    for name in names:
        buf = oiio.ImageBuf(template.replace("{face}", name))
        out[name] = buf.get_pixels(oiio.FLOAT)[:, :, :3]
    return out


def scheme_name(name):
    return "quake" if name == "cube2" else name


def test_sauerbraten_and_quake_files_are_the_same_skybox():
    quake, sauer = render_files(quake_faces(), N), render_files(sauer_faces(), N)
    for name in quake:
        np.testing.assert_array_equal(quake[name], sauer[name])


@pytest.mark.parametrize("name", SETS)
def test_reading_program_files_gives_the_analytic_sky(tmp_path, name):
    template = write_files(tmp_path, render_files(FORMULAS[name](), N))
    truth = envconv_truth(N)
    for faces in (scheme_name(name), None):  # named, and found from the file names
        env = envconv.read(template, faces=faces)
        assert env.layout.name == "cube-faces" and env.size == N
        np.testing.assert_allclose(env.pixels[:, :, :3], truth, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("name", SETS)
def test_writing_gives_the_program_files(tmp_path, name):
    env = envconv.EnvMap(envconv_truth(N), "cube-faces")
    template = str(tmp_path / "out_{face}.exr")
    paths = envconv.write(env, template, bit_depth="float", faces=scheme_name(name))
    expected = render_files(FORMULAS[name](), N)
    assert sorted(os.path.basename(p) for p in paths) == sorted(f"out_{k}.exr" for k in expected)
    got = read_files(template, expected)
    for key, image in expected.items():
        np.testing.assert_allclose(got[key], image, rtol=1e-6, atol=1e-6, err_msg=key)


@pytest.mark.parametrize("name", list(envconv.layouts.facesets.FACE_SETS))
def test_labelled_pattern_round_trip(tmp_path, name):
    from envconv.views.pattern import render_pattern

    pattern = render_pattern("cube-faces", 24, samples=1)
    template = str(tmp_path / "p_{face}.exr")
    envconv.write(pattern, template, bit_depth="float", faces=name)
    back = envconv.read(template, faces=name)
    np.testing.assert_array_equal(back.pixels, pattern.pixels)


def test_guard_and_mip_levels_turn_with_the_face(tmp_path):
    """A guard-grown face and each MIP level turn about the same centre (Quake's up face)."""
    src = envconv.EnvMap(envconv_truth(16), "cube-faces")
    cube = envconv.convert(src, "cube-faces", size=16, guard=2, mips=3, samples=1)
    template = str(tmp_path / "g_{face}_{level}.exr")
    envconv.write(cube, template, bit_depth="float", faces="quake")
    for level in range(3):
        back = envconv.read(template.replace("{level}", str(level)), faces="quake")
        np.testing.assert_array_equal(back.pixels, cube.levels[level])


def edge_seams(images, formulas, n):
    """Per (file, edge): mean |difference| of log radiance across the edge and inside the face.

    The program's own formula assembles the cube: the point half a pixel past an edge pixel,
    on the face plane extended, is looked up on whichever face the formula puts it.
    """
    mats = {}
    for name, fn in formulas.items():
        e = [fn(np.array([x]), np.array([y]))[0] for x, y in ((0.0, 0.0), (1.0, 0.0), (0.0, 1.0))]
        mats[name] = np.column_stack([e[1] - e[0], e[2] - e[0], e[0]])  # dir = M (a, b, 1)
    logs = {k: np.log1p(np.clip(v, 0, None)).mean(axis=2) for k, v in images.items()}
    centre = (2 * np.arange(n) + 1) / n - 1
    past = 1 + 1.0 / n
    result = {}
    for name, m in mats.items():
        for edge, (a, b, inner) in {
            "right": (np.full(n, past), centre, (slice(None), n - 1, n - 2)),
            "left": (np.full(n, -past), centre, (slice(None), 0, 1)),
            "bottom": (centre, np.full(n, past), (n - 1, slice(None), n - 2)),
            "top": (centre, np.full(n, -past), (0, slice(None), 1)),
        }.items():
            dirs = (m @ np.stack([a, b, np.ones(n)])).T
            across = np.empty(n)
            for k, d in enumerate(dirs):
                for other, mo in mats.items():
                    v = mo.T @ d  # signed permutation: inverse is the transpose
                    if other != name and v[2] > 0 and abs(v[0]) <= v[2] and abs(v[1]) <= v[2]:
                        i = min(int((v[0] / v[2] + 1) / 2 * n), n - 1)
                        j = min(int((v[1] / v[2] + 1) / 2 * n), n - 1)
                        across[k] = logs[other][j, i]
                        break
                else:
                    raise AssertionError(f"{name} {edge}: no face across the edge")
            img = logs[name]
            if isinstance(inner[0], slice):  # a column edge
                own, inside = img[:, inner[1]], img[:, inner[2]]
            else:
                own, inside = img[inner[0], :], img[inner[2], :]
            result[(name, edge)] = (np.abs(own - across).mean(), np.abs(own - inside).mean())
    return result


@pytest.fixture(scope="module")
def real_cube():
    sky = envconv.read(DATA)
    return envconv.convert(sky, "cube-faces", size=48)


@pytest.mark.parametrize("name", SETS)
def test_real_sky_has_no_seam_in_the_program(tmp_path, real_cube, name):
    template = str(tmp_path / "r_{face}.exr")
    envconv.write(real_cube, template, bit_depth="float", faces=scheme_name(name))
    formulas = FORMULAS[name]()
    images = read_files(template, formulas)
    seams = edge_seams(images, formulas, 48)
    assert len(seams) == 24  # 12 cube edges, seen from both faces
    across = np.mean([s for s, _ in seams.values()])
    inside = np.mean([i for _, i in seams.values()])
    assert across < 1.6 * inside, (across, inside)
    for key, (s, i) in seams.items():
        assert s < 3 * i + 1e-3, (key, s, i)
    # A face turned a quarter turn the wrong way shows as a seam on its edges.
    first = next(iter(formulas))
    images[first] = np.rot90(images[first]).copy()
    turned = edge_seams(images, formulas, 48)
    assert max(turned[(first, e)][0] / turned[(first, e)][1]
               for e in ("left", "right", "top", "bottom")) > 3  # fmt: skip


def test_faces_are_found_from_names_case_insensitively(tmp_path):
    files = render_files(quake_faces(), N)
    template = write_files(tmp_path, {k.upper(): v for k, v in files.items()}, stem="Sky")
    assert os.path.exists(tmp_path / "Sky_FT.exr") and not os.path.exists(tmp_path / "Sky_ft.exr")
    env = envconv.read(template)
    np.testing.assert_allclose(env.pixels, envconv_truth(N), rtol=1e-6, atol=1e-6)


def test_two_complete_sets_are_ambiguous(tmp_path):
    template = write_files(tmp_path, render_files(quake_faces(), 4))
    write_files(tmp_path, render_files(FORMULAS["envconv"](), 4))
    with pytest.raises(LayoutError, match=r"several face sets: envconv .*quake"):
        envconv.read(template)
    assert envconv.read(template, faces="quake").size == 4  # naming one settles it


def test_incomplete_set_names_the_missing_file(tmp_path):
    files = render_files(quake_faces(), 4)
    del files["dn"]
    template = write_files(tmp_path, files)
    with pytest.raises(ImageIOError, match=r"quake face files are incomplete: no .*sky_dn\.exr"):
        envconv.read(template)


def test_unity_front_and_back_are_not_a_paraboloid(tmp_path):
    template = write_files(tmp_path, render_files(FORMULAS["unity-6sided"](), 4))
    assert envconv.read(template).layout.name == "cube-faces"
    only = tmp_path / "two"
    only.mkdir()
    pair = render_files(FORMULAS["unity-6sided"](), 4)
    two = write_files(only, {k: pair[k] for k in ("front", "back")})
    assert envconv.read(two).layout.name == "paraboloid-split"


def test_face_set_errors():
    with pytest.raises(UsageError, match="unknown face set 'quack'; did you mean quake"):
        envconv.layouts.facesets.get_face_set("quack")
    env = envconv.EnvMap(np.zeros((4, 8, 3), np.float32), "latlong")
    with pytest.raises(LayoutError, match="applies to cube-faces, not latlong"):
        envconv.write(env, "sky_{face}.exr", faces="quake")
    with pytest.raises(LayoutError, match="needs {face} in the path"):
        envconv.read("sky.exr", faces="quake")
    assert envconv.layouts.facesets.get_face_set("Source").name == "quake"


def test_cli_reads_a_game_skybox_by_its_names(tmp_path):
    """The issue's report: six Quake-named .hdr files convert with no option at all."""
    template = write_files(tmp_path, render_files(quake_faces(), 32), ext="hdr")
    out, named = tmp_path / "out.exr", tmp_path / "named.exr"
    result = run_cli(["convert", template, out, "--to", "latlong", "--size", "32"])
    assert result.exit_code == 0, result.stderr
    assert result.stdout.strip() == str(out)
    result = run_cli(["convert", template, named, "--to", "latlong", "--size", "32",
                      "--in-convention", "source"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    got, also = envconv.read(out).pixels, envconv.read(named).pixels
    np.testing.assert_array_equal(got, also)
    truth = naive.pixel_average("latlong", 32, analytic.radiance, samples=4)
    err = np.sqrt(((got - truth) ** 2).sum() / (truth**2).sum())
    assert err < 0.05, err


def test_cli_writes_and_plans_a_face_set(tmp_path):
    envconv.write(envconv.EnvMap(envconv_truth(8), "cube-faces"), tmp_path / "c_{face}.exr")
    template = str(tmp_path / "c_{face}.exr")
    result = run_cli(["convert", template, tmp_path / "u_{face}.exr", "--to", "cube-faces",
                      "--out-convention", "unity-6sided", "--dry-run"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    planned = [line.split(": ", 1)[1] for line in result.stdout.splitlines()
               if line.startswith("would write")]  # fmt: skip
    assert {os.path.basename(p) for p in planned} == {
        f"u_{k}.exr" for k in ("front", "back", "left", "right", "up", "down")
    }
    result = run_cli(["convert", template, tmp_path / "q_{face}.exr", "--to", "cube-faces",
                      "--out-convention", "quake"])  # fmt: skip
    assert result.exit_code == 0, result.stderr
    assert len(result.stdout.split()) == 6
    back = envconv.read(str(tmp_path / "q_{face}.exr"))  # found by name: quake
    np.testing.assert_allclose(back.pixels, envconv.read(template).pixels, rtol=1e-3)


def test_cli_ambiguity_is_one_line(tmp_path):
    template = write_files(tmp_path, render_files(quake_faces(), 4))
    write_files(tmp_path, render_files(FORMULAS["unreal"](), 4))
    result = run_cli(["convert", template, tmp_path / "o.exr", "--to", "latlong"])
    assert result.exit_code == 1
    lines = stderr_lines(result)
    assert len(lines) == 1 and "quake" in lines[0] and "unreal" in lines[0], lines
    assert result.stdout == ""


def test_cli_layouts_lists_face_sets():
    result = run_cli(["layouts"])
    assert result.exit_code == 0
    for name in list(envconv.layouts.facesets.FACE_SETS):
        assert any(line.startswith(name + " ") for line in result.stdout.splitlines()), name
    assert "rt bk lf ft up dn" in result.stdout


def test_pipeline_steps_take_face_sets(tmp_path):
    from envconv.engine.pipeline import Pipeline, Read, Resample, Write

    template = write_files(tmp_path, render_files(quake_faces(), N))
    out = str(tmp_path / "ue_{face}.exr")
    pipeline = Pipeline([Read(template, faces="quake"), Resample("cube-faces", size=N, samples=1),
                         Write(out, faces="unreal", bit_depth="float")])  # fmt: skip
    planned = pipeline.output_files()
    assert sorted(planned) == sorted(out.replace("{face}", k) for k in FORMULAS["unreal"]())
    pipeline.run()
    got = read_files(out, FORMULAS["unreal"]())
    for key, image in render_files(FORMULAS["unreal"](), N).items():
        np.testing.assert_allclose(got[key], image, rtol=1e-6, atol=1e-6, err_msg=key)
    info = run_cli(["info", template])
    assert info.exit_code == 0, info.stderr
