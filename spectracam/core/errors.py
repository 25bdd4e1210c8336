"""The one exception type a user sees: a single line naming the field, the value and what is allowed."""
from __future__ import annotations

__all__ = ["MADE_BY", "ArgumentTypeError", "ConfigError", "SpectracamError", "expect", "expect_integer"]


class SpectracamError(Exception):
    """An error caused by the user's input or environment; the CLI prints it as one line, exit 2."""


class ConfigError(SpectracamError, ValueError):
    """A field of a spec, scene/config file or command line has a value that is not allowed.

    Parameters
    ----------
    field : str
        The field's dotted name as the user writes it (``"sensor.read_noise_e"``).
    value : object
        The value given (shown with ``repr``).
    allowed : str
        What is allowed, as a phrase (``"must be >= 0"``).
    source : str or None
        Where the value came from (a file's path, ``"command line"``); None: not known yet.
    """

    def __init__(self, field: str, value: object, allowed: str, source: str | None = None):
        self.field, self.value, self.allowed, self.source = field, value, allowed, source
        where = f"{source}: " if source else ""
        super().__init__(f"{where}{field} = {value!r}: {allowed}")

    def with_source(self, source: str | None) -> "ConfigError":
        """The same error, located in ``source`` (a file, "command line") unless it already is.

        Parameters
        ----------
        source : str or None
            Where the value came from; None leaves the error as it is.

        Returns
        -------
        ConfigError
            This error if it already has a source or ``source`` is None, else a copy located in ``source``.
        """
        if source is None or self.source is not None:
            return self
        return ConfigError(self.field, self.value, self.allowed, source)


class ArgumentTypeError(SpectracamError, TypeError):
    """A function of the Python API was given an argument of the wrong type: one line naming the
    function's argument, the type given and what is allowed (raised where the argument enters, not as an
    AttributeError deep inside)."""


#: What each kind of object is made by, for the messages of :func:`expect`.
MADE_BY = {
    "Scene": "a Scene (spectracam.load_scene(path) reads a scene file, spectracam.parse_scene(data) a dict)",
    "RadianceCube": "a RadianceCube (spectracam.render(scene); spectracam.read_radiance_exr(path) returns (cube, "
                    "attributes); RadianceCube(radiance, wavelengths_nm) wraps an (H, W, bands) array)",
    "RawCapture": "a RawCapture (spectracam.capture(cube), or spectracam.read_raw_exr(path))",
    "CameraSpec": "a CameraSpec (scene.camera, or spectracam.CameraSpec.from_dict(tables) for [optics], "
                  "[filters], [sensor], [capture] tables)",
    "SensorSpec": "a SensorSpec (scene.camera.sensor, or spectracam.SensorSpec.from_dict(table))",
    "ProcessingSpec": "a ProcessingSpec (scene.processing, or ProcessingSpec.from_dict(table))",
    "WavelengthGrid": "a WavelengthGrid (scene.grid, or WavelengthGrid(centres_nm))",
}


def expect(value: object, types: type | tuple[type, ...], where: str, allowed: str | None = None,
           optional: bool = False) -> object:
    """``value`` if it is one of ``types`` (or None when ``optional``); else :class:`ArgumentTypeError`
    naming ``where`` (``"capture(cube)"``), the type given and what is allowed (default: what makes the
    first type, :data:`MADE_BY`).

    Parameters
    ----------
    value : object
        The argument as given.
    types : type or tuple of type
        The types allowed (``isinstance``'s second argument); the first names what is allowed by default.
    where : str
        The function and argument, as the error names them.
    allowed : str or None
        What is allowed, in words; None: :data:`MADE_BY`'s entry for the first type.
    optional : bool
        Whether None is allowed too.

    Returns
    -------
    object
        ``value``, unchanged.
    """
    if (optional and value is None) or isinstance(value, types):
        return value
    first = (types if isinstance(types, tuple) else (types,))[0].__name__
    allowed = allowed or MADE_BY.get(first, f"a {first}")
    given = type(value).__name__
    if isinstance(value, tuple) and len(value) == 2 and first == "RadianceCube":
        given += " (read_radiance_exr's (cube, attributes)? pass its [0])"
    raise ArgumentTypeError(f"{where}: got {given}; allowed: {allowed}{' or None' if optional else ''}")


def expect_integer(value: object, where: str, optional: bool = False) -> int | None:
    """An integer (not a bool, not a float or a string of digits), or None when ``optional``.

    Parameters
    ----------
    value : object
        The argument as given.
    where : str
        The function and argument, as the :class:`ArgumentTypeError` names them.
    optional : bool
        Whether None is allowed too.

    Returns
    -------
    int or None
        ``value``, unchanged (any ``numbers.Integral``, NumPy's included).
    """
    import numbers

    if (optional and value is None) or (isinstance(value, numbers.Integral) and not isinstance(value, bool)):
        return value
    raise ArgumentTypeError(f"{where}: got {type(value).__name__} {value!r}; allowed: an integer"
                            f"{' or None' if optional else ''}")
