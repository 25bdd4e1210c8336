"""One override mechanism for every file a command reads: ``--set table.field=VALUE``.

A path names a field of a scene, camera or experiment file: ``table.field``, ``table.field[i]`` for
one element of a list, or a top-level ``key``; ``capture.design = "arch/scheme"`` sets the
architecture and the exposure scheme together.  VALUE is read as a TOML value (``3``, ``1.5``,
``true``, ``[490, 610]``, ``"text"``); a bare word is taken as a string.  Sweep axes use the same
path engine, so a path that works in one place works in all.

One assignment (:func:`apply_override`) changes a copy of the tables.  Where one element of a list the file
leaves at its default is set, ``defaults()`` supplies that list.  A key that chooses what the rest of its table
means (:data:`SWITCHES`: ``illuminant.type``, ``illuminant.file``) set to another kind drops the old kind's keys,
except those of the paths in ``kept`` (set earlier by the same overrides).  ``source``, when given (it may be
None), names the file in errors.

>>> apply_overrides({"sensor": {"adc_bits": 8}}, ["sensor.adc_bits=12", "capture.design=fsc/optimal"])
{'sensor': {'adc_bits': 12}, 'capture': {'architecture': 'fsc', 'exposure': 'optimal'}}
"""
from __future__ import annotations

import copy
import re
import tomllib
from typing import Callable, Iterable

from spectracam.core.errors import ConfigError

__all__ = ["DESIGN_PATH", "PATH", "SWITCHES", "apply_override", "apply_overrides", "parse_assignment",
           "parse_value"]

#: ``key``, ``key[i]``, ``table.field`` or ``table.field[i]``; names in either case (``temperatures_K``).
PATH = re.compile(r"^([A-Za-z_][A-Za-z_0-9]*)(?:\.([A-Za-z_][A-Za-z_0-9]*))?(?:\[(\d+)\])?$")
#: "arch/scheme" in one value, so an invalid pair is one error, never two half-applied fields.
DESIGN_PATH = "capture.design"
#: Keys that say what kind of thing their table describes: set to another kind, the old kind's keys go
#: (``--set illuminant.file=spd.csv`` turns a blackbody or CIE scene into a measured SPD; issue 34).
SWITCHES = {"illuminant": ("type", "file")}


def parse_value(text: str) -> object:
    """A TOML value, or the text itself when it is a bare word.

    Parameters
    ----------
    text : str
        The text after ``=``.

    Returns
    -------
    object
        An int, float, bool, str, list, table or date as TOML reads it; else ``text``.
    """
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def parse_assignment(text: str, source: str = "--set") -> tuple[str, object]:
    """``"table.field[i]=VALUE"`` → ``(path, value)``.

    Parameters
    ----------
    text : str
        ``PATH=VALUE``.
    source : str
        The option or file, as errors name it.

    Returns
    -------
    path : str
        The path (:data:`PATH`).
    value : object
        The value (:func:`parse_value`).

    Raises
    ------
    ConfigError
        No ``=``, or not a path.
    """
    path, eq, value = text.partition("=")
    path = path.strip()
    if not eq or not PATH.match(path):
        raise ConfigError(source, text, "must be PATH=VALUE with PATH a 'table.field', 'table.field[i]', 'key' or "
                                        "'key[i]'")
    return path, parse_value(value.strip())


def apply_override(data: dict, path: str, value: object, defaults: Callable[[], dict] | None = None,
                   source: str | None = None, kept: Iterable[str] = ()) -> dict:
    """A copy of ``data`` (a file's tables) with ``path`` (:data:`PATH`) set to ``value`` (module docstring).

    Parameters
    ----------
    data : dict
    path, source : str
    value : object
    defaults : callable, optional
    kept : iterable of str

    Returns
    -------
    dict"""
    m = PATH.match(path) if isinstance(path, str) else None
    if not m:
        raise ConfigError(path, value, "not a path: use 'table.field', 'table.field[i]' or 'key'", source)
    out = copy.deepcopy(data)
    table, key, index = m.groups()
    if path == DESIGN_PATH:
        from spectracam.camera import split_design

        arch, scheme = split_design(value, DESIGN_PATH)
        out.setdefault("capture", {}).update(architecture=arch, exposure=scheme)
        return out
    if index is None and key in SWITCHES.get(table, ()) and isinstance(out.get(table, {}), dict):
        from spectracam.scene.illuminant import switched_table

        mine = {p.split(".", 1)[1].split("[")[0] for p in kept if p.startswith(table + ".")}
        out[table] = switched_table(out.get(table, {}), key, value, mine)
        return out
    if key is None:
        if index is None:
            out[table] = value
            return out
        lst = out.get(table)
        if lst is None and defaults is not None:
            lst = copy.deepcopy(defaults().get(table))
        if not isinstance(lst, list) or int(index) >= len(lst):
            raise ConfigError(path, value, f"{table} is not a list with an element {index}", source)
        lst[int(index)] = value
        out[table] = lst
        return out
    t = out.setdefault(table, {})
    if not isinstance(t, dict):
        raise ConfigError(path, value, f"{table!r} is not a table here", source)
    if index is None:
        t[key] = value
        return out
    lst = t.get(key)
    if lst is None and defaults is not None:
        lst = copy.deepcopy(defaults().get(table, {}).get(key))
    if lst is None:   # a field its spec leaves out of the record while it holds its default
        lst = _unrecorded_default(table, key)
    if not isinstance(lst, list) or int(index) >= len(lst):
        raise ConfigError(path, value, f"{table}.{key} is not a list with an element {index}", source)
    lst[int(index)] = value
    t[key] = lst
    return out


#: Tables whose specs leave fields out of their record while they hold their defaults (issue 37: the lens across the
#: field, the pixel's angle response, the lens-shading correction), so an indexed ``--set`` finds the default there.
_UNRECORDED = {"optics": ("spectracam.optics", "OpticsSpec"), "pixel": ("spectracam.sensor.angle", "PixelAngleSpec"),
               "processing": ("spectracam.processing.color", "ProcessingSpec")}


def _unrecorded_default(table: str, key: str):
    """The default of ``table.key`` as a list, for a spec that does not record its defaults; None otherwise."""
    import dataclasses
    import importlib

    if table not in _UNRECORDED:
        return None
    module, name = _UNRECORDED[table]
    fields = {f.name: f for f in dataclasses.fields(getattr(importlib.import_module(module), name))}
    f = fields.get(key)
    if f is None or f.default is dataclasses.MISSING:
        return None
    return list(f.default) if isinstance(f.default, tuple) else None


def apply_overrides(data: dict, overrides: Iterable[str | tuple[str, object]], defaults: Callable[[], dict] | None = None,
                    source: str = "--set") -> dict:
    """Apply ``overrides`` (``"path=value"`` strings or ``(path, value)`` pairs) in order.

    Parameters
    ----------
    data : dict
        A file's tables (not changed).
    overrides : iterable of str or (str, object)
        The assignments.
    defaults : callable, optional
        As for :func:`apply_override`.
    source : str
        The option or file, as errors name it.

    Returns
    -------
    dict
        The changed copy.
    """
    done: list[str] = []
    for o in overrides:
        path, value = parse_assignment(o, source) if isinstance(o, str) else o
        data = apply_override(data, path, value, defaults, source, kept=done)
        done.append(path)
    return data
