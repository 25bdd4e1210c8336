import json

import numpy as np
import pytest

from spectracam.core.errors import SpectracamError
from spectracam.io.exr import (describe, parse_spectral_channel, read_exr, read_radiance_exr,
                               spectral_channel_name, write_exr, write_radiance_exr)


def test_channel_names_follow_fichet_2021():
    assert spectral_channel_name(550.0) == "S0.550,000000nm"
    assert parse_spectral_channel("S0.412,500000nm") == 412.5
    assert parse_spectral_channel("R") is None


@pytest.fixture(scope="module")
def written(tmp_path_factory, scene_5000, mitsuba_5000):
    path = tmp_path_factory.mktemp("exr") / "radiance.exr"
    write_radiance_exr(path, mitsuba_5000)
    return path


def test_round_trip_is_exact(written, mitsuba_5000, scene_5000):
    cube, attrs = read_radiance_exr(written)
    np.testing.assert_array_equal(cube.radiance, mitsuba_5000.radiance)
    np.testing.assert_array_equal(cube.wavelengths_nm, scene_5000.grid.centres_nm)
    assert attrs["spectralLayoutVersion"] == "1.0" and attrs["emissiveUnits"] == "W.m^-2.sr^-1"
    assert json.loads(attrs["spectracamScene"]) == scene_5000.to_dict()
    assert attrs["spectracamRenderer"] == "mitsuba" and attrs["spectracamSeed"] == 0
    assert attrs["spectracamSamplesPerPixel"] == 4
    assert attrs["spectracamVariant"] == mitsuba_5000.metadata["variant"]


def test_openimageio_reads_the_same_pixels_and_attributes(written, mitsuba_5000):
    oiio = pytest.importorskip("OpenImageIO")
    inp = oiio.ImageInput.open(str(written))
    spec = inp.spec()
    pixels = inp.read_image(oiio.FLOAT)
    inp.close()
    names = list(spec.channelnames)
    for i, w in enumerate(mitsuba_5000.wavelengths_nm):
        np.testing.assert_array_equal(pixels[:, :, names.index(spectral_channel_name(w))], mitsuba_5000.radiance[:, :, i])
    assert spec.getattribute("spectracamRenderer") == "mitsuba"
    assert {"R", "G", "B"} <= set(names)


def test_colour_science_fichet_reader_agrees(written, mitsuba_5000):
    import colour

    components, _ = colour.io.read_spectral_image_Fichet2021(str(written), additional_data=True)
    wl, values = components["S0"]
    np.testing.assert_array_equal(np.asarray(wl), mitsuba_5000.wavelengths_nm)
    np.testing.assert_array_equal(np.asarray(values), mitsuba_5000.radiance)


def test_preview_white_patch_is_near_its_luminous_reflectance(written, scene_5000):
    from spectracam.scene.chart import patch_masks

    channels, _ = read_exr(written)
    masks = patch_masks(scene_5000.chart, 160, 120)
    rgb = np.stack([channels[c][masks[18]].mean() for c in "RGB"])
    # Y of sRGB = 0.2126 R + 0.7152 G + 0.0722 B; the white patch reflects ~91 % of the light
    assert rgb @ [0.2126, 0.7152, 0.0722] == pytest.approx(0.91, abs=0.01)


def test_failed_write_leaves_nothing(tmp_path):
    target = tmp_path / "x.exr"
    with pytest.raises(Exception):
        write_exr(target, {"A": np.zeros((4, 4)), "B": np.zeros((5, 4))}, {})
    assert list(tmp_path.iterdir()) == []


def test_describe_lists_bands_and_parameters(written):
    text = describe(written)
    assert "160 x 120 pixels, 33 channels" in text
    assert "S0.405,000000nm" in text and "spectracamScene" in text and "mean" in text


def test_not_an_exr_is_one_clear_error(tmp_path):
    bad = tmp_path / "bad.exr"
    bad.write_text("hello")
    with pytest.raises(SpectracamError, match="not a readable OpenEXR file"):
        read_exr(bad)


def test_attributes_are_written_typed(tmp_path):
    # numbers as EXR numbers (what OpenImageIO and exrheader show), JSON text only for nested data
    from spectracam.io.exr import attribute_number, double

    attrs = {"aFloat": 1.5, "aDouble": double(0.1), "anInt": 7, "aV3d": np.array([0.1, 0.2, 0.3]),
             "aM33f": np.eye(3, dtype=np.float32), "aDict": {"a": [1, 2]},
             "chromaticities": (0.64, 0.33, 0.3, 0.6, 0.15, 0.06, 0.3127, 0.329)}
    write_exr(tmp_path / "t.exr", {"Y": np.zeros((4, 4))}, attrs)
    _, back = read_exr(tmp_path / "t.exr")
    assert attribute_number(back["aDouble"]) == 0.1 and back["anInt"] == 7
    assert json.loads(back["aDict"]) == {"a": [1, 2]}
    np.testing.assert_array_equal(back["aV3d"], [0.1, 0.2, 0.3])
    assert attribute_number("0.25") == 0.25  # JSON text, as older files hold it
    text = describe(tmp_path / "t.exr")
    assert "aDouble: 0.10000000000000001" in text and "aV3d: 0.1 0.2 0.3" in text
    oiio = pytest.importorskip("OpenImageIO")
    spec = oiio.ImageInput.open(str(tmp_path / "t.exr")).spec()
    types = {a.name: str(a.type) for a in spec.extra_attribs}
    assert types["aFloat"] == "float" and types["aDouble"] == "double" and types["anInt"] == "int"
    assert types["aV3d"] == "vectord" and types["aM33f"] == "matrix33" and types["aDict"] == "string"
    assert types["chromaticities"] == "float[8]"
    assert spec.getattribute("aDouble") == 0.1


def test_radiance_attributes_are_typed_for_openimageio(written):
    oiio = pytest.importorskip("OpenImageIO")
    spec = oiio.ImageInput.open(str(written)).spec()
    types = {a.name: str(a.type) for a in spec.extra_attribs}
    assert types["spectracamSeed"] == types["spectracamSamplesPerPixel"] == "int"
    assert types["spectracamScene"] == types["spectracamRender"] == "string"  # nested: JSON text


def test_inspect_lists_every_part_of_a_multi_part_file(tmp_path):
    import OpenEXR

    def header():
        return {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}

    parts = [OpenEXR.Part(header(), {"R": np.ones((4, 5), np.float32)}, name="first"),
             OpenEXR.Part(header(), {"Z": np.zeros((4, 5), np.float32), "A": np.zeros((4, 5), np.float32)},
                          name="depth")]
    OpenEXR.File(parts).write(str(tmp_path / "mp.exr"))
    text = describe(tmp_path / "mp.exr")
    assert "this file has 2 parts" in text and "part 1 'depth': 5 x 4 pixels, channels A, Z" in text
