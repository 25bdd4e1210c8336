"""The Python API as the README shows it, and the bridges to colour-science (issue 12)."""
import re
from pathlib import Path

import numpy as np
import pytest

README = Path(__file__).resolve().parent.parent / "README.md"


def test_readme_example_runs(tmp_path, monkeypatch):
    code = re.search(r"```python\n(.*?)```", README.read_text(), re.S).group(1)
    monkeypatch.chdir(README.parent)
    namespace = {}
    exec(compile(code.replace("640", "160").replace("480", "120"), "README example", "exec"), namespace)
    assert namespace["result"].summary.delta_e_mean > 0


def test_colour_science_bridges():
    import colour

    import spectracam
    from spectracam.camera import CameraSpec

    scene = spectracam.parse_scene({})
    msds = spectracam.patch_spectra(scene)
    assert isinstance(msds, colour.MultiSpectralDistributions) and msds.values.shape == (30, 24)
    sens = spectracam.camera_sensitivities(CameraSpec(), scene.grid)
    assert isinstance(sens, colour.characterisation.RGB_CameraSensitivities)
    # block filters 490/610 nm with a flat QE of 0.5: green passes exactly 495-605 nm
    g = sens.values[:, 1]
    np.testing.assert_allclose(g[(sens.wavelengths > 490) & (sens.wavelengths < 610)], 0.5)


# -- wrong argument types fail at the API's boundary, naming the argument, the type given and what is allowed --


@pytest.fixture(scope="module")
def small():
    import spectracam

    scene = spectracam.parse_scene({"image": {"width": 64, "height": 48}})
    cube = spectracam.render(scene, "analytic")
    return scene, cube, spectracam.capture(cube)


def _wrong_type_cases(scene, cube, raw):
    import spectracam

    return [
        (lambda: spectracam.load_scene({"image": {}}), "load_scene(path)", "dict", "parse_scene"),
        (lambda: spectracam.load_scene(3), "load_scene(path)", "int", "path"),
        (lambda: spectracam.load_scene("scenes/d65.toml", "image.width=64"), "load_scene(overrides)", "str", "list"),
        (lambda: spectracam.parse_scene("scenes/d65.toml"), "parse_scene(data)", "str", "load_scene"),
        (lambda: spectracam.parse_scene(Path("scenes/d65.toml")), "parse_scene(data)", "PosixPath", "dict"),
        (lambda: spectracam.render({"image": {}}, "analytic"), "render(scene)", "dict", "parse_scene"),
        (lambda: spectracam.render("scenes/d65.toml"), "render(scene)", "str", "load_scene"),
        (lambda: spectracam.render(scene, 3), "render(renderer)", "int", "'analytic'"),
        (lambda: spectracam.render(scene, "analytic", log="x"), "render(log)", "str", "function"),
        (lambda: spectracam.capture(np.zeros((4, 4, 30))), "capture(cube)", "ndarray", "RadianceCube"),
        (lambda: spectracam.capture(5), "capture(cube)", "int", "RadianceCube"),
        (lambda: spectracam.capture(scene), "capture(cube)", "Scene", "spectracam.render(scene)"),
        (lambda: spectracam.capture((cube, {})), "capture(cube)", "tuple", "[0]"),
        (lambda: spectracam.capture(cube, scene), "capture(camera)", "Scene", "CameraSpec"),
        (lambda: spectracam.capture(cube, {"sensor": {}}), "capture(camera)", "dict", "CameraSpec"),
        (lambda: spectracam.capture(cube, seed="1"), "capture(seed)", "str", "integer"),
        (lambda: spectracam.capture(cube, seed=1.5), "capture(seed)", "float", "integer"),
        (lambda: spectracam.capture(cube, scene={"image": {}}), "capture(scene)", "dict", "Scene"),
        (lambda: spectracam.capture(cube, sensor={"adc_bits": 12}), "capture(sensor)", "dict", "SensorSpec"),
        (lambda: spectracam.capture(cube, design=3), "capture(design)", "int", "fsc/optimal"),
        (lambda: spectracam.score(cube), "score(raw)", "RadianceCube", "RawCapture"),
        (lambda: spectracam.score("raw.exr"), "score(raw)", "str", "read_raw_exr"),
        (lambda: spectracam.score(raw, {"image": {}}), "score(scene)", "dict", "Scene"),
        (lambda: spectracam.score(raw, processing={"demosaic": "patch"}), "score(processing)", "dict",
         "ProcessingSpec"),
        (lambda: spectracam.simulate({"image": {}}, "analytic"), "simulate(scene)", "dict", "Scene"),
        (lambda: spectracam.simulate("d65", "analytic"), "simulate(scene)", "str", "load_scene"),
        (lambda: spectracam.simulate(scene, "analytic", seed="0"), "simulate(seed)", "str", "integer"),
        (lambda: spectracam.patch_spectra({}), "patch_spectra(scene)", "dict", "Scene"),
        (lambda: spectracam.camera_sensitivities({}, scene.grid), "camera_sensitivities(camera)", "dict",
         "CameraSpec"),
        (lambda: spectracam.camera_sensitivities(scene.camera, 3), "camera_sensitivities(grid)", "int",
         "WavelengthGrid"),
    ]


