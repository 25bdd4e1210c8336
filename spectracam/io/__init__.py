"""File formats spectracam reads and writes."""

__all__: list = []
