"""Specs: frozen, validated, comparable, hashable descriptions of one stage's parameters.

Every stage owns a spec (a frozen dataclass deriving from :class:`Spec`): its fields carry the
defaults with their reasons, and :meth:`Spec.validate` checks ranges, registered names and
cross-field rules, so an invalid spec cannot be built from Python any more than from a file.
Conversion to and from the plain dicts of TOML/JSON is derived from the fields, not written by
hand: ``spec.to_dict()`` round-trips through ``type(spec).from_dict(...)``.

>>> from dataclasses import dataclass
>>> @dataclass(frozen=True)
... class LensSpec(Spec):
...     TABLE = "lens"
...     f_number: float = 1.4
...     def validate(self):
...         self.number("f_number", 0.5, 64.0)
>>> LensSpec(f_number=2).to_dict()
{'f_number': 2.0}
>>> LensSpec.from_dict({"f_number": 0.1})
Traceback (most recent call last):
...
spectracam.core.errors.ConfigError: lens.f_number = 0.1: must be a number between 0.5 and 64
"""
from __future__ import annotations

import dataclasses
import functools
import math
import typing
from typing import TYPE_CHECKING, Any, ClassVar, Self

import numpy as np

from spectracam.core.errors import ConfigError

if TYPE_CHECKING:
    from spectracam.core.registry import Registry

__all__ = ["Spec", "check_curve"]


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _range_text(lo: float, hi: float, lo_open: bool, unit: str) -> str:
    u = f" {unit}" if unit else ""
    if hi == math.inf:
        return f"{'>' if lo_open else '≥'} {lo:g}{u}"
    if lo == -math.inf:
        return f"≤ {hi:g}{u}"
    return f"between {lo:g} and {hi:g}{u}"


@functools.lru_cache(maxsize=None)
def _type_hints(cls) -> dict:
    """``typing.get_type_hints`` of a spec class, once per class: it compiles every annotation string anew
    each call, which was 60 % of building a scene (a 100 000-cell sweep validates 100 000 scenes)."""
    return typing.get_type_hints(cls)