def test_wrong_argument_types_name_the_argument_the_type_and_what_is_allowed(small):
    from spectracam.core.errors import ArgumentTypeError, SpectracamError

    for call, where, given, allowed in _wrong_type_cases(*small):
        with pytest.raises(TypeError) as e:
            call()
        msg = str(e.value)
        assert isinstance(e.value, ArgumentTypeError) and isinstance(e.value, SpectracamError), (where, msg)
        assert msg.startswith(f"{where}: got {given}") and "allowed:" in msg and allowed in msg, msg
        assert "\n" not in msg


def test_right_types_still_work(small):
    import spectracam

    scene, cube, raw = small
    raw2 = spectracam.capture(cube, scene.camera, np.int64(3), scene=scene, sensor=scene.camera.sensor,
                              design="cfa/single")
    assert spectracam.score(raw2, scene, scene.processing).summary.delta_e_mean > 0
    assert spectracam.load_scene(README.parent / "scenes" / "d65.toml", ["image.width=64"]).image.width == 64


def test_the_version_lives_below_the_stages_and_matches_the_package_metadata():
    """Stages import the version from ``spectracam._version`` (no import back up to the package ``__init__``, issue
    35), and it equals pyproject.toml's, which the wheel's metadata carries."""
    import ast
    import tomllib
    from pathlib import Path

    import spectracam
    from spectracam._version import __version__

    root = Path(spectracam.__file__).parent
    assert spectracam.__version__ == __version__
    with open(root.parent / "pyproject.toml", "rb") as f:
        assert tomllib.load(f)["project"]["version"] == __version__
    upward = []
    for path in root.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level > 0 and node.module is None \
                    and any(a.name == "__version__" for a in node.names):
                upward.append(str(path.relative_to(root)))
    assert not upward, f"import __version__ from spectracam._version instead: {upward}"


def test_load_scene_takes_a_shipped_name_from_any_directory(monkeypatch, tmp_path):
    """``load_scene("d65")`` and the README's ``"scenes/d65.toml"`` work outside the checkout, as the CLI's names do."""
    import spectracam

    monkeypatch.chdir(tmp_path)
    for name in ("d65", "d65.toml", "scenes/d65.toml"):
        assert spectracam.load_scene(name).illuminant.name == "D65"
    (tmp_path / "d65.toml").write_text('name = "mine"\n[illuminant]\ntype = "cie"\nname = "A"\n')
    assert spectracam.load_scene("d65.toml").illuminant.name == "A"        # a file that exists comes first
    with pytest.raises(spectracam.core.errors.ConfigError, match="cannot be read"):
        spectracam.load_scene("nosuch")
