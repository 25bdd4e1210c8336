"""``spectracam field``: which architecture keeps colour uniform to the corner of the field, and with which microlens
shift (issue 37)."""

__all__: list = []
