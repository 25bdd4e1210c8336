"""The scene file: assembles every stage's spec from one TOML document.

A scene file has the tables ``[target]`` (what the camera looks at: the chart, or a textured target of
measured reflectances, :mod:`spectracam.scene.target`), ``[chart]``, ``[wavelengths]``, ``[image]``,
``[render]``, the camera's ``[optics]``, ``[filters]``, ``[sensor]``, ``[capture]`` and
``[processing]`` (all optional, defaults in each stage's spec) and an optional top-level ``name``.
Each stage validates its own table; this module holds only the rules that tie stages together
(the grid within the data, patches large enough to score).  Any unknown key, wrong type or
out-of-range value raises :class:`ConfigError` naming the field, the value and what is allowed.
"""
from __future__ import annotations

import tomllib
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from spectracam.camera import CAMERA_TABLES, CameraSpec
from spectracam.scene.chart import ChartSpec, dataset_range_nm, patch_boxes
from spectracam.processing.color import ProcessingSpec
from spectracam.core.errors import ConfigError
from spectracam.scene.illuminant import IlluminantSpec
from spectracam.scene.lights import LightGroup, brightest, parse_lights
from spectracam.render import RenderSpec
from spectracam.scene.target import TargetSpec, resolve_target_files
from spectracam.core.spec import Spec, _is_number
from spectracam.core.spectra import CIE_RANGE_NM, WavelengthGrid

__all__ = ["CURVE_FILES", "MIN_PATCH_PX", "SCENE_TABLES", "ImageSpec", "Scene", "experiment_base_scene",
           "load_camera_config", "load_scene", "paper_scene", "parse_grid", "parse_scene", "read_toml",
           "resolve_curve_files", "shipped_dir", "shipped_scene_file"]

#: Fewest pixels across a patch's mask: a 4×4 mask still holds 4 pixels of each Bayer colour.
MIN_PATCH_PX = 4
#: The tables of a scene file, in order.
SCENE_TABLES = ("target", "chart", "illuminant", "lights", "wavelengths", "image", "render", *CAMERA_TABLES,
                "processing")


@dataclass(frozen=True)
class ImageSpec(Spec):
    """The ``[image]`` table: pixels across and down, and the columns of a light-group chart scene's grid
    of charts (:mod:`spectracam.scene.lights`; 0: the count that makes the charts largest)."""

    TABLE = "image"

    width: int = 640
    height: int = 480
    lights_columns: int = 0

    def validate(self) -> None:
        self.integer("width", 8, 16384)
        self.integer("height", 8, 16384)
        self.integer("lights_columns", 0, 64)

    def to_dict(self) -> dict:
        d = super().to_dict()
        if not self.lights_columns:   # a scene without a chart grid records what it always did
            d.pop("lights_columns")
        return d


