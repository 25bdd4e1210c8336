"""File formats spectracam reads and writes."""
