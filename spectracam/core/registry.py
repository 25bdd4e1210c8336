"""Named extension points: one registry type for every "which one?" choice in the pipeline.

A registry maps a name to an implementation (a function, a class, a constant).  Looking up an
unknown name raises one :class:`~spectracam.core.errors.ConfigError` naming the field, the value and
the registered names — the same line from Python, from a file and from the command line, because
spec validation and CLI choices read the same registry.  A plug-in registers under a new name and
is accepted everywhere at once (the pattern of colour-science's ``*_METHODS`` mappings).

Examples
--------
>>> from spectracam.core.registry import Registry
>>> SHAPES = Registry("demo.shape", "shape")
>>> @SHAPES.register("square")
... def area(side): return side * side
>>> SHAPES["square"](3)
9
>>> SHAPES.get("circle")
Traceback (most recent call last):
...
spectracam.core.errors.ConfigError: demo.shape = 'circle': must be one of 'square'
"""
from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from typing import Generic, TypeVar

from spectracam.core.errors import ConfigError

__all__ = ["T", "Registry"]

T = TypeVar("T")


class Registry(Mapping[str, T], Generic[T]):
    """A name → implementation map for one field (e.g. ``processing.delta_e``).

    Parameters
    ----------
    field : str
        The field whose values name the implementations (``"processing.delta_e"``): the field an unknown name's
        :class:`~spectracam.core.errors.ConfigError` names.
    what : str
        What an implementation is, in words, for errors about the registry itself.
    """

    def __init__(self, field: str, what: str):
        self.field, self.what = field, what
        self._items: dict[str, T] = {}

    def register(self, name: str, obj: T | None = None) -> Callable[[T], T] | T:
        """Register ``obj`` under ``name``; without ``obj``, a decorator that does so.

        Parameters
        ----------
        name : str
            The name (not empty); registering it again replaces the earlier implementation.
        obj : T or None
            The implementation; None: return a decorator that registers what it decorates.

        Returns
        -------
        T or callable
            ``obj``; without it, the decorator (which returns what it decorates).
        """
        if not isinstance(name, str) or not name:
            raise ValueError(f"{self.what}: a registered name must be a non-empty string, not {name!r}")

        def add(o: T) -> T:
            self._items[name] = o
            return o

        return add if obj is None else add(obj)

    def unregister(self, name: str) -> None:
        """Remove a plug-in (tests that register one clean up with this).

        Parameters
        ----------
        name : str
            The registered name; an unknown name is ignored.
        """
        self._items.pop(name, None)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self._items)

    def allowed(self) -> str:
        return "must be one of " + ", ".join(repr(n) for n in self._items)

    def check(self, name: object, field: str | None = None) -> str:
        """``name`` if it is registered, else a ConfigError naming ``field`` (default: this registry's).

        Parameters
        ----------
        name : object
            The name given (anything that is not a registered string is refused).
        field : str or None
            The field to name in the error; None: this registry's.

        Returns
        -------
        str
            ``name``.
        """
        if not isinstance(name, str) or name not in self._items:
            raise ConfigError(field or self.field, name, self.allowed())
        return name

    def get(self, name: object, field: str | None = None) -> T:  # type: ignore[override]
        """The implementation registered under ``name`` (:meth:`check`'s error if none is).

        Parameters
        ----------
        name : object
            The name given.
        field : str or None
            The field to name in the error; None: this registry's.

        Returns
        -------
        T
            The implementation.
        """
        return self._items[self.check(name, field)]

    def __getitem__(self, name: str) -> T:
        return self.get(name)

    def __contains__(self, name) -> bool:   # Mapping's would raise the ConfigError of an unknown name
        return name in self._items

    def __iter__(self) -> Iterator[str]:
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __repr__(self) -> str:
        return f"Registry({self.field!r}: {', '.join(self._items)})"