def parse_grid(data: dict, source: str | None = None) -> WavelengthGrid:
    """The ``[wavelengths]`` table: ``start_nm``/``stop_nm``/``step_nm`` or ``centres_nm`` (else a ConfigError).

    Parameters
    ----------
    data : dict
        The table: ``start_nm``, ``stop_nm``, ``step_nm`` (nm) or ``centres_nm`` (a list, nm).
    source : str, optional
        The file, as errors name it.

    Returns
    -------
    WavelengthGrid
        The bands.
    """
    if not isinstance(data, dict):
        raise ConfigError("wavelengths", data, "must be a table", source)
    d = dict(data)
    known = ("start_nm", "stop_nm", "step_nm", "centres_nm")
    for k in d:
        if k not in known:
            raise ConfigError(f"wavelengths.{k}", d[k], "unknown key; allowed: " + ", ".join(known), source)
    if "centres_nm" in d:
        c = d.pop("centres_nm")
        if not isinstance(c, (list, tuple)) or not c or not all(_is_number(x) for x in c):
            raise ConfigError("wavelengths.centres_nm", c, "must be a non-empty list of wavelengths in nm", source)
        arr = np.asarray(c, dtype=float)
        if np.any(np.diff(arr) <= 0):
            raise ConfigError("wavelengths.centres_nm", c, "must be strictly increasing", source)
        for k in d:
            raise ConfigError(f"wavelengths.{k}", d[k], "give either centres_nm or start_nm/stop_nm/step_nm, not both",
                              source)
    else:
        start, stop, step = d.get("start_nm", 400.0), d.get("stop_nm", 700.0), d.get("step_nm", 10.0)
        for k, v in (("start_nm", start), ("stop_nm", stop)):
            if not _is_number(v):
                raise ConfigError(f"wavelengths.{k}", v, "must be a number nm", source)
        if not _is_number(step) or step <= 0:
            raise ConfigError("wavelengths.step_nm", step, "must be a number > 0 nm", source)
        if stop <= start:
            raise ConfigError("wavelengths.stop_nm", stop, f"must be > start_nm ({start:g}); the range would be empty",
                              source)
        n = (stop - start) / step
        if n < 1.5:
            raise ConfigError("wavelengths.step_nm", step, f"must give at least two bands in {start:g}–{stop:g} nm",
                              source)
        if abs(n - round(n)) > 1e-6 * max(1.0, n):
            raise ConfigError("wavelengths.step_nm", step, f"must divide the range {start:g}–{stop:g} nm into whole "
                              "bands (band edges lie on the stated limits)", source)
        # bands tile the stated range exactly: edges start, start + step, ..., stop; centres between
        arr = start + step * (np.arange(int(round(n))) + 0.5)
    if arr.size == 1 and "centres_nm" in data:
        raise ConfigError("wavelengths", arr.tolist(), "needs at least two wavelengths", source)
    grid = WavelengthGrid(arr)
    lo, hi = grid.edges_nm[0], grid.edges_nm[-1]
    if lo < CIE_RANGE_NM[0] or hi > CIE_RANGE_NM[1]:
        raise ConfigError("wavelengths", f"{arr[0]:g}–{arr[-1]:g} nm",
                          f"bands must lie within {CIE_RANGE_NM[0]:g}–{CIE_RANGE_NM[1]:g} nm (CIE 1931 range); "
                          f"these span {lo:g}–{hi:g} nm", source)
    return grid


def _default_grid() -> WavelengthGrid:
    """400–700 nm in 10-nm bands (the paper's range, 4.1), edges on the limits: centres 405 … 695 nm."""
    return WavelengthGrid(np.arange(405.0, 700.0, 10.0))


