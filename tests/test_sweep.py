"""Design-space sweeps on Dask (issue 6)."""
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.experiments.sweep.experiment import load_sweep, run_sweep

BASE = (Path(__file__).parent.parent / "scenes" / "blackbody_5000K.toml").resolve()


def sweep_file(tmp_path, cutoffs=(480, 500, 10), temps=(3000, 6500), trials=2, extra=""):
    text = f"""
base_scene = "{BASE}"
renderer = "analytic"
trials = {trials}
seed = 7
metrics = ["delta_e_mean", "snr_combined_db", "capture_time_ms"]
[scene]
image = {{ width = 96, height = 72 }}
[axes]
"illuminant.temperature_K" = {list(temps)}
"filters.cutoffs_nm[0]" = {{ start = {cutoffs[0]}, stop = {cutoffs[1]}, step = {cutoffs[2]} }}
{extra}
"""
    p = tmp_path / "sweep.toml"
    p.write_text(text)
    return p


def read_table(out):
    import pyarrow.parquet as pq

    return pq.read_table(Path(out) / "results.parquet").to_pylist()


def test_sweep_file_validation(tmp_path):
    with pytest.raises(ConfigError, match="axes.filters.cutoffs_nm\\[0\\] = .*start ≤ stop"):
        load_sweep(sweep_file(tmp_path, cutoffs=(500, 480, 10)))
    with pytest.raises(ConfigError, match="sensor.adc_bits = 0"):  # every cell is validated up front
        load_sweep(sweep_file(tmp_path, extra='"sensor.adc_bits" = [8, 0]'))
    with pytest.raises(ConfigError, match="capture.exposure = 'optimal'"):
        load_sweep(sweep_file(tmp_path, extra='"capture.design" = ["cfa/single", "cfa/optimal"]'))
    sw = load_sweep(sweep_file(tmp_path, extra='"capture.design" = ["cfa/single", "fsc/optimal"]'))
    assert len(sw.cells()) == 2 * 3 * 2


def test_serial_and_two_worker_cluster_give_the_same_table(tmp_path):
    sw = load_sweep(sweep_file(tmp_path, extra='"capture.design" = ["cfa/single", "prism/optimal"]'))
    run_sweep(sw, tmp_path / "serial", serial=True, progress=False)
    t = run_sweep(sw, tmp_path / "dask", workers=2, progress=False)
    assert t["new_cells"] == 12
    a, b = read_table(tmp_path / "serial"), read_table(tmp_path / "dask")
    assert len(a) == 12 * 2 and a == b
    assert (tmp_path / "serial" / "results.csv").read_bytes() == (tmp_path / "dask" / "results.csv").read_bytes()
    row = a[0]
    assert {"cell", "trial", "seed", "axis:illuminant.temperature_K", "sensor.read_noise_e", "delta_e_mean"} <= set(row)
    # common random numbers: trial t has the same noise seed in every cell
    assert len({r["seed"] for r in a if r["trial"] == 1}) == 1


