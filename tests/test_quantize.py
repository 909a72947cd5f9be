"""Tests for envconv.color.quantize, envconv.color.prepare and exposure: quantizing, dither, clip reports, NaN/Inf, negatives.

Truth is hand-computed counts and codes, OIIO's own fixNonFinite, and statistics of the dither.
"""

import warnings

import numpy as np
import pytest

from envconv.color import ocio as color
from envconv.color import prepare, quantize
from envconv.errors import EnvconvError, UsageError


def image(values, channels=3):
    return np.asarray(values, np.float32).reshape(1, -1, channels)


def test_dither_is_deterministic():
    px = np.random.default_rng(1).random((64, 48, 4), dtype=np.float32)
    a, _ = quantize.quantize(px, "uint8")
    b, _ = quantize.quantize(px.copy(), "uint8")
    np.testing.assert_array_equal(a, b)
    plain, _ = quantize.quantize(px, "uint8", dither=False)
    assert not np.array_equal(a, plain)
    np.testing.assert_array_equal(a[..., 3], plain[..., 3])  # alpha is only rounded


@pytest.mark.parametrize("offset", [0.5, 0.25, 0.1, 0.9])
def test_dither_preserves_the_mean(offset):
    code = 100 + offset
    px = np.full((128, 128, 3), code / 255, np.float32)
    out, _ = quantize.quantize(px, "uint8")
    assert abs(out.mean() - code) < 0.1
    assert set(np.unique(out)) <= {99, 100, 101, 102}
    undithered, _ = quantize.quantize(px, "uint8", dither=False)
    assert np.unique(undithered).size == 1


def test_clip_report_exact_fractions():
    px = np.full((4, 5, 3), 0.5, np.float32)
    px[0, 0, 0] = 1.5  # pixel 1: one value above
    px[0, 1] = [0.2, -0.2, 2.0]  # pixel 2: one below, one above
    px[2, 3] = 3.0  # pixel 3: three above
    px[3, 4, 2] = np.inf  # pixel 4: +inf clips too
    out, rep = quantize.quantize(px, "uint8", dither=False)
    assert (rep.values_above, rep.values_below) == (6, 1)
    assert (rep.pixels_above, rep.pixels_below, rep.pixels_clipped) == (4, 1, 4)
    assert rep.fraction_pixels_clipped == pytest.approx(4 / 20)
    assert rep.fraction_values_above == pytest.approx(6 / 60)
    assert "20% of pixels" in rep.message()
    assert out[2, 3].tolist() == [255, 255, 255] and out[0, 1, 1] == 0 and out[3, 4, 2] == 255


def test_clip_report_ignores_values_that_round_into_range():
    half_code = 0.5 / 255
    px = image([1 + 0.9 * half_code, -0.9 * half_code, 0.5, 1 + 1.1 * half_code, 0.5, 0.5])
    out, rep = quantize.quantize(px, "uint8", dither=False)
    assert out.ravel().tolist()[:3] == [255, 0, 128]
    assert (rep.values_above, rep.values_below, rep.pixels_clipped) == (1, 0, 1)


def test_no_clip_report_in_range():
    px = np.linspace(0, 1, 60, dtype=np.float32).reshape(4, 5, 3)
    for bits in ("uint8", "uint16", "half", "float"):
        _, rep = quantize.quantize(px, bits)
        assert rep.pixels_clipped == rep.values_above == rep.values_below == 0
        assert rep.message() is None


def test_uint16_codes_and_nan():
    out, _ = quantize.quantize(image([0.0, 0.5, 1.0, np.nan, 0.25, 1 / 65535]), "uint16")
    assert out.dtype == np.uint16
    assert out.ravel().tolist() == [0, 32768, 65535, 0, 16384, 1]


def test_half_overflow_only_above_65504():
    values = [65504.0, 1.0, -65504.0, 65505.0, -70000.0, np.inf]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out, rep = quantize.quantize(image(values), "half")
    assert out.dtype == np.float16
    assert (rep.values_above, rep.values_below, rep.pixels_clipped) == (1, 1, 1)
    assert out.ravel()[:5].tolist() == [65504.0, 1.0, -65504.0, 65504.0, -65504.0]
    assert np.isposinf(out.ravel()[5])
    assert "65504" in rep.message()
    _, quiet = quantize.quantize(image(values[:3] + [np.inf, -np.inf, np.nan]), "half")
    assert not quiet.clipped and quiet.message() is None


def test_unknown_bit_depth():
    with pytest.raises(UsageError):
        quantize.quantize(image([0, 0, 0]), "uint12")


def test_count_nonfinite():
    px = image([np.nan, 1, np.inf, -np.inf, 0, np.nan])
    assert prepare.count_nonfinite(px) == (2, 2)


