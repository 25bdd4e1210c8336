"""The scene every validation runs on: the shipped D65 chart with a camera's measured curves, noise-free."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from spectracam.architecture.cameras import library_curves
from spectracam.core.errors import ConfigError

if TYPE_CHECKING:
    from spectracam.pipeline.scene_file import Scene

__all__ = ["SCENE_OVERRIDES", "validation_scene"]

#: The scene: the shipped D65 chart, small (noise-free, so the size does not change the means).
SCENE_OVERRIDES = {"image": {"width": 192, "height": 144}}


def validation_scene(camera_name: str, filters: dict | None = None, range_nm: tuple | None = None) -> Scene:
    """The shipped D65 chart scene with the camera's curves, noise-free, flat QE (the curves hold it), on
    400–700 nm or the part of it the curves cover (the Sigma's stop at 680 nm).  ``filters`` (with
    ``range_nm``): a ``[filters]`` table of the user's own camera instead of a shipped one.

    Parameters
    ----------
    camera_name : str
        A camera of the shipped library, or the user's camera's name (for the messages).
    filters : dict or None
        The user's ``[filters]`` table; None: the library camera's.
    range_nm : tuple or None
        ``(lo, hi)`` nm the user's curves cover; None: the library camera's.

    Returns
    -------
    Scene
        On 10-nm bands within 400–700 nm.

    Raises
    ------
    ConfigError
        When the curves cover less than 20 nm of 400–700 nm.
    """
    from spectracam.pipeline.scene_file import parse_scene, read_toml, shipped_scene_file

    data = read_toml(shipped_scene_file("d65.toml"), "scene file")
    lo, hi = range_nm or library_curves(camera_name).range_nm  # the scene's 400-700 nm, narrowed to the curves'
    if min(700.0, hi) - max(400.0, lo) < 20.0:
        raise ConfigError("--camera-file", camera_name, f"its curves cover {lo:g}–{hi:g} nm; validation needs at least "
                                                        "20 nm of 400–700 nm")
    lo10, hi10 = 10.0 * np.ceil(max(400.0, lo) / 10.0 - 1e-9), 10.0 * np.floor(min(700.0, hi) / 10.0 + 1e-9)
    wavelengths = {"start_nm": lo10, "stop_nm": hi10, "step_nm": 10.0}
    own = filters if filters is not None else {"camera": camera_name}
    data = {**data, **SCENE_OVERRIDES, "wavelengths": wavelengths,
            "filters": {**data.get("filters", {}), **own, "kind": "camera", "qe": "flat"},
            "sensor": {**data.get("sensor", {}), "shot_noise": False, "dark_current": False, "read_noise": False,
                       "fpn": False, "quantization": False}}
    return parse_scene(data, f"spectracam validate ({camera_name})")
