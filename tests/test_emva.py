"""EMVA 1288 run on the simulated camera recovers the configured camera (issue 10)."""
import json

import pytest
from click.testing import CliRunner

from spectracam.camera import CameraSpec
from spectracam.cli import main
from spectracam.experiments.emva import KEYS, run_emva
from spectracam.sensor import SensorSpec


@pytest.mark.parametrize("sensor", [SensorSpec(), SensorSpec(adc_bits=12, prnu_fraction=0.01, dsnu_fraction=0.2)],
                         ids=["default 8-bit", "12-bit with PRNU and DSNU"])
def test_measured_recovers_configured(sensor):
    r = run_emva(CameraSpec(sensor=sensor))
    c, m = r["configured"], r["measured"]
    for k in KEYS:
        if k == "linearity_error_percent":
            assert m[k] < 0.01  # a linear sensor: LE of the noise alone
        elif c[k] == 0:  # no PRNU configured: not measurable (the spatial variance is temporal noise)
            assert m[k] is None or m[k] < 0.1
        elif k.endswith("_db"):
            assert m[k] == pytest.approx(c[k], abs=0.17), k  # 2 % in amplitude
        else:
            assert m[k] == pytest.approx(c[k], rel=0.02), k
    # the 8-bit camera's dark noise is below the quantisation: the standard's upper limit, 0.40/K
    assert r["notes"]["dark_noise_is_upper_limit"] == (sensor.adc_bits == 8)


def test_emva_command_writes_the_datasheet(tmp_path):
    r = CliRunner().invoke(main, ["emva", "-o", str(tmp_path), "--quiet", "--set", "sensor.adc_bits=10"])
    assert r.exit_code == 0, r.output
    data = json.loads((tmp_path / "emva.json").read_text())
    assert set(data["configured"]) == set(data["measured"]) == set(KEYS)
    assert data["camera"]["sensor"]["adc_bits"] == 10 and "--set sensor.adc_bits=10" in data["command"]
    for f in ("datasheet.md", "photon_transfer.png", "snr.svg", "linearity.png"):
        assert (tmp_path / f).exists()
    assert "| system gain K | DN/e⁻ |" in (tmp_path / "datasheet.md").read_text()
