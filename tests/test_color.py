"""Tests for envconv.color.ocio against analytic formulas, published matrices and hand counts."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from envconv.color import ocio as color
from envconv.color import quantize
from envconv.errors import ColorError, UsageError

LIN = "Linear Rec.709 (sRGB)"
SRGB = "sRGB Encoded Rec.709 (sRGB)"

# Rec.709 (D65) linear -> ACEScg (AP1, D60) with Bradford adaptation, as published
# (e.g. colour-science, ACES TB-2014-004 derived); rows are output channels.
REC709_TO_AP1 = np.array(
    [[0.6131, 0.3395, 0.0474], [0.0702, 0.9164, 0.0134], [0.0206, 0.1096, 0.8698]]
)


def srgb_decode(v):
    """IEC 61966-2-1 sRGB EOTF (encoded -> linear), written from the standard."""
    v = np.asarray(v, np.float64)
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def srgb_encode(x):
    """Inverse of :func:`srgb_decode`."""
    x = np.asarray(x, np.float64)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.maximum(x, 0) ** (1 / 2.4) - 0.055)


@pytest.fixture(scope="module")
def cfg():
    return color.load_config("ocio://default")


def image(values, channels=3):
    return np.asarray(values, np.float32).reshape(1, -1, channels)


# --- config ---------------------------------------------------------------------------------


def test_load_config_falls_back_to_builtin(monkeypatch):
    monkeypatch.delenv("OCIO", raising=False)
    assert color.load_config().getName().startswith("cg-config")


def test_load_config_uses_ocio_env(monkeypatch, tmp_path):
    missing = tmp_path / "nope.ocio"
    monkeypatch.setenv("OCIO", str(missing))
    with pytest.raises(ColorError, match=r"\$OCIO") as info:
        color.load_config()
    assert str(missing) in str(info.value)


@pytest.mark.parametrize("content", [None, "not: [a config", "ocio_profile_version: 2\n"])
def test_bad_config_path_raises_one_line_color_error(tmp_path, content):
    path = tmp_path / "config.ocio"
    if content is not None:
        path.write_text(content)
    with pytest.raises(ColorError) as info:
        color.load_config(path)
    msg = str(info.value)
    assert str(path) in msg and "\n" not in msg
    if content is None:
        assert "no such file" in msg


def test_bad_builtin_uri_raises_color_error():
    with pytest.raises(ColorError, match="ocio://nonsense"):
        color.load_config("ocio://nonsense")


def test_import_is_cheap():
    import subprocess
    import sys

    code = "import sys, envconv.color.ocio; print('PyOpenColorIO' in sys.modules)"
    # envconv/__init__ may import io (OIIO) but nothing may pull in OCIO eagerly.
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


# --- names ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "name, expected",
    [
        ("scene_linear", "ACEScg"),  # role
        ("lin_rec709", LIN),  # alias
        ("LIN_REC709", LIN),  # case-insensitive
        ("lin_rec709_scene", LIN),  # interop id
        ("srgb_tx", SRGB),
        ("ACEScg", "ACEScg"),
        ("acescg", "ACEScg"),
        ("linear", LIN),  # friendly spellings
        ("Linear", LIN),
        ("srgb", SRGB),
        ("sRGB", SRGB),
        ("rec709", "Gamma 2.4 Encoded Rec.709"),
        ("aces", "ACES2065-1"),
        ("raw", "Raw"),
        ("  Linear Rec.709 (sRGB)  ", LIN),
    ],
)
def test_resolve_colorspace(cfg, name, expected):
    assert color.resolve_colorspace(cfg, name) == expected


@pytest.mark.parametrize(
    "name, near",
    [("ACEScgg", "ACEScg"), ("lin_rec790", "lin_rec709"), ("Linear Rec.709 (sRGB", LIN)],
)
def test_unknown_colorspace_lists_close_matches(cfg, name, near):
    with pytest.raises(ColorError) as info:
        color.resolve_colorspace(cfg, name)
    msg = str(info.value)
    assert repr(name) in msg and repr(near) in msg
    suggestions = msg.split("did you mean", 1)[1]
    assert 1 <= suggestions.count("'") // 2 <= 5


def test_empty_colorspace_name_is_an_error(cfg):
    with pytest.raises(ColorError):
        color.resolve_colorspace(cfg, " ")


@pytest.mark.parametrize(
    "fmt, ptype, expected",
    [
        ("openexr", "half", LIN),
        ("exr", "float", LIN),
        (".hdr", "float", LIN),
        ("tiff", "float", LIN),
        ("exr", "uint", LIN),
        ("tiff", np.dtype("float32"), LIN),
        ("png", "uint8", SRGB),
        ("png", "uint16", SRGB),
        ("jpeg", "uint8", SRGB),
        ("tif", "uint16", SRGB),
        ("tiff", np.uint8, SRGB),
    ],
)
def test_default_colorspace(cfg, fmt, ptype, expected):
    assert color.default_colorspace(cfg, fmt, ptype) == expected


def test_default_colorspace_unknown_type(cfg):
    with pytest.raises(ColorError, match="input-colorspace"):
        color.default_colorspace(cfg, "png", "complex64")


@pytest.mark.parametrize(
    "value, expected",
    [
        ("Linear", LIN),
        ("linear", LIN),
        ("lin_rec709", LIN),
        ("lin_rec709_scene", LIN),
        ("sRGB", SRGB),
        ("srgb_rec709_scene", SRGB),
        ("ACEScg", "ACEScg"),
        ("GammaCorrected2.2", "Gamma 2.2 Encoded Rec.709"),
        ("", None),
        (None, None),
        ("definitely-not-a-space", None),
    ],
)
def test_colorspace_from_metadata(cfg, value, expected):
    assert color.colorspace_from_metadata(value, cfg) == expected
    assert color.colorspace_from_metadata(value) == expected  # built-in default config


# --- conversions ----------------------------------------------------------------------------


def test_srgb_decode_matches_analytic(cfg):
    v = np.linspace(0, 1, 1001)
    out = color.convert_colorspace(image(np.repeat(v, 3)), "srgb", "linear", cfg)
    assert out.dtype == np.float32
    np.testing.assert_allclose(out.ravel(), np.repeat(srgb_decode(v), 3), atol=2e-6, rtol=1e-4)


def test_srgb_encode_matches_analytic(cfg):
    x = np.concatenate([np.linspace(0, 0.01, 101), np.linspace(0.01, 1, 500)])
    out = color.convert_colorspace(image(np.repeat(x, 3)), LIN, SRGB, cfg)
    # OCIO derives the toe slope from continuity (12.9232 rather than IEC's rounded 12.92):
    # a difference of at most 1e-5, far below an 8-bit or 16-bit code.
    np.testing.assert_allclose(out.ravel(), np.repeat(srgb_encode(x), 3), atol=1.2e-5, rtol=1e-4)


def test_rec709_to_acescg_matches_published_matrix(cfg):
    basis = image(np.eye(3))  # pixel j is the j-th primary
    out = color.convert_colorspace(basis, "lin_rec709", "ACEScg", cfg)[0]
    np.testing.assert_allclose(out.T, REC709_TO_AP1, atol=1e-3)


def test_8bit_srgb_codes_survive_linear_round_trip(cfg):
    codes = np.arange(256)
    px = image(np.repeat(codes / 255.0, 3))
    lin = color.convert_colorspace(px, "srgb", "linear", cfg)
    back = color.convert_colorspace(lin, "linear", "srgb", cfg)
    out, report = quantize.quantize(back, "uint8", dither=False)
    assert out.dtype == np.uint8
    np.testing.assert_array_equal(out.reshape(-1, 3)[:, 0], codes)
    assert not report.clipped
    dithered, _ = quantize.quantize(back, "uint8", dither=True)
    assert np.abs(dithered.astype(int) - out.astype(int)).max() <= 1
    assert dithered.reshape(-1, 3)[0].tolist() == [0, 0, 0]
    assert dithered.reshape(-1, 3)[-1].tolist() == [255, 255, 255]


@settings(max_examples=50, deadline=None)
@given(
    st.lists(st.floats(0, 1, width=32), min_size=3, max_size=30).filter(lambda v: len(v) % 3 == 0)
)
def test_srgb_round_trip_is_identity(v):
    cfg = color.load_config("ocio://default")
    px = image(v)
    back = color.convert_colorspace(
        color.convert_colorspace(px, "srgb", "linear", cfg), "linear", "srgb", cfg
    )
    np.testing.assert_allclose(back, px, atol=1e-5)


def test_alpha_and_extra_channels_untouched(cfg):
    px = np.array([[[0.5, 0.25, 1.0, 0.3, 7.0]]], np.float32)
    out = color.convert_colorspace(px, "srgb", "linear", cfg)
    np.testing.assert_allclose(out[0, 0, :3], srgb_decode([0.5, 0.25, 1.0]), rtol=1e-4)
    assert out[0, 0, 3:].tolist() == pytest.approx([0.3, 7.0])


@pytest.mark.parametrize("channels", [1, 2])
def test_grey_images_convert_as_grey(cfg, channels):
    px = np.full((2, 2, channels), 0.5, np.float32)
    out = color.convert_colorspace(px, "srgb", "linear", cfg)
    assert out.shape == px.shape
    np.testing.assert_allclose(out[..., 0], srgb_decode(0.5), rtol=1e-4)
    if channels == 2:
        np.testing.assert_array_equal(out[..., 1], 0.5)


def test_same_space_is_a_no_op(cfg):
    px = np.random.default_rng(0).random((4, 4, 3), dtype=np.float32)
    assert color.convert_colorspace(px, "lin_rec709", LIN, cfg) is px


def test_convert_does_not_modify_input(cfg):
    px = np.full((2, 2, 3), 0.5, np.float32)
    color.convert_colorspace(px, "srgb", "ACEScg", cfg)
    np.testing.assert_array_equal(px, 0.5)


def test_bad_shape_is_usage_error(cfg):
    with pytest.raises(UsageError, match="shape"):
        color.convert_colorspace(np.zeros((4, 4), np.float32), "srgb", "linear", cfg)


def test_builtin_config_is_ocios_default_config():
    """``builtin_config`` is OCIO's own ``ocio://default``, loaded once: OCIO answers."""
    lazy = color.builtin_config()
    assert lazy is color.builtin_config()
    assert lazy.getName().startswith("cg-config")
    assert color.resolve_colorspace(lazy, "linear") == "Linear Rec.709 (sRGB)"
    assert color.metadata_name(lazy, "linear") == "lin_rec709_scene"
    assert color.resolve_colorspace(lazy, "srgb") == SRGB
    assert color.default_colorspace(lazy, "png", "uint8") == SRGB
    px = image([0.5, 0.5, 0.5])
    out = color.convert_colorspace(px, "srgb", "linear", lazy)
    np.testing.assert_allclose(out[0, 0], srgb_decode(0.5), rtol=1e-5)
    with pytest.raises(ColorError, match="unknown colour space"):
        color.resolve_colorspace(lazy, "no such space")
