"""envconv.engine.pipeline: steps, the fan-out rule, rotations, variables and plans.

Truth: ``envconv.convert`` run directly on the source (the pipeline must equal it bit for bit),
analytic environments (tests/analytic.py, tests/naive.py), and rotation matrices.
"""

from __future__ import annotations

import numpy as np
import pytest

import envconv
from envconv import io
from envconv.engine.pipeline import (
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
from envconv.errors import UsageError
from envconv.layouts.rotation import rotation_matrix


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
    expected_n = envconv.resample.convert.default_size(
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


# --- issue 15: one engine; the rule for pixel steps after a write; output policy -------------


def _oiio_pixels(path):
    """Pixels and ``oiio:ColorSpace`` of a file as OpenImageIO reads it (not envconv)."""
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(str(path))
    return buf.get_pixels(oiio.FLOAT), buf.spec().getattribute("oiio:ColorSpace")


def test_write_keeps_the_colour_space_of_a_colorspace_step(sky, tmp_path):
    """``colorspace --to ACEScg`` then ``write``: the file holds OCIO's own conversion of the
    plain output's pixels and is tagged ACEScg (main undid the step: plain pixels, Rec.709)."""
    import PyOpenColorIO as ocio

    plain, cg = tmp_path / "plain.exr", tmp_path / "cg.exr"
    Pipeline([Read(sky), Resample("latlong", size=16), Write(plain, bit_depth="float"),
              Resample("latlong", size=16), envconv.engine.pipeline.Colorspace("ACEScg"),
              Write(cg, bit_depth="float")]).run()  # fmt: skip
    config = ocio.Config.CreateFromFile("ocio://default")
    linear, tag = _oiio_pixels(plain)
    assert config.getColorSpace(tag).getName() == "Linear Rec.709 (sRGB)"
    truth = np.array(linear[..., :3], np.float32, copy=True)
    config.getProcessor("Linear Rec.709 (sRGB)", "ACEScg").getDefaultCPUProcessor().applyRGB(truth)
    pixels, tag = _oiio_pixels(cg)
    assert config.getColorSpace(tag).getName() == "ACEScg"
    np.testing.assert_allclose(pixels[..., :3], truth, rtol=1e-5, atol=1e-6)
    assert np.abs(pixels - linear).max() > 1e-3  # the conversion is not a no-op here


def test_write_names_its_own_colour_space_over_the_step(sky, tmp_path):
    """``--output-colorspace`` on the write wins: back to Rec.709, the plain output again."""
    plain, back = tmp_path / "plain.exr", tmp_path / "back.exr"
    Pipeline([Read(sky), Resample("latlong", size=16), Write(plain, bit_depth="float"),
              envconv.engine.pipeline.Colorspace("ACEScg"),
              Write(back, bit_depth="float", output_colorspace="lin_rec709")]).run()  # fmt: skip
    np.testing.assert_allclose(_oiio_pixels(back)[0], _oiio_pixels(plain)[0], rtol=1e-5, atol=1e-6)


def test_a_pixel_step_after_a_write_changes_the_latest_output_and_the_source(sky, tmp_path):
    """``resample --size 8 write e exposure -1 write f``: f is e halved (main wrote the full
    source); a resample after it sees the halved source too (x 0.5 is exact in float)."""
    e, f, g = tmp_path / "e.exr", tmp_path / "f.exr", tmp_path / "g.exr"
    Pipeline([Read(sky), Resample("latlong", size=8), Write(e), Exposure(-1), Write(f),
              Resample("latlong", size=8), Write(g)]).run()  # fmt: skip
    pe, pf, pg = (_oiio_pixels(p)[0] for p in (e, f, g))
    assert pf.shape == pe.shape == (8, 16, 3)
    assert np.array_equal(pf, pe * 0.5) and np.array_equal(pg, pf)


def test_a_rotate_after_a_written_output_needs_a_resample_before_the_next_write(sky, tmp_path):
    steps = [Read(sky), Resample("latlong", size=8), Write(tmp_path / "a.exr"), Rotate(yaw=90),
             Write(tmp_path / "b.exr")]  # fmt: skip
    with pytest.raises(UsageError, match="step 5 .*rotate of step 4"):
        Pipeline(steps).validate()
    assert not (tmp_path / "a.exr").exists()


def test_plan_and_run_agree_on_the_files(sky, tmp_path):
    steps = [Read(sky), Resample("cube-faces", size=4), Write(tmp_path / "f_{face}.exr"),
             Exposure(-1), Write(tmp_path / "g_{face}_{size}.png"),
             Resample("latlong", size=8, mips=3), Write(tmp_path / "m_{level}.exr")]  # fmt: skip
    planned = Pipeline(steps).output_files()
    done = [f for o in Pipeline(steps).run(keep=False) for f in o.files]
    assert planned == done and len(done) == 6 + 6 + 3
    assert all((tmp_path / p).exists() for p in done)


@pytest.mark.parametrize("make_link", ["same", "symlink", "hardlink"])
def test_a_pipeline_never_writes_onto_its_input(sky, tmp_path, make_link):
    import os
    import shutil

    source = tmp_path / "in.exr"
    shutil.copy(sky, source)
    target = {"same": source, "symlink": tmp_path / "s.exr", "hardlink": tmp_path / "h.exr"}[
        make_link
    ]
    if make_link == "symlink":
        os.symlink(source, target)
    elif make_link == "hardlink":
        os.link(source, target)
    before = source.read_bytes()
    with pytest.raises(UsageError, match="never writes onto its inputs"):
        Pipeline([Read(source), Resample("latlong", size=4), Write(target)]).run()
    assert source.read_bytes() == before


def test_two_outputs_on_one_path_and_no_clobber_are_refused_before_any_work(sky, tmp_path):
    first = tmp_path / "a.exr"
    steps = [Read(sky), Resample("latlong", size=4), Write(first),
             Resample("sphere", size=4), Write(tmp_path / "." / "a.exr")]  # fmt: skip
    with pytest.raises(UsageError, match="written twice"):
        Pipeline(steps).run()
    assert not first.exists()
    first.write_bytes(b"old")
    with pytest.raises(UsageError, match="no-clobber"):
        Pipeline([Read(sky), Resample("latlong", size=4), Write(tmp_path / "new.exr"),
                  Write(first, no_clobber=True)]).run()  # fmt: skip
    assert first.read_bytes() == b"old" and not (tmp_path / "new.exr").exists()
    Pipeline([Read(sky), Resample("latlong", size=4), Write(first)]).run()  # replaced
    assert io.read(first).size == 4


def test_convert_file_is_the_pipeline_read_resample_write(tmp_path):
    """api.convert_file and a Pipeline give the same pixels, and the same NaN/Inf warnings
    (on main the pipeline ignored NaN handling that only convert knew)."""
    from envconv.engine.api import convert_file

    pixels = np.ones((8, 16, 3), np.float32)
    pixels[3, 5, 1] = np.nan
    source = tmp_path / "nan.exr"
    io.write(envconv.EnvMap(pixels, "latlong"), source)
    notes_a: list[str] = []
    convert_file(source, tmp_path / "a.exr", resample={"to": "sphere", "size": 8},
                 color={"fix_nonfinite": "black", "exposure": -1}, warnings=notes_a)  # fmt: skip
    notes_b: list[str] = []
    Pipeline([Read(source, fix_nonfinite="black", exposure=-1), Resample("sphere", size=8),
              Write(tmp_path / "b.exr")]).run(warnings=notes_b)  # fmt: skip
    a, b = _oiio_pixels(tmp_path / "a.exr")[0], _oiio_pixels(tmp_path / "b.exr")[0]
    assert np.array_equal(a, b) and np.isfinite(a).all()
    assert notes_a == notes_b and len(notes_a) == 1 and "1 NaN" in notes_a[0]


def test_user_variables_use_each_other_but_not_in_a_cycle():
    from envconv.engine.steps import check_variables

    assert check_variables({"a": "{dir}/x", "b": "{a}_{stem}"}) == {
        "a": "{dir}/x",
        "b": "{dir}/x_{stem}",
    }
    with pytest.raises(UsageError, match="cycle"):
        check_variables({"a": "{b}", "b": "{a}"})
    with pytest.raises(UsageError, match="unknown variable"):
        check_variables({"a": "{nope}"})
    assert expand_path("{b}.exr", {"dir": "d", "stem": "s"}, {"b": "{dir}/x_{stem}"}) == "d/x_s.exr"


def test_count_levels_reads_the_mip_requests_resample_takes():
    assert count_levels(64, 32, "ggx:3") == 3 and count_levels(64, 32, "ggx") == 7
    assert count_levels(64, 32, "box:2") == 2 and count_levels(64, 32, "all") == 7
