"""Shared fixtures: a small chart scene (160x120 px) rendered once per test session."""
import numpy as np
import pytest

from spectracam.pipeline.scene_file import parse_scene

SMALL = {"image": {"width": 160, "height": 120}}


def small_scene(**tables):
    data = {k: dict(v) for k, v in SMALL.items()}
    for k, v in tables.items():
        data.setdefault(k, {}).update(v)
    return parse_scene(data)


@pytest.fixture(scope="session", autouse=True)
def private_render_cache(tmp_path_factory):
    """Keep the tests' renders out of the user's render cache (subprocesses inherit the variable)."""
    import os

    old = os.environ.get("SPECTRACAM_CACHE")
    os.environ["SPECTRACAM_CACHE"] = str(tmp_path_factory.mktemp("render-cache"))
    yield
    if old is None:
        os.environ.pop("SPECTRACAM_CACHE", None)
    else:
        os.environ["SPECTRACAM_CACHE"] = old


@pytest.fixture(scope="session")
def scene_5000():
    return small_scene(illuminant={"temperature_K": 5000})


@pytest.fixture(scope="session")
def analytic_5000(scene_5000):
    from spectracam.render import render

    return render(scene_5000, "analytic")


@pytest.fixture(scope="session")
def mitsuba_5000(scene_5000):
    from spectracam.render import render

    return render(scene_5000, "mitsuba")


def patch_means(cube, masks):
    """(24, n_bands) mean radiance of each patch's masked pixels."""
    return np.stack([cube.radiance[m].mean(axis=0, dtype=np.float64) for m in masks])


def assert_gradient_is_central_differences(problem, x, g, indices, rel: float = 1e-4, step=None) -> None:
    """``g`` (the design problem's gradient at ``x``) equals central differences of its objective at each index,
    within ``rel`` of the difference (floor 1e-3); the step is ``step`` or 1e-4 of the variable (at least 1e-4)."""
    for i in indices:
        h = step if step is not None else 1e-4 * max(1.0, abs(x[i]))
        xp, xm = x.copy(), x.copy()
        xp[i] += h
        xm[i] -= h
        fd = (problem.value_and_gradient(xp)[0] - problem.value_and_gradient(xm)[0]) / (2 * h)
        assert abs(g[i] - fd) <= rel * max(abs(fd), 1e-3), (i, g[i], fd)
