"""The package's version, in a module of its own so that every stage can import it from below
(``from .._version import __version__``) instead of reaching back up to the package ``__init__``, which imports
the stages. Keep equal to ``pyproject.toml``'s ``version`` (``tests/test_api.py``)."""

__version__ = "0.1.0"

__all__ = ["__version__"]
