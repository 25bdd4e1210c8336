"""Design-space sweeps on Dask: every combination of the axes, with noise trials.

A sweep file names a base scene, the axes to vary (any scene, optics, filter, sensor, capture or
processing parameter, by its ``table.field`` path, ``table.field[i]`` for one element of a list),
the metrics to record and the number of noise trials.  Each combination is a *cell*: one Dask task
that captures and scores all of its trials.  Cells that see the same radiance (same render-relevant
scene) share one render, done once in the driver (through the render cache) and scattered.

Rows (one per cell and trial, every parameter and metric) are appended to ``results.jsonl`` as
cells finish; ``--resume`` skips the cells already there, so none is lost or computed twice.
``results.parquet`` and ``results.csv`` are the same rows sorted by (cell, trial).
"""
from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypedDict

import numpy as np

from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.core.files import atomic_write
from spectracam.pipeline.overrides import DESIGN_PATH, PATH, apply_override, apply_overrides, parse_assignment
from spectracam.pipeline.scene_file import Scene, load_scene, parse_scene, read_toml
from spectracam.evaluation.score import SUMMARY_METRICS
from spectracam.evaluation.usability import UsabilitySpec

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable

    from spectracam.render import RadianceCube

__all__ = ["DESIGN_AXIS", "HANDSHAKE_TIMEOUT_S", "HELD_OUT_METRICS", "MAX_CELLS", "METRICS",
           "SCHEDULER_TIMEOUT_S", "SWEEP_KEYS", "TASK_RETRIES", "Sweep", "SweepResult", "base_value", "cell_scene",
           "cells_per_task", "check_meterable", "finished_cells", "load_sweep", "probe_scheduler",
           "run_cell", "run_cells", "run_sweep", "trial_seed"]

#: Held-out metrics (spectracam.evaluation.heldout): the conversion's noise-free error on processing.held_out's
#: colours, which it was not fitted on, and the 95th percentile of its error on the chart it was.
HELD_OUT_METRICS = ("held_out_delta_e_mean", "held_out_delta_e_p95", "held_out_delta_e_max", "delta_e_conversion_p95")
#: What a sweep can record: every field of the chart summary (S-CIELAB beside ΔE*ab: s_cielab_mean, s_cielab_p95),
#: and the held-out scores.  Every row also carries ``usable`` and ``unusable_reason`` (.usability, its defaults):
#: whatever the metrics, a trial that is no usable image says so, and no best cell is named from it.
METRICS = SUMMARY_METRICS + HELD_OUT_METRICS
DESIGN_AXIS = DESIGN_PATH  # "arch/scheme" in one value, so invalid pairs are never crossed
#: How long to wait for an external Dask scheduler before giving up, s.
SCHEDULER_TIMEOUT_S = 10
#: The most cells a sweep may have unless --max-cells raises it (validation costs ~1 ms a cell).
MAX_CELLS = 100_000
#: Keys of a sweep file (``--set`` paths starting with one of these name the sweep; any other path
#: names a field of the base scene).
SWEEP_KEYS = ("base_scene", "scene", "axes", "metrics", "trials", "seed", "renderer")


@dataclass(frozen=True)
class Sweep:
    base: dict  # the base scene as a dict, [scene] overrides applied
    axes: tuple  # ((path, (values...)), ...)
    metrics: tuple
    trials: int
    seed: int
    renderer: str
    source: str
    #: Found while every cell is validated (load_sweep): the largest cell scene and how many distinct
    #: renders the cells need — what a run holds in memory at once.
    largest_scene: Scene | None = dataclasses.field(default=None, compare=False)
    distinct_renders: int = dataclasses.field(default=0, compare=False)

    @property
    def digest(self) -> str:
        text = json.dumps({"base": self.base, "axes": self.axes, "metrics": self.metrics, "trials": self.trials,
                           "seed": self.seed, "renderer": self.renderer}, sort_keys=True, default=list)
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def cells(self) -> list[dict]:
        names = [p for p, _ in self.axes]
        return [dict(zip(names, combo)) for combo in itertools.product(*(v for _, v in self.axes))]


def _axis_values(t: dict | list, field: str, source: str, max_values: int = MAX_CELLS) -> tuple:
    if isinstance(t, list) and t:
        return tuple(t)
    if isinstance(t, dict) and set(t) == {"start", "stop", "step"}:
        a, b, s = (t[k] for k in ("start", "stop", "step"))
        if (not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in (a, b, s))
                or s <= 0 or b < a):
            raise ConfigError(field, t, "a range needs finite numbers start ≤ stop and step > 0", source)
        count = (b - a) / s + 1
        if not count <= max_values:  # counted before a single value is made (a step of 1e-300)
            raise ConfigError(field, t, f"gives {count:.3g} values, more than --max-cells = {max_values}", source)
        n = int(math.floor((b - a) / s + 1e-9)) + 1
        vals = [a + i * s for i in range(n)]
        return tuple(int(v) if all(isinstance(x, int) for x in (a, b, s)) else float(v) for v in vals)
    raise ConfigError(field, t, "must be a non-empty list of values or a table {start, stop, step}", source)


