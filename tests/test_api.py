"""The Python API as the README shows it, and the bridges to colour-science (issue 12)."""
import re
from pathlib import Path

import numpy as np

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
