"""A render cache keyed on everything that determines the radiance cube.

Key: SHA-256 of the scene's render-relevant tables (chart, illuminant, wavelengths, image, render),
the renderer, and the spectracam and Mitsuba versions.  An entry is a spectral EXR and, beside it, the
SHA-256 of its pixel data; on a hit the scene recorded in the file is compared with the request and
the pixels with their checksum, so a collision, a hand-edited file or a damaged one is rendered again,
never served.  Location: ``$SPECTRACAM_CACHE``, ``$XDG_CACHE_HOME/spectracam/renders`` or
``~/.cache/spectracam/renders``.
"""
from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from spectracam._version import __version__
from spectracam.core.files import user_cache_dir
from spectracam.io.exr import read_radiance_exr, write_radiance_exr
from spectracam.render import render

if TYPE_CHECKING:
    from spectracam.pipeline.scene_file import Scene
    from spectracam.render.cube import RadianceCube

__all__ = ["RENDER_METHOD", "RENDER_TABLES", "TEXTURED_RENDER_METHOD", "cache_dir", "cached_render",
           "pixel_checksum", "render_key"]

RENDER_TABLES = ("chart", "illuminant", "wavelengths", "image", "render")
#: Bumped whenever a renderer's method changes what it writes for the same scene, so older entries
#: are never served: 2 = Mitsuba renders light-weighted band-constant spectra (issue 17).
RENDER_METHOD = 2
#: The same for a textured target (spectracam.render.target), whose ``[target]`` table is keyed too (a chart
#: scene's key is unchanged): 3 = every band traced through the same sample positions, one per texel centre
#: (issue 34; before, each band drew new positions and an edge pixel was no mixture of its texels).
TEXTURED_RENDER_METHOD = 3


def cache_dir() -> Path:
    """``$SPECTRACAM_CACHE``, else ``$XDG_CACHE_HOME/spectracam/renders`` (the XDG Base Directory specification's
    user cache, when set to an absolute path), else ``~/.cache/spectracam/renders``."""
    if os.environ.get("SPECTRACAM_CACHE"):
        return Path(os.environ["SPECTRACAM_CACHE"])
    return user_cache_dir() / "renders"


def render_key(scene: Scene, renderer: str) -> tuple[str, dict]:
    """The cache key of a scene rendered by a renderer, and what it was computed from.

    Parameters
    ----------
    scene : Scene
        The scene; its render-relevant tables (:data:`RENDER_TABLES`, and ``target`` when textured) are keyed.
    renderer : str
        The renderer's registered name (``"mitsuba"``, ``"analytic"``).

    Returns
    -------
    key : str
        The first 32 hexadecimal digits of the SHA-256 of ``ident`` as sorted JSON.
    ident : dict
        What the key identifies: the scene's tables, the renderer, the render method (:data:`RENDER_METHOD` or
        :data:`TEXTURED_RENDER_METHOD`) and the spectracam and Mitsuba versions (Mitsuba's only for its renderer).
    """
    d = scene.to_dict()
    tables = ("target", *RENDER_TABLES) if "target" in d else RENDER_TABLES   # to_dict has it when textured
    mitsuba_version = None
    if renderer == "mitsuba":   # imported only for its renderer (0.3-0.6 s that an analytic run does not need)
        import mitsuba

        mitsuba_version = mitsuba.__version__
    ident = {"scene": {k: d[k] for k in tables}, "renderer": renderer,
             "method": TEXTURED_RENDER_METHOD if "target" in d else RENDER_METHOD,
             "spectracam": __version__, "mitsuba": mitsuba_version}
    text = json.dumps(ident, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:32], ident


def pixel_checksum(cube: RadianceCube) -> str:
    """SHA-256 of a cube's float32 pixel data.

    Parameters
    ----------
    cube : RadianceCube
        The cube; its ``(H, W, B)`` radiance is hashed as contiguous float32.

    Returns
    -------
    str
        The hexadecimal SHA-256 digest (64 digits).
    """
    import numpy as np

    return hashlib.sha256(np.ascontiguousarray(cube.radiance, dtype=np.float32).tobytes()).hexdigest()


def cached_render(scene: Scene, renderer: str = "mitsuba", progress: bool = False,
                  log: Callable[[str], object] | None = None,
                  directory: Path | None = None) -> tuple[RadianceCube, bool]:
    """``(cube, hit)``: the cached cube for this scene and renderer, or a fresh render stored for next time.

    Parameters
    ----------
    scene : Scene
        The scene to render.
    renderer : str
        The renderer's registered name.
    progress : bool
        Show the renderer's progress bar on a miss.
    log : callable or None
        Receives a line when an entry does not match or the cache cannot be written.
    directory : Path or None
        The cache's folder; ``None``: :func:`cache_dir`.

    Returns
    -------
    cube : RadianceCube
        The ``(H, W, B)`` radiance, W·m⁻²·sr⁻¹·nm⁻¹, with the scene in its metadata.
    hit : bool
        Whether it was served from the cache.
    """
    from spectracam.core.files import atomic_write

    key, ident = render_key(scene, renderer)
    path = (directory or cache_dir()) / f"{key}.exr"
    checksum = path.with_suffix(".sha256")
    if path.exists():
        try:
            cube, attrs = read_radiance_exr(path)
            recorded = json.loads(attrs.get("spectracamScene", "{}"))
            if ({k: recorded.get(k) for k in ident["scene"]} == ident["scene"]
                    and attrs.get("spectracamRenderer") == renderer
                    and checksum.read_text().strip() == pixel_checksum(cube)):
                cube.metadata["scene"] = scene.to_dict()
                return cube, True
            if log:
                log(f"render cache entry {path.name} does not match its scene or checksum: rendering again")
        except Exception:  # unreadable or damaged entry: render again and overwrite it
            pass
    cube = render(scene, renderer=renderer, progress=progress, log=log)
    try:
        write_radiance_exr(path, cube)
        atomic_write(checksum, pixel_checksum(cube).encode())
    except OSError as e:  # a read-only cache never stops a run
        if log:
            log(f"render cache not written ({e.strerror or e}); the run goes on")
    return cube, False
