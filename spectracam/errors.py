"""The one exception type a user sees: a single line naming the field, the value and what is allowed."""
from __future__ import annotations


class SpectracamError(Exception):
    """An error caused by the user's input or environment; the CLI prints it as one line, exit 2."""


class ConfigError(SpectracamError):
    """A field of a scene/config file has a value that is not allowed."""

    def __init__(self, field: str, value, allowed: str, source: str | None = None):
        self.field, self.value, self.allowed, self.source = field, value, allowed, source
        where = f"{source}: " if source else ""
        super().__init__(f"{where}{field} = {value!r}: {allowed}")
