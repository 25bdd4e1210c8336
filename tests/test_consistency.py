"""The map of the paper's open choices (issue 10): readings, recalibrated light, verdicts, outputs."""
import json

import pytest

import spectracam.experiments.consistency.experiment as cons
from spectracam.experiments.paper.experiment import load_experiment


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
    exp = load_experiment(cons.__file__.replace("spectracam/experiments/consistency/experiment.py", "scenes/paper.toml"))
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
    # every claim's sentence is recorded for the figure's key
    assert set(r["claim_text"]) == set(r["claims"]) and "green" in r["claim_text"]["fig4-green"]


def test_a_reading_with_another_spectral_range_is_rendered_on_that_range(monkeypatch):
    """Issue 18's planted slip: the cubes keyed on something other than the grid let the 380–730 nm
    reading run silently on 400–700 nm cubes.  Every capture must see the reading's own bands."""
    import spectracam.experiments.paper.experiment as paper

    monkeypatch.setattr(cons, "FACTORS", {k: v[:1] for k, v in cons.FACTORS.items()})
    monkeypatch.setattr(cons, "ONE_AT_A_TIME", [r for r in cons.ONE_AT_A_TIME if r[0] == "spectral range"])
    seen = []
    real = paper.design_case

    def spy(cube, scene, *args, **kwargs):
        seen.append((cube.grid.edges_nm[0], cube.grid.edges_nm[-1], scene.grid.edges_nm[0], scene.grid.edges_nm[-1]))
        return real(cube, scene, *args, **kwargs)

    monkeypatch.setattr(paper, "design_case", spy)
    exp = load_experiment(cons.__file__.replace("spectracam/experiments/consistency/experiment.py", "scenes/paper.toml"))
    cons.run_consistency(exp)
    ranges = {(a, b) for a, b, c, d in seen}
    assert ranges == {(400.0, 700.0), (380.0, 730.0)}, ranges
    assert all((a, b) == (c, d) for a, b, c, d in seen)  # the cube's bands are always its scene's


def _text_artists(fig):
    from matplotlib.text import Text

    return [t for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip()]


def test_consistency_figure_is_readable_and_explains_its_codes():
    """The map's labels were 5 pt and its claim codes unexplained: every text is ≥ 8 pt, the rows are
    at least a line of 8 pt apart, the choices are named over their columns, and a key gives every
    claim code its claim."""
    from matplotlib.patches import Rectangle

    claims = ["fig4-green", "exposure", "de-prism", "fig6-main"]
    verdicts = ("reproduced", "partly", "not")
    rows = [{"reading": r.values, "verdicts": {c: verdicts[(i + j) % 3] for j, c in enumerate(claims)}}
            for i, r in enumerate(cons.readings())]
    text = {"fig4-green": "CFA, one exposure: only green responds optimally (saturates)",
            "exposure": "FSC with per-channel exposures needs ~4x the CFA's time",
            "de-prism": "the dichroic prism matches the FSC in ΔE*ab", "fig6-main": "the main sources are CMOS noise"}
    fig = cons.consistency_figure({"rows": rows, "claims": claims, "claim_text": text, "best": 7})
    fig.canvas.draw()
    texts = _text_artists(fig)
    small = [(t.get_text(), t.get_fontsize()) for t in texts if t.get_fontsize() < 8]
    assert not small, small
    ax = fig.axes[0]
    assert [t.label1.get_text() for t in ax.xaxis.get_major_ticks()] == claims  # under the columns, and over
    assert all(t.get_fontsize() >= 8 for t in ax.get_xticklabels() + ax.get_yticklabels())
    assert ax.get_window_extent().height / fig.dpi * 72 / len(rows) >= 1.2 * 8  # points per row
    shown = [" ".join(t.get_text().split()) for t in texts]
    assert set(cons.FACTORS) <= set(shown)  # each choice named over its column
    assert "photodiode 2 µm" in shown and "pixel: 5 µm pixel" in shown
    # the key: every code, each beside its claim (from claims.evaluate)
    key = [t.get_text() for t in fig.texts]
    assert all(key.count(c) == 1 for c in claims), key
    for code, words in (("fig4-green", "only green responds optimally"), ("exposure", "~4x the CFA's time"),
                        ("de-prism", "the dichroic prism matches the FSC"), ("fig6-main", "CMOS noise")):
        i = key.index(code)
        assert words in key[i + 1], (code, key[i + 1])
    # the two outlined rows: the experiment's reading (row 0) and the one with most claims reproduced
    outlines = {(round(p.get_y() + 0.5), p.get_edgecolor()[:3]) for p in ax.patches if isinstance(p, Rectangle)}
    assert (0, (0.0, 0.0, 0.0)) in outlines and 7 in {y for y, c in outlines if c != (0.0, 0.0, 0.0)}
    import matplotlib.pyplot as plt

    plt.close(fig)