@dataclass(frozen=True)
class Scene(Spec):
    """A whole simulation: what is in front of the camera, how it is rendered, the camera and the
    processing.  Frozen, comparable and hashable."""

    name: str = "Macbeth ColorChecker"
    #: What the camera looks at; the chart (``[chart]``) is also what the conversion is fitted on and
    #: the exposure metered on (its white patch under the same light), whatever the target.
    target: TargetSpec = field(default_factory=TargetSpec)
    chart: ChartSpec = field(default_factory=ChartSpec)
    illuminant: IlluminantSpec = field(default_factory=IlluminantSpec)
    grid: WavelengthGrid = field(default_factory=_default_grid)
    image: ImageSpec = field(default_factory=ImageSpec)
    render: RenderSpec = field(default_factory=RenderSpec)
    camera: CameraSpec = field(default_factory=CameraSpec)
    processing: ProcessingSpec = field(default_factory=ProcessingSpec)
    #: Light groups (``[[lights]]``, :mod:`spectracam.scene.lights`), each lighting its own region; empty: the
    #: scene is lit by ``illuminant`` alone.  With groups, ``illuminant`` is the brightest group's (set here).
    lights: tuple[LightGroup, ...] = ()

    def validate(self) -> None:
        self.string("name")
        chart, image, grid = self.chart, self.image, self.grid
        if self.target.textured:
            self.target.check_size(image.width, image.height)
            from spectracam.scene.reflectances import check_available

            check_available(self.target.library, "target.library")
        if self.lights:
            object.__setattr__(self, "lights", parse_lights(self.lights))
            object.__setattr__(self, "illuminant", self.lights[brightest(self.lights)].illuminant)
        smallest, where = self._smallest_patch()
        if smallest < MIN_PATCH_PX and not self.target.textured:
            raise where
        for name, light in [("illuminant", self.illuminant)] + [(f"lights[{i}].illuminant", g.illuminant)
                                                                for i, g in enumerate(self.lights)]:
            if light.kind == "measured" and (light.wavelengths_nm[0] > grid.edges_nm[0] + 1e-9
                                             or light.wavelengths_nm[-1] < grid.edges_nm[-1] - 1e-9):
                raise ConfigError(f"{name}.wavelengths_nm", f"{light.wavelengths_nm[0]:g}–"
                                  f"{light.wavelengths_nm[-1]:g} nm", "the measured SPD must cover the scene's bands, "
                                  f"{grid.edges_nm[0]:g}–{grid.edges_nm[-1]:g} nm")
        if self.target.textured:
            from spectracam.scene.reflectances import load

            load(self.target.library, "target.library").check_covers(float(grid.edges_nm[0]),
                                                                       float(grid.edges_nm[-1]), "target.library")
        proc = self.processing
        if proc.white_balance_method == "corrected_moments":   # never trained on what is scored (issue 33)
            from spectracam.evaluation.target_score import CHART_LIBRARIES

            lib = proc.white_balance_training
            scored = {self.target.library} if self.target.textured else set()
            scored |= {name for name, dataset in CHART_LIBRARIES.items() if dataset == chart.dataset}
            if lib in scored:
                raise ConfigError("processing.white_balance_training", lib,
                                  "is the scored scene's own library (" + ", ".join(sorted(scored)) + "); the trained "
                                  "white balance must be trained on other colours, e.g. 'rawtoaces190'")
        d_lo, d_hi = dataset_range_nm(chart.dataset)
        if grid.edges_nm[0] < d_lo or grid.edges_nm[-1] > d_hi:
            raise ConfigError("wavelengths", f"{grid.centres_nm[0]:g}–{grid.centres_nm[-1]:g} nm",
                              f"bands span {grid.edges_nm[0]:g}–{grid.edges_nm[-1]:g} nm, beyond the reflectance "
                              f"data of {chart.dataset!r} ({d_lo:g}–{d_hi:g} nm)")

    def _smallest_patch(self) -> tuple[int, ConfigError]:
        """The fewest pixels across a patch's scoring box (of any chart cell), and the error that names it."""
        image = self.image
        if len(self.lights) > 1 and not self.target.textured:
            from spectracam.scene.lights import cell_columns, cell_slices

            n = len(self.lights)
            columns = cell_columns(n, image.width, image.height, self.chart.board_size_mm, image.lights_columns)
            sizes = {(c.stop - c.start, r.stop - r.start) for r, c in cell_slices(n, image.width, image.height,
                                                                                   columns)}
            smallest, w, h = min((min(min(b.stop - b.start, a.stop - a.start) for b, a in
                                      patch_boxes(self.chart, w, h)), w, h) for w, h in sizes)
            return smallest, ConfigError("lights", f"{n} light groups", f"too many for image {image.width}x"
                                         f"{image.height} ({columns} columns): a chart cell is {w}x{h} px, its "
                                         f"smallest patch mask {smallest} px across, at least {MIN_PATCH_PX} are "
                                         "needed to meter and score a patch; use fewer lights or a larger image")
        smallest = min(min(r.stop - r.start, c.stop - c.start)
                       for r, c in patch_boxes(self.chart, image.width, image.height))
        return smallest, ConfigError("image", f"{image.width}x{image.height}",
                                     f"too small: the smallest patch mask is {smallest} px across, at least "
                                     f"{MIN_PATCH_PX} are needed to meter and score a patch")

    def to_dict(self) -> dict:
        """A plain, JSON-serialisable description that round-trips through :meth:`from_dict`."""
        target = {"target": self.target.to_dict()} if self.target.textured else {}
        lights = {"lights": [g.to_dict() for g in self.lights]} if self.lights else {}
        return {"name": self.name, **target, "chart": self.chart.to_dict(), "illuminant": self.illuminant.to_dict(),
                **lights,
                "wavelengths": {"centres_nm": list(self.grid.centres_nm)}, "image": self.image.to_dict(),
                "render": self.render.to_dict(), **self.camera.to_dict(), "processing": self.processing.to_dict()}

    @classmethod
    def from_dict(cls, data: dict, source: str | None = None, base: "Scene | None" = None) -> "Scene":
        """Validate a parsed TOML/JSON dict and build a Scene; tables not given keep ``base``'s values
        (default: the defaults).

        Parameters
        ----------
        data : dict
            The scene's tables (``name`` and :data:`SCENE_TABLES`).
        source : str, optional
            The file, as errors name it.
        base : Scene, optional
            The scene whose tables the missing ones keep.

        Returns
        -------
        Scene
            The validated scene.

        Raises
        ------
        ConfigError
            An unknown table or a value that is not allowed (naming the field and the source).
        """
        if not isinstance(data, dict):
            raise ConfigError("scene", data, "must be a table", source)
        base = base or cls()
        for k, v in data.items():
            if k != "name" and k not in SCENE_TABLES:
                raise ConfigError(k, v, "unknown key", source)
        try:
            grid = parse_grid(data["wavelengths"], source) if "wavelengths" in data else base.grid
            lights = parse_lights(data["lights"], source) if "lights" in data else base.lights
            illuminant = IlluminantSpec.from_dict(data.get("illuminant", {}), source, base.illuminant)
            if lights and "illuminant" in data:
                _check_lit_by_lights(illuminant, lights, data["illuminant"])
            return cls(name=data.get("name", base.name),
                       target=TargetSpec.from_dict(data.get("target", {}), source, base.target),
                       chart=ChartSpec.from_dict(data.get("chart", {}), source, base.chart),
                       illuminant=illuminant,
                       grid=grid,
                       image=ImageSpec.from_dict(data.get("image", {}), source, base.image),
                       render=RenderSpec.from_dict(data.get("render", {}), source, base.render),
                       camera=CameraSpec.from_dict({k: data[k] for k in CAMERA_TABLES if k in data}, source,
                                                   base.camera),
                       processing=ProcessingSpec.from_dict(data.get("processing", {}), source, base.processing),
                       lights=lights)
        except ConfigError as e:
            raise e.with_source(source) from None


