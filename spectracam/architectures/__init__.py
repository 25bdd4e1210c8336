"""Architectures beyond the paper's three, one module each: every module in this package is imported
when :mod:`spectracam.architecture` is, and registers its architecture there — adding one is adding
a file here.
"""
from importlib import import_module
from pkgutil import iter_modules

for _module in iter_modules(__path__):
    import_module(f"{__name__}.{_module.name}")
