"""The map of the paper's open choices (issue 10): readings, recalibrated light, verdicts, outputs."""
import json

import pytest

import spectracam.experiments.consistency as cons
from spectracam.experiments.paper import load_experiment


@pytest.fixture
def small_map(monkeypatch):
    monkeypatch.setattr(cons, "FACTORS", {"QE": cons.FACTORS["QE"][:2], "FPN < 1 %": cons.FACTORS["FPN < 1 %"][:1],
                                          "FPN across channels": cons.FACTORS["FPN across channels"][:1],
                                          "ADC at code 0": cons.FACTORS["ADC at code 0"][:1]})
    monkeypatch.setattr(cons, "ONE_AT_A_TIME", cons.ONE_AT_A_TIME[-1:])


def test_readings_cover_the_factorial_and_the_one_at_a_time_choices():
    rs = cons.readings()
    n = 1
    for v in cons.FACTORS.values():
        n *= len(v)
    assert len(rs) == n + len(cons.ONE_AT_A_TIME) and rs[0].values == {k: v[0][0] for k, v in cons.FACTORS.items()}
    assert rs[-1].light_scale == 0.1 and rs[-1].values["light level"].startswith("10×")


def test_consistency_map(small_map, tmp_path):
    exp = load_experiment(cons.__file__.replace("spectracam/experiments/consistency.py", "scenes/paper.toml"))
    r = cons.run_consistency(exp)
    assert len(r["rows"]) == 3
    shallow, flat, dim = r["rows"]
    # the light is recalibrated per reading: cfa/single needs 28 ms at 5000 K for every QE
    for row in (shallow, flat):
        assert "28 ms" in row["measured"]["exposure"] or "/ 28 ms" in row["measured"]["exposure"]
    assert dim["white_luminance_cd_m2"] == pytest.approx(0.1 * shallow["white_luminance_cd_m2"])
    # the Figure 4 verdict turns on the QE: a shallow photodiode's red falls below green, a flat QE's does not
    assert shallow["verdicts"]["fig4-green"] == "reproduced" and flat["verdicts"]["fig4-green"] == "not"
    paths = cons.write_consistency_outputs(tmp_path, r, "test")
    assert {p.name for p in paths} == {"consistency.png", "consistency.svg", "consistency.json", "consistency.md"}
    assert json.loads((tmp_path / "consistency.json").read_text())["best"] == 0


def test_a_reading_with_another_spectral_range_is_rendered_on_that_range(monkeypatch):
    """Issue 18's planted slip: the cubes keyed on something other than the grid let the 380–730 nm
    reading run silently on 400–700 nm cubes.  Every capture must see the reading's own bands."""
    import spectracam.experiments.paper as paper

    monkeypatch.setattr(cons, "FACTORS", {k: v[:1] for k, v in cons.FACTORS.items()})
    monkeypatch.setattr(cons, "ONE_AT_A_TIME", [r for r in cons.ONE_AT_A_TIME if r[0] == "spectral range"])
    seen = []
    real = paper.design_case

    def spy(cube, scene, *args, **kwargs):
        seen.append((cube.grid.edges_nm[0], cube.grid.edges_nm[-1], scene.grid.edges_nm[0], scene.grid.edges_nm[-1]))
        return real(cube, scene, *args, **kwargs)

    monkeypatch.setattr(paper, "design_case", spy)
    exp = load_experiment(cons.__file__.replace("spectracam/experiments/consistency.py", "scenes/paper.toml"))
    cons.run_consistency(exp)
    ranges = {(a, b) for a, b, c, d in seen}
    assert ranges == {(400.0, 700.0), (380.0, 730.0)}, ranges
    assert all((a, b) == (c, d) for a, b, c, d in seen)  # the cube's bands are always its scene's