def _check_lit_by_lights(illuminant: IlluminantSpec, lights: tuple, table) -> None:
    """Refuse an ``[illuminant]`` beside ``[[lights]]`` unless it is the brightest group's (as a scene records it)."""
    top = lights[brightest(lights)]
    if illuminant != top.illuminant:
        raise ConfigError("illuminant", table, "a scene with [[lights]] is lit by its light groups and its "
                          f"illuminant is the brightest group's ({top.name!r}: {top.illuminant.label}, "
                          f"{top.white_luminance_cd_m2:g} cd/m²); leave [illuminant] out or change the lights")


def parse_scene(data: dict, source: str | None = None) -> Scene:
    """Validate a parsed TOML/JSON dict and build a :class:`Scene`.

    Parameters
    ----------
    data : dict
        The scene tables, e.g. ``{"image": {"width": 320}}``; a missing table or key takes its default.
    source : str, optional
        Where the dict came from, named in error messages.

    Returns
    -------
    Scene

    Raises
    ------
    SpectracamError
        ``data`` not a mapping (ArgumentTypeError), or a field with a value that is not allowed (ConfigError,
        naming the field, the value and what is allowed).
    """
    from collections.abc import Mapping

    from spectracam.core.errors import expect

    expect(data, Mapping, "parse_scene(data)", "a dict of scene tables, e.g. {'image': {'width': 320}} (a scene "
           "file: spectracam.load_scene(path))")
    return Scene.from_dict(data, source)


def read_toml(path: str | Path, what: str) -> dict:
    """Parse a TOML file; an unreadable or invalid file is one ConfigError naming ``what``.

    Parameters
    ----------
    path : str or Path
        A regular file.
    what : str
        The kind of file, as the error names it (``"scene file"``, ``"experiment file"``).

    Returns
    -------
    dict
        The parsed tables.

    Raises
    ------
    ConfigError
        Not a regular file, unreadable, not UTF-8 or not valid TOML.
    """
    from spectracam.core.files import regular_file

    p = regular_file(path, what)
    try:
        text = p.read_bytes().decode("utf-8")
    except OSError as e:
        raise ConfigError(what, str(p), f"cannot be read ({e.strerror})") from None
    except UnicodeDecodeError:
        raise ConfigError(what, str(p), "is not a text (UTF-8 TOML) file") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ConfigError(what, str(p), f"is not valid TOML ({e})") from None


#: Curves a scene file may give as a file, relative to the scene file: (table, file key, fields).
CURVE_FILES = (("illuminant", "file", "wavelengths_nm", "values"),
               ("filters", "qe_file", "qe_curve_nm", "qe_curve"),
               ("optics", "transmittance_file", "transmittance_curve_nm", "transmittance_curve"))


