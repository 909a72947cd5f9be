"""envconv.pipeline: steps, the fan-out rule, rotations, variables and plans.

Truth: ``envconv.convert`` run directly on the source (the pipeline must equal it bit for bit),
analytic environments (tests/analytic.py, tests/naive.py), and rotation matrices.
"""

from __future__ import annotations

import numpy as np
import pytest

import envconv
from envconv import io
from envconv.errors import UsageError
from envconv.pipeline import (
    Exposure,
    Pipeline,
    Read,
    Resample,
    Rotate,
    Write,
    compose_rotations,
    count_levels,
    expand_path,
    path_variables,
)
from envconv.rotation import rotation_matrix


@pytest.fixture(scope="module")
def sky(tmp_path_factory):
    """A 128×64 float lat-long of the smooth analytic environment, on disk."""
    import analytic
    import naive

    pixels = naive.pixel_average("latlong", 32, analytic.smooth_radiance, samples=4)
    path = tmp_path_factory.mktemp("src") / "sky.exr"
    io.write(envconv.EnvMap(pixels.astype(np.float32), "latlong"), path)
    return path


def test_fan_out_equals_direct_convert(sky, tmp_path):
    outputs = Pipeline(
        [
            Read(sky),
            Resample("cube-vcross", size=16),
            Write(tmp_path / "cross.exr"),
            Resample("paraboloid", size=16, alpha=True, guard=2),
            Write(tmp_path / "para.exr"),
        ]
    ).run()
    source = io.read(sky)
    cross = envconv.convert(source, "cube-vcross", size=16)
    para = envconv.convert(source, "paraboloid", size=16, alpha=True, guard=2)
    # Each output is resampled from the source, never from the previous output.
    assert np.array_equal(outputs[0].envmap.pixels, cross.pixels)
    assert np.array_equal(outputs[1].envmap.pixels, para.pixels)
    assert outputs[1].envmap.channels == ("R", "G", "B", "A")
    assert outputs[0].files == [str(tmp_path / "cross.exr")]
    assert np.array_equal(io.read(tmp_path / "para.exr").pixels, para.pixels)


def test_rotate_step_matches_analytic_rotation(sky):
    import analytic
    import naive

    yaw, pitch = 90.0, 30.0
    (out,) = Pipeline([Read(sky), Rotate(f"{yaw},{pitch}"), Resample("latlong", size=32)]).run()
    matrix = rotation_matrix(yaw, pitch, 0.0)
    # L'(d) = L(Rᵀ d): the rotated environment, averaged over each output pixel.
    truth = naive.pixel_average(
        "latlong", 32, lambda d: analytic.smooth_radiance(d @ matrix), samples=4
    )
    error = np.abs(out.envmap.pixels - truth).max() / np.abs(truth).max()
    assert error < 0.03
    # The same rotation as convert --rotate, bit for bit.
    direct = envconv.convert(io.read(sky), "latlong", size=32, rotate=f"{yaw},{pitch}")
    assert np.array_equal(out.envmap.pixels, direct.pixels)


@pytest.mark.parametrize(
    "first, second",
    [((10, 20, 30), (40, -50, 60)), ((90, 0, 0), (0, 90, 0)), ((0, 90, 0), (30, 0, 0))],
)
def test_compose_rotations(first, second):
    composed = compose_rotations(first, second)
    expected = rotation_matrix(*second) @ rotation_matrix(*first)
    assert np.allclose(rotation_matrix(*composed), expected, atol=1e-12)


def test_two_rotations_compose_inside_one_resample(sky):
    (two,) = Pipeline([Read(sky), Rotate("60"), Resample("latlong", size=32, rotate="30")]).run()
    one = envconv.convert(io.read(sky), "latlong", size=32, rotate="90")
    assert np.abs(two.envmap.pixels - one.pixels).max() < 1e-4 * np.abs(one.pixels).max()


def test_exposure_source_level_and_output_level(sky):
    first, second = (o.envmap for o in Pipeline(
        [
            Read(sky),
            Resample("cube-hstrip", size=8, alpha=True),
            Exposure(-1),  # output-level: only this output
            Resample("cube-hstrip", size=8, alpha=True),
        ]
    ).run())  # fmt: skip
    plain = envconv.convert(io.read(sky), "cube-hstrip", size=8, alpha=True)
    assert np.array_equal(first.pixels[..., :3], plain.pixels[..., :3] * np.float32(0.5))
    assert np.array_equal(first.pixels[..., 3], plain.pixels[..., 3])  # alpha untouched
    assert np.array_equal(second.pixels, plain.pixels)  # resampled from the unexposed source

    later = Pipeline([Read(sky), Exposure(2), Resample("cube-hstrip", size=8)]).run()
    assert np.allclose(later[0].envmap.pixels, plain.pixels[..., :3] * 4, rtol=1e-6)