class Spec:
    """Base of every stage's spec.  Subclasses are ``@dataclass(frozen=True)`` and set ``TABLE``
    (the TOML table / dotted prefix that names their fields in errors)."""

    TABLE: ClassVar[str] = ""

    def __post_init__(self) -> None:
        hints = _type_hints(type(self))
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            hint = hints.get(f.name)
            # numbers written as integers are floats; lists from TOML/JSON are tuples (hashable)
            if (hint is float or hint == (float | None)) and _is_number(v):
                object.__setattr__(self, f.name, float(v))
            elif isinstance(v, list):
                object.__setattr__(self, f.name, tuple(v))
        self.validate()

    # -- validation helpers, each raising one ConfigError naming the field -------------------
    def validate(self) -> None:
        """Check every field; overridden by each stage's spec."""

    def field_name(self, name: str) -> str:
        """A field's name as the user writes it, under the spec's table.

        Parameters
        ----------
        name : str
            The dataclass field.

        Returns
        -------
        str
            ``"TABLE.name"`` (``name`` for a spec without a table).
        """
        return f"{self.TABLE}.{name}" if self.TABLE else name

    def error(self, name: str, allowed: str, value: Any = dataclasses.MISSING) -> ConfigError:
        """The :class:`~spectracam.core.errors.ConfigError` of a field (to raise).

        Parameters
        ----------
        name : str
            The dataclass field.
        allowed : str
            What is allowed, as a phrase.
        value : Any
            The value to show; default: the field's.

        Returns
        -------
        ConfigError
            The error, naming the field under the spec's table.
        """
        return ConfigError(self.field_name(name), getattr(self, name) if value is dataclasses.MISSING else value,
                           allowed)

    def number(self, name: str, lo: float = -math.inf, hi: float = math.inf, *, lo_open: bool = False,
               unit: str = "") -> None:
        """Check that a field is a real number (not a bool) in ``[lo, hi]``; else raise its error.

        Parameters
        ----------
        name : str
            The dataclass field.
        lo, hi : float
            The bounds, in the field's unit.
        lo_open : bool
            Exclude ``lo`` itself.
        unit : str
            The unit, for the error's wording.
        """
        v = getattr(self, name)
        ok = _is_number(v) and lo <= v <= hi and not (lo_open and v == lo)
        if not ok:
            raise self.error(name, f"must be a number {_range_text(lo, hi, lo_open, unit)}")

    def integer(self, name: str, lo: int, hi: int | None = None) -> None:
        """Check that a field is an integer (not a bool) of at least ``lo`` and at most ``hi``.

        Parameters
        ----------
        name : str
            The dataclass field.
        lo : int
            The least value allowed.
        hi : int or None
            The largest value allowed; None: no bound.
        """
        v = getattr(self, name)
        if isinstance(v, bool) or not isinstance(v, int) or v < lo or (hi is not None and v > hi):
            raise self.error(name, f"must be an integer ≥ {lo}" if hi is None else
                             f"must be an integer between {lo} and {hi}")

    def boolean(self, *names: str) -> None:
        """Check that fields are true or false (a bool, not 0 or 1).

        Parameters
        ----------
        *names : str
            The dataclass fields.
        """
        for name in names:
            if not isinstance(getattr(self, name), bool):
                raise self.error(name, "must be true or false")

    def string(self, name: str) -> None:
        """Check that a field is a string.

        Parameters
        ----------
        name : str
            The dataclass field.
        """
        if not isinstance(getattr(self, name), str):
            raise self.error(name, "must be a string")

    def numbers(self, name: str, n: int, lo: float = -math.inf, *, lo_open: bool = False, increasing: bool = False,
                unit: str = "") -> None:
        """Check that a field is a tuple of ``n`` real numbers of at least ``lo``; store them as floats.

        Parameters
        ----------
        name : str
            The dataclass field.
        n : int
            How many numbers.
        lo : float
            The least value allowed, in the field's unit.
        lo_open : bool
            Exclude ``lo`` itself.
        increasing : bool
            Require strictly increasing numbers.
        unit : str
            The unit, for the error's wording.
        """
        v = getattr(self, name)
        ok = (isinstance(v, tuple) and len(v) == n and all(_is_number(x) for x in v)
              and all(x > lo if lo_open else x >= lo for x in v))
        if not ok or (increasing and any(b <= a for a, b in zip(v, v[1:]))):
            raise self.error(name, f"must be a list of {n} numbers {_range_text(lo, math.inf, lo_open, unit)}"
                             + (", increasing" if increasing else ""), list(v) if isinstance(v, tuple) else v)
        object.__setattr__(self, name, tuple(float(x) for x in v))

    def choice(self, name: str, registry: Registry | tuple) -> None:
        """The field names a member of ``registry`` (a :class:`~spectracam.core.registry.Registry` or a tuple).

        Parameters
        ----------
        name : str
            The dataclass field.
        registry : Registry or tuple
            The names allowed.
        """
        v = getattr(self, name)
        if hasattr(registry, "check"):
            registry.check(v, self.field_name(name))
        elif v not in registry:
            raise self.error(name, "must be one of " + ", ".join(repr(c) for c in registry))

    # -- conversion ---------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """Plain, JSON-serialisable fields (nested specs as tables, tuples as lists)."""
        out = {}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            out[f.name] = v.to_dict() if isinstance(v, Spec) else (list(v) if isinstance(v, tuple) else v)
        return out

    @classmethod
    def from_dict(cls, data: object, source: str | None = None, base: "Spec | None" = None) -> Self:
        """Build from a table; keys not given keep ``base``'s values (default: the defaults).
        Unknown keys and bad values raise one ConfigError naming ``source``.

        Parameters
        ----------
        data : object
            The table (a dict of field names to values, as TOML reads them); anything else is refused.
        source : str or None
            Where the table came from (a file, ``"command line"``), for the error.
        base : Spec or None
            The spec whose values fill the keys not given; None: the defaults.

        Returns
        -------
        Self
            The validated spec.
        """
        try:
            if not isinstance(data, dict):
                raise ConfigError(cls.TABLE or "table", data, "must be a table")
            names = {f.name for f in dataclasses.fields(cls)}
            for k in data:
                if k not in names:
                    raise ConfigError(f"{cls.TABLE}.{k}" if cls.TABLE else k, data[k],
                                      "unknown key; allowed: " + ", ".join(sorted(names)))
            kwargs = dict(data)
            if base is not None:
                kwargs = {**{f.name: getattr(base, f.name) for f in dataclasses.fields(cls)}, **kwargs}
            return cls(**kwargs)
        except ConfigError as e:
            raise e.with_source(source) from None

    def replace(self, **changes: Any) -> Self:
        """A validated copy with some fields changed.

        Parameters
        ----------
        **changes : Any
            New values by field name.

        Returns
        -------
        Self
            The copy (validated as a new spec is).
        """
        return dataclasses.replace(self, **changes)


def check_curve(spec: "Spec", wl_field: str, value_field: str, required: bool) -> None:
    """A tabulated curve of a spec: increasing wavelengths and values in [0, 1], of equal length.

    Checks the curve (raising the spec's error) and stores both fields as tuples of floats.

    Parameters
    ----------
    spec : Spec
        The spec holding the curve.
    wl_field : str
        The field of its wavelengths, nm.
    value_field : str
        The field of its values (transmittance or QE, 0…1).
    required : bool
        Whether an empty curve is an error.
    """
    wl, v = getattr(spec, wl_field), getattr(spec, value_field)
    if not wl and not v:
        if required:
            raise spec.error(value_field, "needs a curve (wavelengths and values, or a file)", ())
        return
    ok = (isinstance(wl, tuple) and isinstance(v, tuple) and len(wl) == len(v) >= 2
          and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in wl + v))
    if not ok or np.any(np.diff(np.asarray(wl, float)) <= 0) or not np.all(np.isfinite(np.asarray(wl + v, float))):
        raise spec.error(wl_field, "must be ≥ 2 increasing wavelengths (nm) with as many values", list(wl))
    if min(v) < 0 or max(v) > 1:
        raise spec.error(value_field, "values must lie in [0, 1]", [min(v), max(v)])
    object.__setattr__(spec, wl_field, tuple(float(x) for x in wl))
    object.__setattr__(spec, value_field, tuple(float(x) for x in v))