def resolve_curve_files(data: dict, base_dir: Path) -> dict:
    """Replace ``illuminant.file`` / ``filters.qe_file`` / ``optics.transmittance_file`` /
    ``filters.camera_file`` by the curves they hold, so the scene (and every file made from it) records
    the data, not a path (``type = "measured"``, ``qe = "data"``, respectively ``kind = "camera"`` and
    ``camera = "file"``, are implied), and a target's files by absolute paths (:mod:`spectracam.scene.target`).

    Parameters
    ----------
    data : dict
        The scene's tables (not changed).
    base_dir : Path
        The scene file's folder, which the file names are relative to.

    Returns
    -------
    dict
        A copy with the curves in place of the file names.
    """
    from spectracam.architecture.filters import load_curve

    data = dict(data)
    if isinstance(data.get("target"), dict):
        data["target"] = resolve_target_files(data["target"], base_dir)
    if isinstance(data.get("lights"), list):
        data["lights"] = [_resolve_light_file(t, i, base_dir) for i, t in enumerate(data["lights"])]
    for table, key, wl_field, value_field in CURVE_FILES:
        t = data.get(table)
        if isinstance(t, dict) and key in t:
            t = dict(t)
            path = t.pop(key)
            if not isinstance(path, str):
                raise ConfigError(f"{table}.{key}", path, "must be a path to a CSV or TOML file")
            t[wl_field], t[value_field] = load_curve(Path(base_dir) / path, f"{table}.{key}")
            if table == "illuminant":   # a measured SPD, named after its file
                if t.setdefault("type", "measured") != "measured":
                    raise ConfigError("illuminant.type", t["type"], f"contradicts illuminant.file = {path!r} (a "
                                      "measured SPD): leave type out or make it 'measured'")
                t.setdefault("name", Path(path).name)
            if table == "filters":
                t.setdefault("qe", "data")
            data[table] = t
    t = data.get("filters")
    if isinstance(t, dict) and "camera_file" in t:  # a camera's curves: wavelength, R, G, B
        from spectracam.architecture.cameras import FROM_FILE, load_camera_csv

        t = dict(t)
        path = t.pop("camera_file")
        if not isinstance(path, str):
            raise ConfigError("filters.camera_file", path, "must be a path to a CSV file (wavelength nm, R, G, B)")
        t["camera_curve_nm"], t["camera_curve"] = load_camera_csv(Path(base_dir) / path)
        t["camera"] = FROM_FILE
        t.setdefault("kind", "camera")
        data["filters"] = t
    return data


def _resolve_light_file(table, i: int, base_dir: Path):
    """A ``[[lights]]`` table whose ``illuminant.file`` is replaced by the SPD it holds (as ``[illuminant]``'s)."""
    if not (isinstance(table, dict) and isinstance(table.get("illuminant"), dict) and "file" in table["illuminant"]):
        return table
    try:
        return {**table, "illuminant": resolve_curve_files({"illuminant": table["illuminant"]}, base_dir)["illuminant"]}
    except ConfigError as e:
        raise ConfigError(f"lights[{i}].{e.field}", e.value, e.allowed, e.source) from None


