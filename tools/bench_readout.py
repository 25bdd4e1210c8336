"""Benchmark of the read-out schemes (issue 36): each against a single read by the fused kernel, same run.

Prints, for a 2 Mpx frame (1920 × 1080 rates given), the best of several interleaved runs of each scheme and of
the fused single read (``spectracam.sensor.kernels.expose``), their ratio, and for multiple capture the target
``1.5 + 0.1·N``; then the whole capture (``spectracam.camera.capture.capture`` of a random 30-band float32 cube,
2048 × 1024 px, CFA) with ``readout = "single"`` against ``"multiple_capture"`` for N = 2, 4, 8, 16, interleaved,
best of the repeats.  Not a test.  ``python tools/bench_readout.py [repeats] [--no-capture]``.
"""
from __future__ import annotations

import sys
import time

import numpy as np

from spectracam.sensor import SensorSpec, expose, fixed_pattern, kernels
from spectracam.sensor import readout

__all__ = ["main"]


def _best(fn, repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def _pair(sensor, rate, pattern, repeats: int) -> tuple[float, float]:
    """(single, scheme) best times, interleaved so both see the same machine state."""
    noise = np.random.SeedSequence(1)
    single = (lambda: kernels.expose(rate, 0.05, sensor, noise, pattern)) if kernels.available() else (
        lambda: expose(rate, 0.05, sensor, noise, pattern))
    scheme = lambda: readout.read(rate, 0.05, sensor, noise, pattern)  # noqa: E731
    single(), scheme()  # compile, warm
    ts, tr = np.inf, np.inf
    for _ in range(repeats):
        ts, tr = min(ts, _best(single, 1)), min(tr, _best(scheme, 1))
    return ts, tr


def _capture_pair(cube, camera, n: int, repeats: int) -> tuple[float, float]:
    """(single, multiple capture N) best whole-capture times, interleaved."""
    from spectracam.camera.capture import capture

    box = (slice(0, 64), slice(0, 64))
    mc = camera.replace(sensor=camera.sensor.replace(readout="multiple_capture", readout_samples=n))
    single = lambda: capture(cube, camera, 1, metering_box=box)  # noqa: E731
    multi = lambda: capture(cube, mc, 1, metering_box=box)  # noqa: E731
    single(), multi()  # compile, warm
    ts, tm = np.inf, np.inf
    for _ in range(repeats):
        ts, tm = min(ts, _best(single, 1)), min(tm, _best(multi, 1))
    return ts, tm


def capture_main(repeats: int = 5) -> None:
    from spectracam.camera import CameraSpec
    from spectracam.render.cube import RadianceCube

    wl = np.linspace(400.0, 700.0, 30)
    radiance = np.random.default_rng(0).uniform(0.0, 0.02, (1024, 2048, 30)).astype(np.float32)
    cube = RadianceCube(radiance, wl)
    camera = CameraSpec()
    print(f"whole capture, 2048 x 1024 px x 30 bands, {camera.design}, best of {repeats}")
    print(f"{'read-out':<26}{'single s':>10}{'scheme s':>10}{'ratio':>8}{'target':>8}")
    for n in (2, 4, 8, 16):
        ts, tm = _capture_pair(cube, camera, n, repeats)
        print(f"{'multiple_capture N=' + str(n):<26}{ts:>10.4f}{tm:>10.4f}{tm / ts:>8.2f}{1.5 + 0.1 * n:>8.2f}")


def main(repeats: int = 5) -> None:
    rate = np.random.default_rng(0).uniform(0, 3e6, (1080, 1920)).astype(np.float32)
    print(f"2 Mpx frame, {kernels.threads()} threads, fused kernels: {kernels.available()}, best of {repeats}")
    print(f"{'scheme':<26}{'single s':>10}{'scheme s':>10}{'ratio':>8}{'target':>8}")
    for n in (2, 4, 8, 16):
        s = SensorSpec(readout="multiple_capture", readout_samples=n)
        ts, tr = _pair(s, rate, fixed_pattern(s, rate.shape, 1), repeats)
        target = 1.5 + 0.1 * n
        print(f"{'multiple_capture N=' + str(n):<26}{ts:>10.4f}{tr:>10.4f}{tr / ts:>8.2f}{target:>8.2f}")
    for name in ("dual_gain", "split_pixel", "bracketing"):
        s = SensorSpec(readout=name)
        ts, tr = _pair(s, rate, fixed_pattern(s, rate.shape, 1), repeats)
        print(f"{name:<26}{ts:>10.4f}{tr:>10.4f}{tr / ts:>8.2f}{'-':>8}")


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    reps = int(args[0]) if args else 5
    main(reps)
    if "--no-capture" not in sys.argv:
        capture_main(reps)