def load_sweep(path: str | Path, overrides: Iterable[str | tuple[str, object]] = (), max_cells: int = MAX_CELLS,
               log: Callable[[str], object] = lambda m: None, progress: bool = True) -> Sweep:
    """Read and validate a sweep file; every cell's scene is validated here, before anything runs.
    ``overrides`` (``--set``): a path whose table is a sweep key changes the sweep, any other the
    base scene.

    Parameters
    ----------
    path : str or Path
        The sweep file.
    overrides : iterable of str or (str, object)
        ``PATH=VALUE`` strings or ``(path, value)`` pairs.
    max_cells : int
        ``--max-cells``: more cells are refused.
    log : callable
        ``log(line)``: the number of cells and trials.
    progress : bool
        A bar over the cells' validation.

    Returns
    -------
    Sweep
        With its largest scene and the number of distinct renders.

    Raises
    ------
    ConfigError
        On an invalid key or value, a cell that cannot be metered, or more cells than ``max_cells``.
    """
    p = Path(path)
    pairs = [parse_assignment(o) if isinstance(o, str) else o for o in overrides]
    mine = [(k, v) for k, v in pairs if k.split(".")[0].split("[")[0] in SWEEP_KEYS]
    scene_overrides = [(k, v) for k, v in pairs if (k, v) not in mine]
    data = apply_overrides(read_toml(p, "sweep file"), mine)
    src = str(p)
    _check_sweep_keys(data, src)
    base = _base_scene(p, data, scene_overrides, src)
    axes = _sweep_axes(data, src, max_cells)
    metrics, trials, seed = _sweep_settings(data, base, src)
    renderer = _sweep_renderer(data, src)
    sweep = Sweep(base, tuple(axes), tuple(metrics), trials, seed, renderer, src)
    n = math.prod(len(v) for _, v in axes)
    log(f"{n} cells × {trials} trial(s)")
    if n > max_cells:
        raise ConfigError("axes", f"{n} cells", f"more than --max-cells = {max_cells}; raise it if this is meant",
                          src)
    largest, renders = _validate_cells(sweep, n, log, progress)
    return dataclasses.replace(sweep, largest_scene=largest, distinct_renders=renders)


def _check_sweep_keys(data: dict, src: str) -> None:
    """Refuse an unknown key of a sweep file, or a known one of the wrong type."""
    known = set(SWEEP_KEYS)
    for k in data:
        if k not in known:
            raise ConfigError(k, data[k], "unknown key; a sweep file has " + ", ".join(sorted(known)), src)
    for key, kind, name in (("base_scene", str, "a path to a scene file"), ("scene", dict, "a table of scene tables"),
                            ("axes", dict, "a table of axis = values")):
        if key in data and not isinstance(data[key], kind):
            raise ConfigError(key, data[key], f"must be {name}", src)


def _base_scene(p: Path, data: dict, scene_overrides: list, src: str) -> dict:
    """The base scene as a dict: its file, then the sweep's ``[scene]`` tables, then ``--set``."""
    scene_file = p.parent / data.get("base_scene", "blackbody_5000K.toml")
    wavelength_sets = [kv for kv in scene_overrides if kv[0].split(".")[0] == "wavelengths"]
    base = load_scene(scene_file, wavelength_sets).to_dict()  # a grid is set in the file's own terms
    for table, values in data.get("scene", {}).items():
        if table not in base or not isinstance(values, dict):
            raise ConfigError(f"scene.{table}", values, "must be a table of the scene file", src)
        base[table].update(values)
    others = [kv for kv in scene_overrides if kv not in wavelength_sets]
    if others:  # --set comes last: over the base scene and the sweep's own [scene] table
        from spectracam.pipeline.scene_file import parse_scene, resolve_curve_files

        merged = resolve_curve_files(apply_overrides(base, others, defaults=lambda: base, source="--set"), Path.cwd())
        base = parse_scene(merged, f"{src} with --set").to_dict()
    return base


def _sweep_axes(data: dict, src: str, max_cells: int) -> list:
    """The sweep's axes, ``[(path, (values...)), ...]``; at least one."""
    axes = []
    for field, spec in data.get("axes", {}).items():
        if field != DESIGN_AXIS and not PATH.match(field):
            raise ConfigError(f"axes.{field}", spec, "an axis is a 'table.field' or 'table.field[i]' path", src)
        axes.append((field, _axis_values(spec, f"axes.{field}", src, max_cells)))
    if not axes:
        raise ConfigError("axes", {}, "needs at least one axis", src)
    return axes


