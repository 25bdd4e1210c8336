"""Light groups: several illuminants of different spectra and levels in one scene, each lighting its own region.

A scene file's ``[[lights]]`` array of tables lists the groups (none: the scene is lit by its ``[illuminant]``
alone, exactly as before).  Each group has a ``name`` and an ``illuminant`` table, the whole ``[illuminant]``
table of :mod:`spectracam.scene.illuminant` (type, temperature_K or name, white_luminance_cd_m2 or
illuminance_lux) — a sub-table, because ``name`` names the group and an ``[illuminant]``'s ``name`` names a CIE
light::

    [[lights]]
    name = "sun"
    illuminant = { type = "cie", name = "D50", illuminance_lux = 100000 }

Which region each group lights:

* a **chart** target: the image is divided into a grid of equal cells (``image.lights_columns`` across, 0:
  the count that makes the charts largest), one per group, row by row; each cell shows one ColorChecker fitted
  and centred in it (the rules of a one-chart scene, :class:`spectracam.scene.chart.View`) lit by its group.
  Cells left over in the last row are unlit (radiance 0).
* a **textured** target (every kind is a label image, :mod:`spectracam.scene.target`): every label (a library
  sample, or the surround) is assigned a group by a seeded draw from the target's ``seed``
  (:func:`label_groups`: a shuffled, balanced assignment, so every group lights ⌊n/K⌋ or ⌈n/K⌉ labels); all the
  leaves or squares that show one sample share its group.

The scene's ``illuminant`` is then the brightest group's (largest white luminance; the first on ties): the chart
the colour conversion is fitted on and the exposure metered on is lit by it ("metered on the brightest light").
Rendering is linear, so a light-group scene is the sum of one render per group with every surface of the other
groups black — the "light groups" of production renderers (a render split by light, written as light path
expressions after [Heckbert1990]_), as Mitsuba renders it (:mod:`spectracam.render.mitsuba`); the closed form
renders each region under its own light.  The shipped scenes ``scenes/hdr_*.toml`` state their levels' sources
([IESVE2021]_, [WikipediaLux]_; spectra [CIE015]_).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from spectracam.core.errors import ConfigError
from spectracam.core.spec import Spec
from spectracam.scene.illuminant import IlluminantSpec

__all__ = ["LIGHTS_SEED_STREAM", "MAX_LIGHTS", "LightGroup", "brightest", "cell_columns", "cell_slices",
           "label_groups", "parse_lights"]

#: Most light groups a scene may have (a chart cell each: 64 charts already need a 2000-px image).
MAX_LIGHTS = 64
#: The seed-sequence stream of :func:`label_groups` (the sensor uses 1 and 2, textured renders 34).
LIGHTS_SEED_STREAM = 36


@dataclass(frozen=True)
class LightGroup(Spec):
    """One ``[[lights]]`` table: a group's ``name`` and the ``illuminant`` that lights its region."""

    TABLE = "lights"

    name: str = "light"
    illuminant: IlluminantSpec = field(default_factory=IlluminantSpec)

    def validate(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise self.error("name", "must be a non-empty string naming the group, e.g. 'sun'")
        if not isinstance(self.illuminant, IlluminantSpec):
            raise self.error("illuminant", "must be an [illuminant] table, e.g. { type = 'cie', name = 'D50', "
                             "illuminance_lux = 100000 }")

    @property
    def white_luminance_cd_m2(self) -> float:
        """Luminance of a perfect white diffuser under the group's light, cd/m²."""
        return self.illuminant.white_luminance_cd_m2

    def to_dict(self) -> dict:
        return {"name": self.name, "illuminant": self.illuminant.to_dict()}

    @classmethod
    def from_dict(cls, data: object, source: str | None = None, base: LightGroup | None = None) -> LightGroup:
        """A ``[[lights]]`` table: ``name`` and ``illuminant`` (an ``[illuminant]`` table, over ``base``'s).

        Parameters
        ----------
        data : object
            The table; only ``name`` and ``illuminant`` are allowed.
        source : str or None
            Where the table came from, for the error.
        base : LightGroup or None
            The group whose name and illuminant fill what is not given; None: the default.

        Returns
        -------
        LightGroup
            The validated group.
        """
        if not isinstance(data, dict):
            raise ConfigError("lights", data, "must be a table with name and illuminant, e.g. { name = 'sun', "
                              "illuminant = { type = 'cie', name = 'D50', illuminance_lux = 100000 } }", source)
        for k in data:
            if k not in ("name", "illuminant"):
                raise ConfigError(f"lights.{k}", data[k], "unknown key; allowed: illuminant, name (the light's own "
                                  "keys go in the illuminant sub-table)", source)
        base = base or cls()
        illuminant = IlluminantSpec.from_dict(data.get("illuminant", {}), source, base.illuminant)
        return cls(name=data.get("name", base.name), illuminant=illuminant)


def _prefixed(e: ConfigError, i: int) -> ConfigError:
    """``e`` with its field located in ``lights[i]`` (``illuminant.x`` → ``lights[i].illuminant.x``)."""
    name = e.field.split(".", 1)[1] if e.field.startswith("lights.") else e.field
    return ConfigError(f"lights[{i}].{name}" if name != "lights" else f"lights[{i}]", e.value, e.allowed, e.source)


def parse_lights(data: object, source: str | None = None) -> tuple[LightGroup, ...]:
    """The ``[[lights]]`` array of tables as light groups.

    Parameters
    ----------
    data : list of dict
        One table per group: ``name`` and ``illuminant`` (an ``[illuminant]`` table).  Empty: no light groups.
    source : str, optional
        Where the data came from, named in error messages.

    Returns
    -------
    tuple of LightGroup

    Raises
    ------
    ConfigError
        Not a list of tables, more than :data:`MAX_LIGHTS` groups, two groups of one name, or a bad value in a
        group (the field named ``lights[i].…``).
    """
    if isinstance(data, LightGroup):
        data = [data]
    if not isinstance(data, (list, tuple)):
        raise ConfigError("lights", data, "must be an array of tables ([[lights]]), each with name and illuminant",
                          source)
    if len(data) > MAX_LIGHTS:
        raise ConfigError("lights", f"{len(data)} groups", f"at most {MAX_LIGHTS} light groups are allowed", source)
    out = []
    for i, table in enumerate(data):
        try:
            out.append(table if isinstance(table, LightGroup) else LightGroup.from_dict(table))
        except ConfigError as e:
            raise _prefixed(e, i).with_source(source) from None
    names = [g.name for g in out]
    for i, name in enumerate(names):
        if name in names[:i]:
            raise ConfigError(f"lights[{i}].name", name, "must differ from every other group's name", source)
    return tuple(out)


def brightest(lights: Sequence[LightGroup]) -> int:
    """Index of the group with the largest white luminance (the first on ties): the scene's metering light.

    Parameters
    ----------
    lights : sequence of LightGroup
        The scene's light groups.

    Returns
    -------
    int
        The index; 0 when there are none.
    """
    levels = [g.white_luminance_cd_m2 for g in lights]
    return int(np.argmax(levels)) if levels else 0


def cell_columns(n: int, width_px: int, height_px: int, board_mm: tuple[float, float], columns: int = 0) -> int:
    """Columns of the grid of ``n`` chart cells: ``columns`` if given, else the count (1 … n) that makes a chart
    of ``board_mm`` (width, height) fitted in its cell largest, the fewest cells on ties.

    Parameters
    ----------
    n : int
        How many cells (one per light group).
    width_px, height_px : int
        The image's size, pixels.
    board_mm : tuple of float
        The chart board's width and height, mm.
    columns : int
        The columns asked for (at most ``n`` are used); 0: choose.

    Returns
    -------
    int
        The number of columns.
    """
    if columns:
        return min(columns, n)
    bw, bh = board_mm
    best, best_scale = 1, -1.0
    for c in range(1, n + 1):
        rows = -(-n // c)
        scale = min((width_px // c) / bw, (height_px // rows) / bh)
        if scale > best_scale * (1 + 1e-12):
            best, best_scale = c, scale
    return best


def cell_slices(n: int, width_px: int, height_px: int, columns: int) -> list[tuple[slice, slice]]:
    """``(rows, cols)`` pixel slices of ``n`` cells on a grid ``columns`` across, row by row from the top left;
    cell edges at ``W·j // columns`` and ``H·i // rows`` (the cells tile the image).

    Parameters
    ----------
    n : int
        How many cells.
    width_px, height_px : int
        The image's size, pixels.
    columns : int
        The grid's columns (:func:`cell_columns`).

    Returns
    -------
    list of (slice, slice)
        ``n`` pairs of row and column slices.
    """
    rows = -(-n // columns)
    xe = [width_px * j // columns for j in range(columns + 1)]
    ye = [height_px * i // rows for i in range(rows + 1)]
    return [(slice(ye[k // columns], ye[k // columns + 1]), slice(xe[k % columns], xe[k % columns + 1]))
            for k in range(n)]


def label_groups(seed: int, n_labels: int, n_groups: int) -> np.ndarray:
    """``(n_labels,)`` int32: the light group of each label of a textured target, a seeded, balanced draw.

    Parameters
    ----------
    seed : int
        The target's seed (its own stream, :data:`LIGHTS_SEED_STREAM`, of the seed sequence).
    n_labels, n_groups : int
        Labels (samples and the surround) and light groups.

    Returns
    -------
    ndarray
        A random permutation of ``0, 1, …, K−1, 0, 1, …`` (``K = n_groups``): every group lights ⌊n/K⌋ or
        ⌈n/K⌉ labels, so none is left dark when there are at least as many labels as groups.

    Examples
    --------
    >>> g = label_groups(0, 10, 3)
    >>> sorted(np.bincount(g).tolist())
    [3, 3, 4]
    """
    rng = np.random.default_rng(np.random.SeedSequence([seed, LIGHTS_SEED_STREAM]))
    return rng.permutation(np.arange(n_labels) % max(n_groups, 1)).astype(np.int32)