def load_scene(path: str | Path, overrides: Iterable[str | tuple[str, object]] = ()) -> Scene:
    """Read and validate a TOML scene file, with ``--set``-style overrides applied first.

    Parameters
    ----------
    path : str or os.PathLike
        The scene file; curve files it names (``illuminant.file``, ``filters.qe_file``, …) are relative to it.
        Where no such file exists, the name of a scene shipped with spectracam (``"d65"``, ``"scenes/d65.toml"``),
        from any working directory, as the command line takes it.
    overrides : iterable
        ``"PATH=VALUE"`` strings or ``(path, value)`` pairs, e.g. ``["image.width=320"]``, applied in order.

    Returns
    -------
    Scene

    Raises
    ------
    SpectracamError
        An argument of the wrong type (ArgumentTypeError), or a file that cannot be read, is not valid TOML or
        holds a value that is not allowed (ConfigError).
    """
    import os

    from spectracam.core.errors import ArgumentTypeError, expect
    from spectracam.pipeline.overrides import apply_overrides

    expect(path, (str, os.PathLike), "load_scene(path)", "a path to a TOML scene file, str or Path (a dict: "
           "spectracam.parse_scene(data))")
    if isinstance(overrides, (str, bytes)) or not hasattr(overrides, "__iter__"):
        raise ArgumentTypeError(f"load_scene(overrides): got {type(overrides).__name__}; allowed: a list of "
                                "'PATH=VALUE' strings or (path, value) pairs, e.g. ['image.width=320']")
    if not Path(path).is_file():   # the name of a shipped scene, as the command line takes it ("d65", "scenes/d65")
        name = str(path).strip().removeprefix("./").removeprefix("scenes/").removesuffix(".toml")
        root = shipped_dir()
        if root is not None and "/" not in name and (root / f"{name}.toml").is_file():
            path = root / f"{name}.toml"
    data = apply_overrides(read_toml(path, "scene file"), overrides)
    return parse_scene(resolve_curve_files(data, Path(path).parent), source=str(path))


def experiment_base_scene(table: dict, directory: str | Path, overrides: Iterable[str | tuple[str, object]] = (),
                          source: str | None = None) -> Scene:
    """The scene an experiment file (``scenes/paper.toml``) builds on: its ``base_scene`` file (relative to
    ``directory``) with its ``[scene.*]`` tables and then ``overrides`` applied.

    Parameters
    ----------
    table : dict
        The experiment file's tables (``base_scene``, ``[scene.*]``).
    directory : str or Path
        The experiment file's folder.
    overrides : iterable of str or (str, object)
        ``--set`` assignments, applied after the file's.
    source : str, optional
        The experiment file, as errors name it.

    Returns
    -------
    Scene
        The validated scene.
    """
    base_name = table.get("base_scene", "blackbody_5000K.toml")
    if not isinstance(base_name, str):
        raise ConfigError("base_scene", base_name, "must be a path to a scene file", source)
    scene_tables = table.get("scene", {})
    if not isinstance(scene_tables, dict) or not all(isinstance(v, dict) for v in scene_tables.values()):
        raise ConfigError("scene", scene_tables, "must be a table of scene tables, e.g. [scene.sensor]", source)
    from_file = [(f"{t}.{k}", v) for t, kv in scene_tables.items() for k, v in kv.items()]
    return load_scene(Path(directory) / base_name, from_file + list(overrides))


def paper_scene() -> Scene:
    """The camera, chart, bands and processing of ``spectracam paper`` (the base scene of the shipped
    ``scenes/paper.toml``): the one camera every experiment means by "the paper's camera"."""
    path = shipped_scene_file("paper.toml")
    return experiment_base_scene(read_toml(path, "experiment file"), path.parent, source=str(path))


def load_camera_config(path: str | Path, base: CameraSpec | None = None) -> CameraSpec:
    """Read a camera config file (the scene file's camera tables only), over ``base``.

    Parameters
    ----------
    path : str or Path
        The TOML file (``[sensor]``, ``[filters]``, ``[optics]``, ``[capture]``, … tables).
    base : CameraSpec, optional
        The camera whose tables the missing ones keep (default: the defaults).

    Returns
    -------
    CameraSpec
        The validated camera.
    """
    return CameraSpec.from_dict(read_toml(path, "config file"), source=str(path), base=base)


def shipped_dir() -> Path | None:
    """The directory of the shipped scene, sweep, experiment and design files: the package's
    ``spectracam/scenes`` (in a wheel), else the checkout's ``scenes/``."""
    from importlib.resources import files

    d = files("spectracam") / "scenes"
    if d.is_dir():
        return Path(str(d))
    here = Path(__file__).resolve().parents[2] / "scenes"
    return here if here.is_dir() else None


def shipped_scene_file(name: str) -> Path:
    """A scene file shipped with spectracam (``spectracam/scenes/NAME``, or the checkout's ``scenes/``).

    Parameters
    ----------
    name : str
        The file's name, e.g. ``"paper.toml"``.

    Returns
    -------
    Path
        The file.

    Raises
    ------
    ConfigError
        No such file is shipped.
    """
    root = shipped_dir()
    if root is None or not (root / name).is_file():
        raise ConfigError("scene", name, "not shipped with this installation")
    return root / name