def _sweep_settings(data: dict, base: dict, src: str) -> tuple:
    """The sweep's metrics, number of trials and seed, checked."""
    metrics = data.get("metrics", ["delta_e_mean", "snr_combined_db"])
    bad = [m for m in metrics if m not in METRICS] if isinstance(metrics, list) else [metrics]
    if bad or not metrics:
        raise ConfigError("metrics", metrics, "must be a list drawn from " + ", ".join(METRICS), src)
    trials = data.get("trials", 1)
    if isinstance(trials, bool) or not isinstance(trials, int) or not 1 <= trials <= 10000:
        raise ConfigError("trials", trials, "must be an integer between 1 and 10000", src)
    seed = data.get("seed", base["render"]["seed"])
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= 2**31 - 1:
        raise ConfigError("seed", seed, "must be an integer between 0 and 2147483647", src)
    return metrics, trials, seed


def _sweep_renderer(data: dict, src: str) -> str:
    """The sweep's renderer, one of the registered renderers."""
    from spectracam.render import RENDERERS

    renderer = data.get("renderer", "mitsuba")
    try:
        RENDERERS.check(renderer)
    except ConfigError as e:
        raise e.with_source(src) from None
    return renderer


def _validate_cells(sweep: Sweep, n: int, log, progress: bool) -> tuple:
    """Validate every cell's scene; returns the largest one and how many distinct renders they need."""
    from spectracam.io.cache import RENDER_TABLES

    from spectracam.core.progress import Counter

    src, metrics = sweep.source, sweep.metrics
    largest, renders = None, set()
    # a bar, or lines when piped, and an estimate up front: validating 100 000 cells takes minutes
    checking = Counter(n, desc="validating cells", unit="cell", log=log, progress=progress)
    for i, cell in checking.iterate(enumerate(sweep.cells())):
        scene = cell_scene(sweep, cell, i)  # validate every combination now
        if scene.target.textured:
            raise ConfigError("target.kind", scene.target.kind, "a sweep scores the ColorChecker; a textured target is "
                              f"scored by simulate or score (cell {i})", src)
        check_meterable(scene, cell, i, src)
        wanted = [m for m in metrics if m in HELD_OUT_METRICS]
        if wanted and scene.processing.held_out == "none":
            raise ConfigError("metrics", wanted, f"need processing.held_out (it is 'none' in cell {i})", src)
        d = scene.to_dict()
        renders.add(json.dumps({k: d[k] for k in RENDER_TABLES}, sort_keys=True))
        if largest is None or _size(scene) > _size(largest):
            largest = scene
    return largest, len(renders)


def _size(scene: Scene) -> int:
    return scene.image.width * scene.image.height * len(scene.grid)


def check_meterable(scene: Scene, cell: dict, index: int, source: str) -> None:
    """A cell whose white patch cannot be metered (a channel left dark, dark current filling the well)
    is refused here, before anything runs, not midway through the sweep.

    Parameters
    ----------
    scene : Scene
        The cell's scene.
    cell : dict
        Its axis values (named in the error).
    index : int
        Its index.
    source : str
        The sweep file.

    Raises
    ------
    ConfigError
        When the white patch cannot be metered.
    """
    from spectracam.scene.chart import WHITE_PATCH
    from spectracam.sensor.exposure import saturation_times_s
    from spectracam.scene.reference import ChartReference

    white = ChartReference.of(scene).patch_rates(scene.camera)[WHITE_PATCH]
    try:
        saturation_times_s(white, scene.camera.sensor, scene.camera.capture.white_fill)
    except SpectracamError as e:
        raise ConfigError(f"cell {index}", cell, str(e), source) from None


def base_value(base: dict, path: str) -> Any:
    """The base scene's value at an axis path (``capture.design`` as ``"arch/scheme"``), or None.

    Parameters
    ----------
    base : dict
        The base scene's tables.
    path : str
        An axis (``table.field`` or ``table.field[i]``).

    Returns
    -------
    object
        The value (an element with an index), or None where the scene has none.
    """
    if path == DESIGN_AXIS:
        return f"{base['capture']['architecture']}/{base['capture']['exposure']}"
    m = PATH.match(path)
    table, key, index = m.groups() if m else (None, None, None)
    v = base.get(table, {}).get(key) if key else base.get(table)
    return v[int(index)] if index is not None and isinstance(v, list) and int(index) < len(v) else v


def cell_scene(sweep: Sweep, cell: dict, index: int) -> Scene:
    """The scene of one cell: the base scene with each axis's value set (the ``--set`` path engine).

    Parameters
    ----------
    sweep : Sweep
    cell : dict
        Axis path → value.
    index : int
        The cell's index (named in errors).

    Returns
    -------
    Scene
    """
    d = sweep.base
    for path, value in cell.items():
        d = apply_override(d, path, value, source=f"{sweep.source}: axes")
    return parse_scene(d, source=f"{sweep.source}: cell {index} {cell}")


