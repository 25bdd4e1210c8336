"""The one exception type a user sees: a single line naming the field, the value and what is allowed."""
from __future__ import annotations


class SpectracamError(Exception):
    """An error caused by the user's input or environment; the CLI prints it as one line, exit 2."""


class ConfigError(SpectracamError, ValueError):
    """A field of a spec, scene/config file or command line has a value that is not allowed."""

    def __init__(self, field: str, value, allowed: str, source: str | None = None):
        self.field, self.value, self.allowed, self.source = field, value, allowed, source
        where = f"{source}: " if source else ""
        super().__init__(f"{where}{field} = {value!r}: {allowed}")

    def with_source(self, source: str | None) -> "ConfigError":
        """The same error, located in ``source`` (a file, "command line") unless it already is."""
        if source is None or self.source is not None:
            return self
        return ConfigError(self.field, self.value, self.allowed, source)