def test_killed_sweep_resumes_without_loss_or_duplicates(tmp_path):
    sw_path = sweep_file(tmp_path, cutoffs=(450, 530, 2), trials=3)  # 2 × 41 cells
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-m", "spectracam", "sweep", str(sw_path), "-o", str(out), "--serial",
                             "--quiet"])
    journal = out / "results.jsonl"
    deadline = time.time() + 120
    while time.time() < deadline:
        if journal.exists() and journal.read_bytes().count(b"\n") >= 30:
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    n_before = journal.read_bytes().count(b"\n")
    assert 30 <= n_before < 82 * 3, "the sweep should have been killed half way"
    with open(journal, "ab") as f:
        f.write(b'{"cell": 999, "tri')  # a line cut short by the kill
    r = subprocess.run([sys.executable, "-m", "spectracam", "sweep", str(sw_path), "-o", str(out), "--serial",
                        "--quiet"], capture_output=True, text=True)
    assert r.returncode == 2 and "--resume" in r.stderr
    r = subprocess.run([sys.executable, "-m", "spectracam", "sweep", str(sw_path), "-o", str(out), "--serial",
                        "--resume", "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    rows = read_table(out)
    keys = [(x["cell"], x["trial"]) for x in rows]
    assert len(keys) == len(set(keys)) == 82 * 3
    run_sweep(load_sweep(sw_path), tmp_path / "whole", serial=True, progress=False)
    assert rows == read_table(tmp_path / "whole")
    journal_rows = [json.loads(line) for line in journal.read_text().splitlines()]
    assert len(journal_rows) == 82 * 3  # nothing computed twice, the cut line dropped


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_for_port(port, timeout_s=60.0):
    """Until something listens on 127.0.0.1:``port`` (a scheduler just started), or fail after ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=1.0):
                return
        except OSError:
            if time.monotonic() > deadline:
                pytest.fail(f"nothing listens on 127.0.0.1:{port} after {timeout_s:g} s")
            time.sleep(0.2)


def test_sweep_through_a_separate_scheduler_and_worker(tmp_path):
    port = _free_port()
    addr = f"tcp://127.0.0.1:{port}"
    env = dict(os.environ, SPECTRACAM_THREADS="1")
    sched = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                              "--port", str(port), "--no-dashboard"], stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL, env=env)
    worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", addr, "--nworkers", "1",
                               "--nthreads", "1", "--no-dashboard", "--host", "127.0.0.1"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    try:
        _wait_for_port(port)   # the sweep starts faster than the scheduler binds its port (since issue 38's sixth
        sw_path = sweep_file(tmp_path)   # session it no longer imports colour-science): a race the test must not run
        r = subprocess.run([sys.executable, "-m", "spectracam", "sweep", str(sw_path), "-o", str(tmp_path / "remote"),
                            "--scheduler", addr, "--quiet"], capture_output=True, text=True, timeout=180)
        assert r.returncode == 0, r.stderr
        run_sweep(load_sweep(sw_path), tmp_path / "serial", serial=True, progress=False)
        assert read_table(tmp_path / "remote") == read_table(tmp_path / "serial")
    finally:
        for p in (worker, sched):
            p.terminate()
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()


def test_plot_sweep(tmp_path):
    sw = load_sweep(sweep_file(tmp_path))
    run_sweep(sw, tmp_path / "out", serial=True, progress=False)
    r = subprocess.run([sys.executable, "-m", "spectracam", "plot-sweep", str(tmp_path / "out"), "--x",
                        "filters.cutoffs_nm[0]", "--line", "illuminant.temperature_K"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    for m in ("delta_e_mean", "snr_combined_db", "capture_time_ms"):
        assert (tmp_path / "out" / "plots" / f"{m}.png").stat().st_size > 0
        assert (tmp_path / "out" / "plots" / f"{m}.svg").exists()
    bad = subprocess.run([sys.executable, "-m", "spectracam", "plot-sweep", str(tmp_path / "out"), "--x", "nope"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "must be one of the sweep's axes" in bad.stderr


@pytest.mark.parametrize("damage", ["cell 9999", "trial 99", "duplicate", "nan metric", "text metric",
                                    "edited parameter", "wrong seed"])
def test_resume_drops_journal_rows_that_cannot_belong(tmp_path, damage):
    """Issue 18: each damaged row is dropped with a warning and its cell computed again; the tables then
    hold exactly one row per cell and trial, equal to a clean run's."""
    from spectracam.experiments.sweep.experiment import load_sweep, run_sweep

    sw_path = sweep_file(tmp_path)  # 2 temperatures × 3 cutoffs, 2 trials
    sweep = load_sweep(sw_path)
    clean = tmp_path / "clean"
    run_sweep(sweep, clean, serial=True, progress=False)
    want = read_table(clean)
    lines = (clean / "results.jsonl").read_text().splitlines()
    row = json.loads(lines[0])
    edited = dict(row)
    if damage == "cell 9999":
        edited["cell"] = 9999
    elif damage == "trial 99":
        edited["trial"] = 99
    elif damage == "nan metric":
        edited["delta_e_mean"] = float("nan")
    elif damage == "text metric":
        edited["delta_e_mean"] = "five"
    elif damage == "edited parameter":
        edited["sensor.read_noise_e"] = 0.0
    elif damage == "wrong seed":
        edited["seed"] = 12345
    run = tmp_path / "run"
    run.mkdir()
    (run / "sweep.json").write_text((clean / "sweep.json").read_text())
    body = lines + [json.dumps(edited)] if damage == "duplicate" else [json.dumps(edited)] + lines[1:]
    (run / "results.jsonl").write_text("\n".join(body) + "\n")
    notes = []
    t = run_sweep(sweep, run, serial=True, resume=True, progress=False, log=notes.append)
    assert any("do not belong to this sweep" in n for n in notes), notes
    assert t["new_cells"] == 1  # only row 0's cell is computed again
    got = read_table(run)
    assert len(got) == len(want) and [(r["cell"], r["trial"]) for r in got] == [(r["cell"], r["trial"]) for r in want]
    assert [r["delta_e_mean"] for r in got] == [r["delta_e_mean"] for r in want]


def test_a_damaged_sweep_json_is_not_called_another_sweep(tmp_path):
    from spectracam.experiments.sweep.experiment import load_sweep, run_sweep

    sweep = load_sweep(sweep_file(tmp_path))
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "sweep.json").write_text('{"digest": "abc", ')
    with pytest.raises(SpectracamError, match="sweep.json is damaged"):
        run_sweep(sweep, tmp_path / "run", serial=True, resume=True, progress=False)


@pytest.mark.parametrize("axis, message", [
    ("{ start = 450, stop = nan, step = 10 }", "finite numbers"),
    ("{ start = 450, stop = inf, step = 10 }", "finite numbers"),
    ("{ start = 450, stop = 460, step = 1e-300 }", r"gives 1e\+301 values, more than --max-cells"),
])
def test_axis_ranges_are_checked_before_any_value_is_made(tmp_path, axis, message):
    from spectracam.experiments.sweep.experiment import load_sweep

    p = sweep_file(tmp_path)
    p.write_text(p.read_text().replace("{ start = 480, stop = 500, step = 10 }", axis))
    t = time.perf_counter()
    with pytest.raises(ConfigError, match=message):
        load_sweep(p)
    assert time.perf_counter() - t < 5


def test_two_runs_in_one_directory_at_once_are_refused(tmp_path):
    """Issue 18: two --resume runs at once both computed the same cells; the journal is locked."""
    import subprocess

    from spectracam.experiments.sweep.experiment import _lock_journal, load_sweep, run_sweep

    sw_path = sweep_file(tmp_path)
    sweep = load_sweep(sw_path)
    run_sweep(sweep, tmp_path / "o", serial=True, progress=False, stop_after=1)
    held = _lock_journal(tmp_path / "o" / "results.jsonl")  # another run holds it (a separate open file)
    try:
        r = subprocess.run([sys.executable, "-m", "spectracam", "sweep", str(sw_path), "-o", str(tmp_path / "o"),
                            "--serial", "--resume", "--quiet"], capture_output=True, text=True)
        assert r.returncode == 2 and "another spectracam sweep is running" in r.stderr, r.stderr
    finally:
        held.close()
    t = run_sweep(sweep, tmp_path / "o", serial=True, resume=True, progress=False)  # free again
    assert t["new_cells"] == t["cells"] - 1


def _synthetic_sweep(noise, xs=(450, 470, 490, 510, 530), temps=(6500, 3000)):
    """A sweep's meta and rows without running it: mean ΔE = 1 + |x − 490|/10 + |noise − 3| + (T = 6500),
    two trials ±0.1 about it, so the best cell is x = 490 nm on the 3 e⁻ line in each panel."""
    meta = {"axes": [["illuminant.temperature_K", list(temps)], ["filters.cutoffs_nm[0]", list(xs)],
                     ["sensor.read_noise_e", list(noise)]], "metrics": ["delta_e_mean"], "trials": 2,
            "base_values": {"illuminant.temperature_K": 5000, "filters.cutoffs_nm[0]": 490,
                            "sensor.read_noise_e": 3}}
    rows = [{"axis:illuminant.temperature_K": T, "axis:filters.cutoffs_nm[0]": x, "axis:sensor.read_noise_e": n,
             "trial": k, "delta_e_mean": 1 + abs(x - 490) / 10 + abs(n - 3) + (T == 6500) + (0.1 if k else -0.1)}
            for T in temps for n in noise for x in xs for k in (0, 1)]
    return meta, rows


def test_sweep_figure_legend_order_colours_and_best_line():
    """The legend came in string order (10 before 2) and the best cell's line could not be told: lines
    are listed and coloured in the line variable's numeric order, the legend sits beside the axes in
    columns, the best cell is annotated with its value, x and line, and its line is the thick one."""
    import matplotlib.pyplot as plt
    from matplotlib.text import Text

    from spectracam.experiments.sweep.plot import natural_key, sweep_figure

    noise = [10, 2, 0.5, 100, 3, 1.5, 20, 5, 1, 50, 15, 7, 0.2, 30]  # 14 lines, scrambled, "10" < "2" as text
    meta, rows = _synthetic_sweep(noise)
    fig = sweep_figure(meta, rows, "delta_e_mean", "filters.cutoffs_nm[0]", "sensor.read_noise_e",
                       "illuminant.temperature_K")
    fig.canvas.draw()
    leg = fig.legends[0]
    labels = [t.get_text() for t in leg.get_texts()]
    assert labels[:len(noise)] == [str(v) for v in sorted(noise)]
    assert labels[len(noise):] == ["the base scene", "best (annotated;\nits line thick)"]
    assert leg.get_title().get_text() == "read noise (e⁻)"
    # the colours follow the order: viridis, darkest for the smallest value
    lum = [0.2126 * r + 0.7152 * g + 0.0722 * b for r, g, b, _ in (h.get_color() for h in leg.legend_handles[:len(noise)])]
    assert all(a < b for a, b in zip(lum, lum[1:])), lum
    # beside the axes, inside the figure, in more than one column
    box, fig_box = leg.get_window_extent(), fig.bbox
    assert box.x0 >= max(ax.get_window_extent().x1 for ax in fig.axes) and box.x1 <= fig_box.x1 + 1
    assert box.y0 >= fig_box.y0 and box.y1 <= fig_box.y1 and box.width > 2 * leg.get_texts()[0].get_window_extent().width
    assert [ax.get_title() for ax in fig.axes] == ["colour temperature = 3000 K", "colour temperature = 6500 K"]
    handle_colour = dict(zip(labels, (tuple(h.get_color()) for h in leg.legend_handles)))
    for ax, best in zip(fig.axes, ("1", "2")):
        notes = [t.get_text() for t in ax.texts]
        assert any(n.startswith(f"best: {best}\n") and "blue/green cutoff = 490 nm" in n and "read noise = 3 e⁻" in n
                   for n in notes), notes
        thick = max(ax.lines, key=lambda ln: ln.get_linewidth())
        assert tuple(thick.get_color()) == handle_colour["3"]
        assert sorted(ln.get_linewidth() for ln in ax.lines if ln.get_linestyle() != "None")[-2] < thick.get_linewidth()
    small = [t.get_text() for t in fig.findobj(Text) if t.get_text().strip() and t.get_fontsize() < 8]
    assert not small, small
    plt.close(fig)
    # text values in natural order, numbers by value
    assert sorted(["fsc 10", "fsc 9", "cfa", "fsc 100"], key=natural_key) == ["cfa", "fsc 9", "fsc 10", "fsc 100"]
    assert sorted([10, 9.5, 100, 2], key=natural_key) == [2, 9.5, 10, 100]