def test_write_without_resample_writes_the_source(sky, tmp_path):
    (out,) = Pipeline([Read(sky), Write(tmp_path / "copy.exr")]).run()
    assert out.layout == "latlong" and out.size == 32
    assert np.array_equal(io.read(tmp_path / "copy.exr").pixels, io.read(sky).pixels)


@pytest.mark.parametrize(
    "steps, message",
    [
        ([Resample("latlong")], "step 1 (resample): comes before any read"),
        ([Read("a.exr"), Resample("latlong"), Rotate("9"), Write("b.exr")], "step 3 (rotate)"),
        ([Read("a.exr"), Write("{nope}.exr")], "step 2 (write): path: unknown variable {nope}"),
        ([Read("a.exr"), Resample("cube-faces"), Write("b.exr")], "put {face}"),
        ([Read(), Write("b.exr")], "step 1 (read): read needs a file"),
    ],
)
def test_validation_names_the_step(steps, message):
    with pytest.raises(UsageError, match=message.replace("{", r"\{").replace("(", r"\(")
                       .replace(")", r"\)")):  # fmt: skip
        Pipeline(steps).validate()


def test_unwritten_resample_is_an_error_when_writes_are_required():
    steps = [Read("a.exr"), Resample("latlong"), Write("a2.exr"), Resample("sphere")]
    Pipeline(steps).validate()
    with pytest.raises(UsageError, match=r"step 4 \(resample\): this resample is never written"):
        Pipeline(steps).validate(require_writes=True)


def test_expand_path_variables():
    variables = {**path_variables("/data/hdri/park.exr"), "layout": "sphere", "size": 64}
    assert variables["ext"] == "exr" and variables["dir"] == "/data/hdri"
    assert expand_path("{dir}/{stem}_{layout}_{size}.{ext}", variables) == (
        "/data/hdri/park_sphere_64.exr"
    )
    assert expand_path("out/{name}_{face}_{level}.png", variables) == (
        "out/park.exr_{face}_{level}.png"
    )
    with pytest.raises(UsageError, match=r"unknown variable \{stm\}"):
        expand_path("{stm}.exr", variables)


def test_recipe_binds_the_input(sky, tmp_path):
    recipe = Pipeline(
        [
            Read(layout="latlong"),
            Resample("sphere", size=8),
            Write(str(tmp_path / "{stem}_{layout}.exr")),
        ]
    )
    (out,) = recipe.run(input=sky)
    assert out.files == [str(tmp_path / "sky_sphere.exr")]
    assert io.read(out.files[0]).layout.name == "sphere"


def test_plan_reads_headers_only(sky, tmp_path, monkeypatch):
    steps = [
        Read(sky),
        Resample("cube-faces"),  # default size from the header's N
        Write(str(tmp_path / "{stem}_{size}_{face}.exr")),
        Resample("paraboloid", size=16, guard=1, mips=True),
        Write(str(tmp_path / "p_{level}.png")),
    ]

    def no_pixels(*args, **kwargs):
        raise AssertionError("plan read pixels")

    monkeypatch.setattr(io.reader, "read_file", no_pixels)
    faces, para = Pipeline(steps).plan()
    expected_n = envconv.resample.default_size(
        envconv.EnvMap(np.zeros((32, 64, 3), np.float32), "latlong"), "cube-faces"
    )
    assert (faces.layout, faces.size, faces.width, faces.height) == (
        "cube-faces", expected_n, expected_n, expected_n,
    )  # fmt: skip
    assert faces.files == [str(tmp_path / f"sky_{expected_n}_{f}.exr")
                           for f in ("px", "nx", "py", "ny", "pz", "nz")]  # fmt: skip
    assert (para.width, para.height, para.levels) == (36, 18, 6)  # 2(16+2) x (16+2): 36→1
    assert para.files == [str(tmp_path / f"p_{k}.png") for k in range(6)]


def test_count_levels():
    assert count_levels(36, 18, None) == 1
    assert count_levels(36, 18, True) == 6
    assert count_levels(36, 18, 0) == 6
    assert count_levels(36, 18, 3) == 3
    assert count_levels(36, 18, 99) == 6


def test_failure_reports_what_was_written(sky, tmp_path):
    written: list[str] = []
    steps = [
        Read(sky),
        Resample("sphere", size=8),
        Write(tmp_path / "ok.exr"),
        Resample("sphere", size=8),
        Write(tmp_path / "missing" / "bad.exr", makedirs=False),  # fails only when written
    ]
    with pytest.raises(envconv.EnvconvError):
        Pipeline(steps).run(written=written)
    assert written == [str(tmp_path / "ok.exr")]


def test_bad_output_settings_fail_before_any_file_is_written(sky, tmp_path):
    steps = [Read(sky), Resample("sphere", size=8), Write(tmp_path / "ok.exr"),
             Resample("sphere", size=8), Write(tmp_path / "bad.unknownext")]  # fmt: skip
    with pytest.raises(envconv.EnvconvError):
        Pipeline(steps).run()
    assert not (tmp_path / "ok.exr").exists()