def trial_seed(sweep_seed: int, trial: int) -> int:
    """Noise seed of a trial, the same in every cell (common random numbers across cells).

    Parameters
    ----------
    sweep_seed : int
        The sweep's seed.
    trial : int

    Returns
    -------
    int
        0 … 2³¹ − 1.
    """
    return int(np.random.SeedSequence([sweep_seed, trial]).generate_state(1)[0] >> 1)  # 0 … 2³¹ − 1


def _flatten(d: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(_flatten(v, key + "."))
        else:
            out[key] = json.dumps(v) if isinstance(v, list) else v
    return out


def run_cell(index: int, cell: dict, scene: Scene, cube: RadianceCube, trials: int, sweep_seed: int, metrics: tuple,
             sweep_digest: str = "") -> dict:
    """One cell: capture and score every trial.  Runs on a Dask worker (or in-process).

    Parameters
    ----------
    index : int
    cell : dict
        Axis path → value.
    scene : Scene
        The cell's scene (:func:`cell_scene`).
    cube : RadianceCube
        Its render.
    trials, sweep_seed : int
        Trials per cell and the sweep's seed (:func:`trial_seed`).
    metrics : tuple of str
        The summary metrics recorded.
    sweep_digest : str
        The sweep's digest, stamped on each row (the journal's check).

    Returns
    -------
    dict
        ``cell``, ``rows`` (one per trial: seed, axis values, scene parameters, metrics, usability) and
        ``compute_s`` (s).
    """
    from spectracam.camera.capture import capture
    from spectracam.processing import metered_camera
    from spectracam.scene.reference import ChartReference
    from spectracam.evaluation.score import score

    t0 = time.perf_counter()
    params = _flatten(scene.to_dict())
    reference = ChartReference.of(scene)
    camera = metered_camera(scene.camera, scene.processing)   # capture.metering "auto": processing.camera's
    rows = []
    for trial in range(trials):
        seed = trial_seed(sweep_seed, trial)
        raw = capture(cube, camera, seed, reference.white_box)
        result = score(raw, reference, scene.processing)
        values = dataclasses.asdict(result.summary)
        if result.held_out is not None:
            values.update({f"held_out_{k}": result.held_out[k] for k in ("delta_e_mean", "delta_e_p95", "delta_e_max")},
                          delta_e_conversion_p95=result.training["delta_e_p95"])
        usable, why = UsabilitySpec().judge(values["s_cielab_mean"], values["snr_white_rendered_db"])
        rows.append({"sweep": sweep_digest, "cell": index, "trial": trial, "seed": seed,
                     **{f"axis:{k}": v for k, v in cell.items()}, **params, **{m: values[m] for m in metrics},
                     "usable": usable, "unusable_reason": why})
    return {"cell": index, "rows": rows, "compute_s": time.perf_counter() - t0}


def run_cells(items: list, cube: RadianceCube, trials: int, sweep_seed: int, metrics: tuple,
              sweep_digest: str = "") -> list[dict]:
    """Several cells that share a radiance cube, as one Dask task: a task costs the engine a few
    milliseconds (scheduling, transfer), which a batch of cells shares.

    Parameters
    ----------
    items : list
        ``(index, cell, scene)`` per cell.
    cube : RadianceCube
        Their shared render.
    trials, sweep_seed : int
    metrics : tuple of str
    sweep_digest : str
        As :func:`run_cell`.

    Returns
    -------
    list of dict
        :func:`run_cell`'s, in order.
    """
    return [run_cell(i, cell, scene, cube, trials, sweep_seed, metrics, sweep_digest) for i, cell, scene in items]


def cells_per_task(n_cells: int, workers: int) -> int:
    """About eight tasks per worker (load balance, progress), at most 32 cells each.

    Parameters
    ----------
    n_cells, workers : int

    Returns
    -------
    int
        Cells per task, at least 1.
    """
    return max(1, min(32, math.ceil(n_cells / (8 * max(workers, 1)))))


# --------------------------------------------------------------------------------------------
# the driver


def _read_journal(path: Path, digest: str, log=lambda m: None) -> tuple[list[dict], int]:
    """The journal's rows of this sweep, and the byte length of its complete lines.  A line cut short
    by a kill ends the journal; an empty, damaged or foreign line (another sweep's digest) is skipped
    with a warning, and its cell is recomputed."""
    rows, good_len, skipped = [], 0, 0
    if path.exists():
        with open(path, "rb") as f:
            for line in f:
                if not line.endswith(b"\n"):
                    break  # a line cut short by a kill: that cell is not done
                good_len += len(line)
                try:
                    row = json.loads(line)
                    ok = isinstance(row, dict) and row.get("sweep") == digest and isinstance(row.get("cell"), int)
                except ValueError:
                    ok = False
                if ok:
                    rows.append(row)
                else:
                    skipped += 1
    if skipped:
        log(f"warning: {skipped} line(s) of {path} are empty, damaged or from another sweep; their cells are "
            "computed again")
    return rows, good_len


def finished_cells(rows: list[dict], sweep: "Sweep", cells: list[dict],
                   log: Callable[[str], object] = lambda m: None) -> tuple[list[dict], set]:
    """``(rows, done)``: the journal rows that belong to this sweep and the cells they finish.  A row
    belongs when its cell exists, its trial is one of the sweep's with that trial's seed, its axis values
    and every scene parameter are the cell's, and every metric is a finite number (an SNR may be null:
    noise-free); a cell is finished by exactly one such row per trial.  Anything else — a row for cell
    9999, trial 99 of 2, a duplicate, a NaN or text metric, edited parameters — is dropped with a
    warning and its cell computed again.

    Parameters
    ----------
    rows : list of dict
        The journal's rows (results.jsonl).
    sweep : Sweep
    cells : list of dict
        The sweep's cells, by index.
    log : callable
        ``log(line)``: the warning.

    Returns
    -------
    tuple of (list of dict, set)
        The rows kept and the indices of the finished cells.
    """
    by_cell: dict[int, dict[int, list]] = {}
    bad = 0
    expected_params: dict[int, dict] = {}
    for r in rows:
        c, t = r.get("cell"), r.get("trial")
        ok = (isinstance(c, int) and not isinstance(c, bool) and 0 <= c < len(cells) and isinstance(t, int)
              and not isinstance(t, bool) and 0 <= t < sweep.trials and r.get("seed") == trial_seed(sweep.seed, t))
        if ok:
            ok = all(r.get(f"axis:{k}") == v for k, v in cells[c].items())
        if ok:
            for m in sweep.metrics:
                v = r.get(m, "missing")
                if v is None and m.startswith("snr"):
                    continue
                if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                    ok = False
                    break
        if ok:
            if c not in expected_params:
                expected_params[c] = _flatten(cell_scene(sweep, cells[c], c).to_dict())
            ok = all(r.get(k) == v for k, v in expected_params[c].items())
        if not ok:
            bad += 1
            continue
        by_cell.setdefault(c, {}).setdefault(t, []).append(r)
    done, kept = set(), []
    for c, trials in by_cell.items():
        if len(trials) == sweep.trials and all(len(v) == 1 for v in trials.values()):
            done.add(c)
            kept += [v[0] for _, v in sorted(trials.items())]
        elif any(len(v) > 1 for v in trials.values()):
            bad += sum(len(v) for v in trials.values())
    if bad:
        log(f"warning: {bad} journal row(s) do not belong to this sweep (unknown cell or trial, duplicate, "
            "edited parameters, a metric that is not a finite number); their cells are computed again")
    return kept, done


def _write_tables(out: Path, rows: list[dict]) -> None:
    import csv
    import io

    import pyarrow as pa
    import pyarrow.parquet as pq

    rows = sorted(rows, key=lambda r: (r["cell"], r["trial"]))
    columns = list(dict.fromkeys(k for r in rows for k in r))
    table = pa.Table.from_pylist(rows)
    buf = pa.BufferOutputStream()
    pq.write_table(table, buf)
    atomic_write(out / "results.parquet", buf.getvalue().to_pybytes())
    s = io.StringIO()
    w = csv.DictWriter(s, fieldnames=columns)
    w.writeheader()
    w.writerows(rows)
    atomic_write(out / "results.csv", s.getvalue().encode())


#: How often Dask runs a task again when the worker running it dies (a killed worker mid-sweep).
TASK_RETRIES = 2
#: How long a scheduler may take to send Dask's handshake after a connection opens, s.
HANDSHAKE_TIMEOUT_S = 5.0


def probe_scheduler(address: object) -> None:
    """Refuse, in one line and within :data:`HANDSHAKE_TIMEOUT_S`, an address that is not a Dask
    scheduler: not ``tcp://HOST:PORT``, nothing listening, or a peer that does not open with Dask's
    handshake (an HTTP server sends nothing; another service sends something else) — before a client
    could hang on it or read its bytes as a message length.

    Parameters
    ----------
    address : object
        ``--scheduler``.

    Raises
    ------
    SpectracamError
        When it is not a Dask scheduler's address, cannot be connected to, or does not answer as one.
    """
    import re
    import socket

    m = re.fullmatch(r"tcp://(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):(\d{1,5})", address) if isinstance(address, str) else None
    if not m or not 0 < int(m.group(2)) < 65536:
        raise SpectracamError(f"--scheduler = {address!r}: must be a Dask scheduler's address tcp://HOST:PORT")
    host, port = m.group(1).strip("[]"), int(m.group(2))
    try:
        with socket.create_connection((host, port), timeout=HANDSHAKE_TIMEOUT_S) as s:
            s.settimeout(HANDSHAKE_TIMEOUT_S)
            data, t0 = b"", time.monotonic()
            while b"pickle-protocol" not in data and len(data) < 4096 and time.monotonic() - t0 < HANDSHAKE_TIMEOUT_S:
                chunk = s.recv(4096)
                if not chunk:
                    break
                data += chunk
    except socket.timeout:
        data = b""
    except OSError as e:
        raise SpectracamError(f"--scheduler = {address!r}: cannot connect ({e.strerror or e})") from None
    if b"pickle-protocol" not in data:
        raise SpectracamError(f"--scheduler = {address!r}: the peer is not a Dask scheduler (no Dask handshake within "
                              f"{HANDSHAKE_TIMEOUT_S:g} s: it sent {len(data)} bytes)")


def _lock_journal(journal: Path):
    """An exclusive lock on the journal (``flock``; released when the file is closed, also by a kill):
    a second run in the same directory — two ``--resume`` at once — is refused in one line instead of
    computing the same cells twice.  Returns the open file, to be kept while the sweep runs."""
    f = open(journal, "ab")
    try:
        import fcntl

        fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except ImportError:  # not POSIX: no lock
        pass
    except OSError:
        f.close()
        raise SpectracamError(f"output = {str(journal.parent)!r}: another spectracam sweep is running in this "
                              "directory; wait for it to finish (or stop it), then --resume") from None
    return f


class SweepResult(TypedDict):
    """What :func:`run_sweep` returns: its timing figures.  A sweep's results are its files, written as it runs
    (``results.jsonl`` a cell at a time, then ``results.parquet``/``.csv``; ``sweep.json``), so it has no writer."""

    cells: int
    new_cells: int
    render_s: float
    wall_s: float
    cluster_start_s: float
    #: Seconds to close the Dask client and a local cluster after the last cell (0 serially); in ``wall_s``.
    cluster_stop_s: float
    compute_s: float


def run_sweep(sweep: Sweep, out_dir: str | Path, *, scheduler: str | None = None, workers: int | None = None,
              serial: bool = False, resume: bool = False, progress: bool = True,
              log: Callable[[str], object] = lambda m: None, stop_after: int | None = None) -> SweepResult:
    """Run (or resume) a sweep; returns timing figures.  ``stop_after`` ends after that many new cells
    (for tests of interruption).

    Parameters
    ----------
    sweep : Sweep
    out_dir : str or Path
    scheduler : str or None
    workers, stop_after : int or None
    serial, resume, progress : bool
        Here, not on Dask (``scheduler``'s, or a local cluster if None); go on from the journal; progress bars.
    log : callable

    Returns
    -------
    SweepResult"""
    from spectracam.core.progress import Counter

    if scheduler is not None and not serial:
        probe_scheduler(scheduler)  # before anything is written: a wrong address leaves no half-made sweep
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    journal = out / "results.jsonl"
    meta_path = out / "sweep.json"
    meta = _sweep_meta(sweep)
    _check_output(out, journal, meta_path, sweep, resume)
    lock = _lock_journal(journal)  # held until this function returns: one run per directory at a time
    atomic_write(meta_path, json.dumps(meta, indent=1).encode(), now=True)
    rows = _clean_journal(journal, sweep.digest, log)
    cells = sweep.cells()
    rows, done = finished_cells(rows, sweep, cells, log)  # a cell with missing or foreign rows is recomputed whole
    todo = [(i, c) for i, c in enumerate(cells) if i not in done]
    preparing = Counter(len(todo), desc="preparing cells", unit="cell", log=log, progress=progress)
    scenes = {i: cell_scene(sweep, c, i) for i, c in preparing.iterate(todo)}

    t0 = time.perf_counter()
    cubes, groups = _render_cells(scenes, sweep.renderer, log)
    t_render = time.perf_counter() - t0

    with open(journal, "ab") as jf:
        # cells done, rate and time left: a bar on a terminal, else a line every 30 s; the estimate up front
        bar = Counter(len(cells), initial=len(done), desc="sweep cells", unit="cell", log=log, progress=progress)
        t1, cluster_start, cluster_stop = time.perf_counter(), 0.0, 0.0
        record = _Recorder(jf, rows, bar)
        work = _Work(sweep, todo, scenes, cubes, groups, stop_after)
        if serial or not todo:
            _run_serial(work, record)
        else:
            cluster_start, cluster_stop = _run_dask(work, record, scheduler, workers,
                                      lambda e: _cluster_failed(e, len(done) + record.n_new, len(cells), journal))
        bar.close()
        wall = time.perf_counter() - t1
    _write_tables(out, rows)
    lock.close()
    return {"cells": len(cells), "new_cells": record.n_new, "render_s": t_render, "wall_s": wall, "cluster_start_s":
            cluster_start, "cluster_stop_s": cluster_stop, "compute_s": float(np.sum(record.compute, initial=0.0))}


def _sweep_meta(sweep: Sweep) -> dict:
    """What ``sweep.json`` records of a sweep: its source, digest, axes, metrics and base values."""
    return {"source": sweep.source, "digest": sweep.digest, "axes": [[p, list(v)] for p, v in sweep.axes],
            "metrics": list(sweep.metrics), "trials": sweep.trials, "seed": sweep.seed, "renderer": sweep.renderer,
            "base_values": {p: base_value(sweep.base, p) for p, _ in sweep.axes}}


def _check_output(out: Path, journal: Path, meta_path: Path, sweep: Sweep, resume: bool) -> None:
    """Refuse an output directory that holds a sweep, unless resuming that same sweep."""
    from spectracam.core.files import regular_file

    for p in (journal, meta_path):   # a FIFO in their place would block the journal's open for ever
        regular_file(p, "output")
    if journal.exists() or meta_path.exists():
        if not resume:
            raise SpectracamError(f"output = {str(out)!r}: already holds a sweep; pass --resume to continue it, "
                                  "or choose a new directory")
        try:
            old = json.loads(meta_path.read_text()) if meta_path.exists() else {}
        except (ValueError, UnicodeDecodeError) as e:
            raise SpectracamError(f"output = {str(out)!r}: its sweep.json is damaged ({e}); it cannot tell which sweep "
                                  "the journal belongs to: choose a new directory") from None
        if not isinstance(old, dict) or old.get("digest") not in (None, sweep.digest):
            raise SpectracamError(f"output = {str(out)!r}: holds a different sweep (digest "
                                  f"{old.get('digest') if isinstance(old, dict) else old!r} ≠ {sweep.digest}); "
                                  "choose a new directory")


def _clean_journal(journal: Path, digest: str, log) -> list[dict]:
    """The journal's rows of this sweep, a partial last line cut off so appends start on a clean line."""
    rows, good_len = _read_journal(journal, digest, log)
    if journal.exists():  # drop a partial last line, so appends start on a clean line
        with open(journal, "r+b") as f:
            f.truncate(good_len)
    return rows


def _render_cells(scenes: dict, renderer: str, log) -> tuple[dict, dict]:
    """One render per distinct radiance: ``(cubes by render key, each cell's render key)``."""
    from spectracam.io.cache import cached_render, render_key

    cubes, groups = {}, {}
    for i, s in scenes.items():
        key, _ = render_key(s, renderer)
        groups[i] = key
        if key not in cubes:
            cubes[key], hit = cached_render(s, renderer, log=log)
            log(f"render {s.illuminant.label}, {s.image.width}x{s.image.height}: "
                f"{'cached' if hit else renderer}")
    return cubes, groups


@dataclass(frozen=True)
class _Work:
    """The cells a run has still to do, with their scenes and radiance cubes."""
    sweep: Sweep
    todo: list
    scenes: dict
    cubes: dict
    groups: dict
    stop_after: int | None


class _Recorder:
    """Appends a finished cell's rows to the journal (flushed at once, on disk every second) and counts it."""

    def __init__(self, jf, rows: list, bar):
        self.jf, self.rows, self.bar = jf, rows, bar
        self.compute, self.n_new = [], 0
        self.last_sync = time.perf_counter()

    def __call__(self, res: dict) -> None:
        """Record one cell's result."""
        self.jf.write(b"".join(json.dumps(r).encode() + b"\n" for r in res["rows"]))
        self.jf.flush()  # in the OS's hands: survives a killed process
        if time.perf_counter() - self.last_sync > 1.0:  # and on disk at least every second
            os.fsync(self.jf.fileno())
            self.last_sync = time.perf_counter()
        self.rows.extend(res["rows"])
        self.compute.append(res["compute_s"])
        self.n_new += 1
        self.bar.update(1)

    def stopped(self, stop_after: int | None) -> bool:
        """Whether ``stop_after`` new cells are done."""
        return stop_after is not None and self.n_new >= stop_after


def _run_serial(work: _Work, record: _Recorder) -> None:
    """The cells to do, one after another in this process."""
    sweep = work.sweep
    for i, c in work.todo:
        record(run_cell(i, c, work.scenes[i], work.cubes[work.groups[i]], sweep.trials, sweep.seed, sweep.metrics,
                        sweep.digest))
        if record.stopped(work.stop_after):
            break


def _quiet_dask() -> None:
    """No heartbeat tracebacks from a finished run, no resource-tracker warnings from an interrupted one."""
    import logging
    import sys

    for name in ("distributed", "tornado"):  # a finished run prints no heartbeat tracebacks
        logging.getLogger(name).setLevel(logging.CRITICAL)
    # an interrupted run ends its workers: their semaphores are then "leaked" and the resource
    # tracker (its own process, started with this interpreter's -W options) warns after the
    # one line that says so
    import warnings

    warnings.filterwarnings("ignore", category=UserWarning, module="multiprocessing.resource_tracker")
    if "ignore::UserWarning:multiprocessing.resource_tracker" not in sys.warnoptions:
        sys.warnoptions.append("ignore::UserWarning:multiprocessing.resource_tracker")


def _dask_client(scheduler: str | None, workers: int | None) -> tuple:
    """``(client, cluster)``: a client of the scheduler, or of a local cluster made here (else None)."""
    from distributed import Client, LocalCluster

    cluster = None
    if scheduler:
        try:
            client = Client(scheduler, timeout=SCHEDULER_TIMEOUT_S)
        except (OSError, TimeoutError, ValueError, MemoryError) as e:
            raise SpectracamError(f"--scheduler = {scheduler!r}: no Dask scheduler answered within "
                                  f"{SCHEDULER_TIMEOUT_S} s ({type(e).__name__})") from None
    else:
        import dask

        # one single-threaded process per core (no BLAS or sensor-chunk threads fighting over
        # cores), and without the nanny's MALLOC_TRIM_THRESHOLD_, which makes every large
        # NumPy allocation an mmap and doubled the time of a cell (measured: 0.10 → 0.05 s)
        environ = {k: v for k, v in dask.config.get("distributed.nanny.pre-spawn-environ", {}).items()
                   if k != "MALLOC_TRIM_THRESHOLD_"}
        environ.update({v: "1" for v in ("SPECTRACAM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                         "MKL_NUM_THREADS")})
        with dask.config.set({"distributed.nanny.pre-spawn-environ": environ}):
            cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                                   processes=True, dashboard_address=None)
        client = Client(cluster)
    return client, cluster


def _submit_cells(client, work: _Work) -> list:
    """Submit the cells to do, batched by radiance (:func:`run_cells`); returns their futures."""
    sweep, todo, groups = work.sweep, work.todo, work.groups
    # on every worker: a worker lost mid-sweep takes no radiance with it (its tasks run again)
    shared = {k: client.scatter(v, broadcast=True) for k, v in work.cubes.items()}
    n_workers = max(len(client.scheduler_info(n_workers=-1).get("workers", {})), 1)
    size = cells_per_task(len(todo), n_workers)
    futures = []
    for key in dict.fromkeys(groups[i] for i, _ in todo):  # cells of one radiance together
        items = [(i, c, work.scenes[i]) for i, c in todo if groups[i] == key]
        for a in range(0, len(items), size):
            chunk = items[a:a + size]
            futures.append(client.submit(run_cells, chunk, shared[key], sweep.trials, sweep.seed,
                                         sweep.metrics, sweep.digest,
                                         key=f"cells-{sweep.digest}-{chunk[0][0]}", pure=False,
                                         retries=TASK_RETRIES))
    return futures


def _cluster_failed(e: Exception, finished: int, total: int, journal: Path) -> SpectracamError:
    """The one-line error for a Dask cluster that failed mid-sweep (a worker lost, a task cancelled)."""
    first = (str(e).splitlines() or [""])[0][:200]
    return SpectracamError(f"sweep: the Dask cluster failed ({type(e).__name__}: {first}) after "
                           f"{finished} of {total} cells; every finished cell is in "
                           f"{journal} and the renders in the render cache: run the same command with "
                           "--resume to continue")


def _run_dask(work: _Work, record: _Recorder, scheduler: str | None, workers: int | None,
              failed) -> tuple[float, float]:
    """The cells to do on a Dask cluster; returns how long the cluster took to start and to close, s.  ``failed``
    makes the error for a cluster that fails mid-sweep."""
    from distributed import as_completed

    t_start = time.perf_counter()
    _quiet_dask()
    client, cluster = _dask_client(scheduler, workers)
    cluster_start = time.perf_counter() - t_start
    try:
        futures = _submit_cells(client, work)
        try:
            for fut in as_completed(futures):
                for res in fut.result():
                    record(res)
                if record.stopped(work.stop_after):
                    break
        except (SpectracamError, KeyboardInterrupt):
            raise
        except Exception as e:  # noqa: BLE001 - a worker lost, a task cancelled: the cluster's fault
            raise failed(e) from None
    finally:
        t_stop = time.perf_counter()
        client.close()
        if cluster is not None:
            cluster.close()
    return cluster_start, time.perf_counter() - t_stop
