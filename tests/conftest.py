"""Shared fixtures: a small chart scene (160x120 px) rendered once per test session; Debian's Chromium, headless."""
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest

from spectracam.pipeline.scene_file import parse_scene

SMALL = {"image": {"width": 160, "height": 120}}

#: The tests marked slow (issue 39's quick subset: ``pytest -m "not slow"``), measured: see the file's header.
SLOW_TESTS = Path(__file__).parent / "slow_tests.txt"


def pytest_collection_modifyitems(config, items):
    """Mark the tests listed in :data:`SLOW_TESTS` slow (a test may also carry ``@pytest.mark.slow`` itself)."""
    slow = {ln.strip() for ln in SLOW_TESTS.read_text().splitlines() if ln.strip() and not ln.startswith("#")}
    for item in items:
        if item.nodeid in slow:
            item.add_marker(pytest.mark.slow)


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


def pytest_configure(config):
    """Keep the tests' snapshot of colour-science's tables (:mod:`spectracam.core.colour_data`) out of the user's
    cache, from before collection (a module may read a table as it is imported); subprocesses inherit the variable.
    Made once per run by the first reader; removed at the end."""
    if not os.environ.get("SPECTRACAM_TABLES"):
        config._colour_tables = tempfile.mkdtemp(prefix="spectracam-colour-tables-")
        os.environ["SPECTRACAM_TABLES"] = config._colour_tables


def pytest_unconfigure(config):
    folder = getattr(config, "_colour_tables", None)
    if folder:
        os.environ.pop("SPECTRACAM_TABLES", None)
        shutil.rmtree(folder, ignore_errors=True)


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


CHROMIUM, CHROMEDRIVER = "/usr/bin/chromium", "/usr/bin/chromedriver"


@pytest.fixture(scope="session")
def browser():
    """Debian's Chromium, headless, through its own chromedriver (tools/setup.sh --test installs both)."""
    webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed (tools/setup.sh --test)")
    from selenium.webdriver.chrome.service import Service

    missing = [p for p in (CHROMIUM, CHROMEDRIVER) if not os.access(p, os.X_OK)]
    if missing:
        pytest.skip(f"{', '.join(missing)} missing: Debian's chromium and chromium-driver (tools/setup.sh --test "
                    "installs them where apt-get may run)")
    os.environ["SE_OFFLINE"] = "true"  # Selenium Manager must never fetch a browser or driver
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    profile = tempfile.mkdtemp(prefix="spectracam-chromium-")
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
              "--disable-background-networking", "--disable-component-update", "--disable-sync",
              "--disable-dev-shm-usage", f"--user-data-dir={profile}", "--window-size=1400,1500",
              "--force-device-scale-factor=1"):
        opts.add_argument(a)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=opts)
    yield driver
    driver.quit()
    shutil.rmtree(profile, ignore_errors=True)