@pytest.mark.parametrize(
    "values, expected",
    [
        ([3e38, 3e38, 3e38, 1.0], (0, 0)),  # finite values whose float32 sum overflows
        ([np.inf, -np.inf, 1.0, 2.0], (0, 2)),  # Infs whose sum is NaN
        ([np.inf, 1.0, 2.0, 3.0], (0, 1)),
        ([1.0, 2.0, np.nan, 4.0], (1, 0)),
        ([0.0, -1e-30, 65504.0, 1e30], (0, 0)),
    ],
)
def test_count_nonfinite_single_values_and_overflow(values, expected):
    """The one-pass check must neither miss a lone NaN or Inf nor count an overflowing sum."""
    big = np.ones((64, 64, 3), np.float32)
    big.reshape(-1)[[5, 999, 4000, 12000]] = values
    assert prepare.count_nonfinite(big) == expected
    with np.errstate(over="ignore"):
        half = big.astype(np.float16)  # 3e38 becomes Inf
    assert prepare.count_nonfinite(half) == (int(np.isnan(half).sum()), int(np.isinf(half).sum()))
    assert prepare.count_nonfinite(np.ones((4, 4, 3), np.uint8)) == (0, 0)


def test_fix_nonfinite_box3_hand_computed():
    px = np.array([[1, 2, 3, 4], [5, np.nan, 7, 8], [9, 10, 11, np.inf]], np.float32)[..., None]
    px = np.concatenate([px, np.ones_like(px)], axis=2)
    px[0, 0, 1] = -np.inf
    fixed, n = prepare.fix_nonfinite(px, "box3")
    assert n == 3
    assert fixed[1, 1, 0] == pytest.approx((1 + 2 + 3 + 5 + 7 + 9 + 10 + 11) / 8)
    assert fixed[2, 3, 0] == pytest.approx((7 + 8 + 11) / 3)  # corner: in-image neighbours
    assert fixed[0, 0, 1] == pytest.approx(1.0)  # other channel, own neighbours
    assert fixed[0, 0, 0] == 1 and np.isfinite(fixed).all()
    lonely = np.full((3, 3, 1), np.nan, np.float32)
    assert prepare.fix_nonfinite(lonely, "box3")[0].tolist() == np.zeros((3, 3, 1)).tolist()


def test_fix_nonfinite_box3_matches_oiio_on_isolated_values():
    oiio = pytest.importorskip("OpenImageIO")
    rng = np.random.default_rng(3)
    px = rng.random((9, 11, 3), dtype=np.float32)
    for y, x, c, v in [
        (0, 0, 0, np.nan),
        (4, 5, 1, np.inf),
        (8, 10, 2, -np.inf),
        (2, 7, 0, np.nan),
        (6, 0, 2, np.nan),
    ]:
        px[y, x, c] = v
    dst = oiio.ImageBuf()
    assert oiio.ImageBufAlgo.fixNonFinite(dst, oiio.ImageBuf(px), oiio.NONFINITE_BOX3)
    ours, n = prepare.fix_nonfinite(px, "box3")
    assert n == 5
    np.testing.assert_allclose(ours, dst.get_pixels(oiio.FLOAT), rtol=1e-6)


def test_fix_nonfinite_other_modes():
    px = image([np.nan, 2, -np.inf])
    black, n = prepare.fix_nonfinite(px, "black")
    assert black.ravel().tolist() == [0, 2, 0] and n == 2
    same, n = prepare.fix_nonfinite(px, "none")
    assert same is px and n == 0
    with pytest.raises(EnvconvError, match="1 NaN and 1 Inf"):
        prepare.fix_nonfinite(px, "error")
    with pytest.raises(UsageError):
        prepare.fix_nonfinite(px, "median")


def test_apply_exposure_scales_colour_only():
    px = image([0.5, 1.0, 2.0, 0.7], channels=4)
    out = color.apply_exposure(px, 2)
    assert out.ravel().tolist() == pytest.approx([2.0, 4.0, 8.0, 0.7])
    assert color.apply_exposure(px, 0) is px
    grey = color.apply_exposure(image([1.0, 0.5], channels=2), -1)
    assert grey.ravel().tolist() == [0.5, 0.5]
    with pytest.raises(UsageError):
        color.apply_exposure(px, float("nan"))


def test_clamp_negative_colour_only():
    px = np.array([[[-0.5, 0.25, -np.inf, -1.0], [np.nan, -0.0, 1.0, 0.5]]], np.float32)
    out, n = prepare.clamp_negative(px)
    assert n == 2
    assert out[0, 0].tolist() == [0.0, 0.25, 0.0, -1.0]
    assert np.isnan(out[0, 1, 0]) and out[0, 1, 1:].tolist() == [0.0, 1.0, 0.5]
    unchanged, n = prepare.clamp_negative(np.ones((2, 2, 3), np.float32))
    assert n == 0


def test_dither_leaves_values_on_the_code_grid():
    codes = np.arange(256, dtype=np.float32)
    px = np.repeat((codes / 255)[None, :, None], 3, axis=2)
    out, _ = quantize.quantize(px, "uint8")
    assert out[0, :, 0].tolist() == list(range(256))
    nudged, _ = quantize.quantize(px + np.float32(0.3 / 255), "uint8")
    assert not np.array_equal(nudged, out)  # off the grid: dithered


def test_bad_shape_is_usage_error():
    with pytest.raises(UsageError, match="shape"):
        quantize.quantize(np.zeros((4, 4), np.float32), "uint8")
