"""How long `spectracam view` takes against the run it shows, and how large the page is.

    python3 tools/bench_view.py [--size 640x480] [--repeat 3]

Times, in one process, `simulate` of the D65 chart (analytic renderer: the baseline, the work whose
outputs the page shows) and `write_view` of its directory; prints the median of each, their ratio, the
page's size and the stride the page keeps.  Then the same for a paper --quick directory (25 cases).
"""
from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def timed(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def main() -> int:
    from click.testing import CliRunner

    from spectracam.cli import main as cli
    from spectracam.view import write_view
    from spectracam.view.contents import find_contents

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="640x480")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    w, h = (int(v) for v in a.size.lower().split("x"))
    work = Path(tempfile.mkdtemp(prefix="bench_view_"))

    def run(args):
        r = CliRunner().invoke(cli, args, catch_exceptions=False)
        if r.exit_code != 0:
            raise SystemExit(r.output)

    sim = work / "simulate"
    t_sim = timed(lambda: run(["simulate", "d65", "-o", str(sim), "--renderer", "analytic", "--quiet",
                               "--set", f"image.width={w}", "--set", f"image.height={h}"]), a.repeat)
    t_view = timed(lambda: write_view(sim), a.repeat)
    page = (sim / "index.html").stat().st_size
    from spectracam.view.cases import load_case

    stride = load_case(".", sim / "radiance.exr", sim / "raw.exr", sim / "rendered.exr").stride
    print(f"simulate d65 {w}x{h} (analytic): {t_sim:.2f} s; view: {t_view:.2f} s = {t_view / t_sim:.2f} x the "
          f"simulate; page {page / 1e6:.1f} MB, 1 pixel in {stride} along each axis")
    paper = work / "paper"
    t_paper = timed(lambda: run(["paper", "--quick", "-o", str(paper), "--renderer", "analytic", "--quiet"]), 1)
    t_pview = timed(lambda: write_view(paper), a.repeat)
    print(f"paper --quick (analytic, {len(find_contents(paper).cases)} cases): {t_paper:.2f} s; view: "
          f"{t_pview:.2f} s = {t_pview / t_paper:.2f} x the paper run; page "
          f"{(paper / 'index.html').stat().st_size / 1e6:.1f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
