"""Do ordinary raw developers develop spectracam's DNGs right?  darktable, RawTherapee and LibRaw on the chart's greys.

    python3 tools/dng_developers.py [--designs cfa/single,prism/optimal,fsc/optimal] [--temperatures 3000,6500]
        [--size 320x240] [--repeat 30] [--developers libraw,rawtherapee,darktable,darktable-modern] [--judge 19-24]
        [--detail] [--keep DIR]

1. For each design × blackbody temperature, ``spectracam simulate scenes/blackbody_3000K.toml --renderer analytic``
   (``--set capture.design=…``, ``--set illuminant.temperature_K=…``, ``--set image.width/height=…``) writes the
   capture's ``raw.dng`` exactly as a user gets it.
2. Each developer develops it with the camera's white balance (the DNG's AsShotNeutral):

   * ``libraw``: rawpy (LibRaw) ``postprocess(use_camera_wb=True, no_auto_bright=True, gamma=(1, 1),
     output_color=sRGB, output_bps=16)``: linear sRGB.
   * ``rawtherapee``: ``rawtherapee-cli -t -b16 -Y -o OUT -c DNG`` with RawTherapee's neutral profile (no ``-p``/``-d``:
     camera white balance, camera-standard input profile, no curves), a fresh HOME per run; output RTv4_sRGB, i.e.
     the sRGB tone curve, decoded here with the sRGB EOTF.
   * ``darktable`` / ``darktable-modern``: ``darktable-cli DNG OUT.tif --icc-type LIN_REC709
     --apply-custom-presets false --core --configdir FRESH --library :memory:`` with
     ``plugins/darkroom/workflow=none`` (no exposure, filmic or base curve: the greys are measured linear, not
     through a tone curve that clips the light ones) and ``plugins/darkroom/chromatic-adaptation=legacy`` (what Debian's
     darktablerc ships: the white-balance module applies the as-shot coefficients) or ``=modern`` (white balance
     to the matrix's D65 "camera reference", then color calibration adapts from the as-shot illuminant), 16-bit
     TIFF, linear Rec.709/sRGB primaries.
3. The chart's six neutral patches (19–24: white 9.5 … black 2, the chart's scoring boxes; RawTherapee's CFA output
   is cropped 4 px on every side and the boxes follow) → mean linear sRGB → XYZ, scaled so that greys 20–23 have the
   scene's Y → CIELAB against D65.  The reference is the scene's own a*, b* of those patches against the
   illuminant's white (``xyz_to_lab(patch_xyz, white_xyz)``, the greys' own small chroma).  Printed: the largest
   |Δa*| and |Δb*| over the six greys (and which), the same against the camera's own noise-free rendering of the
   greys (its camera → XYZ fit under the scene's light, white kept, then Bradford to D65: what the camera's
   colour allows, whatever the file), the black patch's L* against the scene's, and PASS when |Δa*|, |Δb*| ≤ 2
   against the scene on the judged greys (``--judge``, default all six; ``--detail``: every grey).  For LinearRaw
   captures it first prints what clipping the pedestal-subtracted pixels at 0 does to the darkest grey.
4. darktable (each mode) develops the prism/optimal 3000 K file ``--repeat`` times, each with a fresh config
   directory; the decoded pixels are hashed and the identical outputs counted (expected: all).

Exit status 1 when any check fails, 0 otherwise; a developer that is not installed is skipped with a line.
"""
from __future__ import annotations

import argparse
import collections
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "blackbody_3000K.toml"
GREYS = range(18, 24)  # the chart's neutral row (0-based): white 9.5 ... black 2
LIMIT = 2.0
DARKTABLE_MODES = {"darktable": "legacy", "darktable-modern": "modern"}
DEVELOPERS = ("libraw", "rawtherapee", "darktable", "darktable-modern")


def simulate(out: Path, design: str, temperature: float, size: tuple[int, int], sets=()) -> Path:
    """``spectracam simulate`` of the 3000 K blackbody scene with the design, light and size (and any further
    ``--set PATH=VALUE``); the DNG's path."""
    w, h = size
    cmd = [sys.executable, "-m", "spectracam", "simulate", str(SCENE), "-o", str(out), "--renderer", "analytic",
           "--set", f"image.width={w}", "--set", f"image.height={h}", "--set", f"capture.design={design}",
           "--set", f"illuminant.temperature_K={temperature:g}", "--quiet", *[a for v in sets for a in ("--set", v)]]
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    if r.returncode != 0:
        raise SystemExit(f"simulate {design} {temperature:g} K failed:\n{r.stderr}")
    return out / "raw.dng"


def develop_libraw(dng: Path, out: Path) -> np.ndarray:
    import rawpy

    with rawpy.imread(str(dng)) as r:
        rgb = r.postprocess(use_camera_wb=True, no_auto_bright=True, output_bps=16, gamma=(1, 1), user_flip=0,
                            output_color=rawpy.ColorSpace.sRGB)
    return rgb / 65535.0


def _read_tiff(path: Path) -> np.ndarray:
    import tifffile

    img = tifffile.imread(path)
    return img[..., :3].astype(np.float64) / np.iinfo(img.dtype).max


def develop_rawtherapee(dng: Path, out: Path) -> np.ndarray:
    import colour

    with tempfile.TemporaryDirectory() as home:
        env = {**os.environ, "HOME": home, "XDG_CONFIG_HOME": f"{home}/config", "XDG_CACHE_HOME": f"{home}/cache"}
        r = subprocess.run(["rawtherapee-cli", "-o", str(out), "-t", "-b16", "-Y", "-c", str(dng)], env=env,
                           capture_output=True, text=True)
    if r.returncode != 0 or not out.exists():
        raise RuntimeError(f"rawtherapee-cli failed ({r.returncode}): {r.stdout[-500:]} {r.stderr[-500:]}")
    return colour.models.eotf_sRGB(_read_tiff(out))


def develop_darktable(dng: Path, out: Path, mode: str) -> np.ndarray:
    out.unlink(missing_ok=True)  # darktable-cli writes NAME_01.tif beside an existing NAME.tif
    with tempfile.TemporaryDirectory() as config:
        cmd = ["darktable-cli", str(dng), str(out), "--icc-type", "LIN_REC709", "--apply-custom-presets", "false",
               "--core", "--configdir", config, "--library", ":memory:",
               "--conf", "plugins/imageio/format/tiff/bpp=16", "--conf", "plugins/darkroom/workflow=none",
               "--conf", f"plugins/darkroom/chromatic-adaptation={mode}"]
        r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0 or not out.exists():
        raise RuntimeError(f"darktable-cli failed ({r.returncode}): {r.stdout[-500:]} {r.stderr[-500:]}")
    return _read_tiff(out)


def develop(name: str, dng: Path, out_dir: Path, tag: str) -> np.ndarray:
    if name == "libraw":
        return develop_libraw(dng, out_dir / f"{tag}.tif")
    if name == "rawtherapee":
        return develop_rawtherapee(dng, out_dir / f"{tag}.tif")
    return develop_darktable(dng, out_dir / f"{tag}.tif", DARKTABLE_MODES[name])


def missing(name: str) -> str | None:
    """Why a developer cannot run here, or None."""
    if name == "libraw":
        try:
            import rawpy  # noqa: F401
        except ImportError:
            return "rawpy (LibRaw) is not installed"
        return None
    exe = "rawtherapee-cli" if name == "rawtherapee" else "darktable-cli"
    return None if shutil.which(exe) else f"{exe} is not on PATH"


def version(name: str) -> str:
    if name == "libraw":
        import rawpy

        return f"LibRaw {'.'.join(map(str, rawpy.libraw_version))} (rawpy {rawpy.__version__})"
    if name == "rawtherapee":
        out = subprocess.run(["rawtherapee-cli", "-v"], capture_output=True, text=True).stdout
        line = next((ln for ln in out.splitlines() if "version" in ln.lower()), out.strip()[:60])
        return line.strip()
    out = subprocess.run(["darktable-cli", "--version"], capture_output=True, text=True).stdout
    return f"{out.splitlines()[0].strip() if out else 'darktable-cli'}, chromatic-adaptation={DARKTABLE_MODES[name]}"


class Chart:
    """The truth for one capture: the scene's greys, and the camera's own noise-free rendering of them."""

    def __init__(self, dng: Path):
        import colour

        from spectracam import ChartReference
        from spectracam.io.dng import camera_patches, camera_to_xyz_matrix
        from spectracam.io.exr import read_raw_exr
        from spectracam.core.cielab import xyz_to_lab
        from spectracam.pipeline.scene_file import parse_scene

        self.raw = read_raw_exr(dng.with_name("raw.exr"))
        self.ref = ref = ChartReference.of(parse_scene(self.raw.scene))
        self.srgb = np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_RGB_to_XYZ)
        self.d65 = self.srgb.sum(axis=1)
        #: the scene's own a*, b*: each patch against the illuminant's white
        self.scene = xyz_to_lab(ref.patch_xyz, ref.white_xyz)[list(GREYS)]
        # the camera's own noise-free rendering, developer-independent: the camera → XYZ fit under the scene's
        # light (white kept, as the DNG's matrices are fitted), then Bradford from the light's white to D65
        self.B = camera_to_xyz_matrix(self.raw, ref)
        self.cat = colour.adaptation.matrix_chromatic_adaptation_VonKries(ref.white_xyz, self.d65, transform="Bradford")
        self.camera = self.lab(camera_patches(self.raw, ref) @ self.B.T @ self.cat.T)[list(GREYS)]

    def lab(self, xyz: np.ndarray) -> np.ndarray:
        """CIELAB against D65 of ``(24, 3)`` XYZ scaled so that greys 20–23 have the scene's Y (a developer
        cannot know that the white patch was metered to full scale)."""
        from spectracam.core.cielab import xyz_to_lab

        xyz = xyz * (self.ref.patch_xyz[19:23, 1].sum() / xyz[19:23, 1].sum())
        return xyz_to_lab(xyz, self.d65)

    def developed(self, rgb: np.ndarray) -> np.ndarray:
        """CIELAB ``(6, 3)`` of the six greys of a developed linear-sRGB image (mean per scoring box)."""
        H, W = self.ref.height_px, self.ref.width_px
        h, w = rgb.shape[:2]
        dy, dx = (H - h) // 2, (W - w) // 2  # RawTherapee crops a demosaicked mosaic by 4 px on each side
        if dy < 0 or dx < 0:
            raise RuntimeError(f"developed image {w}x{h} is larger than the scene's {W}x{H}")
        means = [rgb[r.start - dy:r.stop - dy, c.start - dx:c.stop - dx].reshape(-1, 3).mean(axis=0)
                 for r, c in self.ref.boxes]
        return self.lab(np.stack(means) @ self.srgb.T)[list(GREYS)]

    def pedestal_clip(self) -> dict | None:
        """For a LinearRaw DNG (the pedestal subtracted from its pixels, clipped at 0), on the black patch: the
        noise-free signal, the mean code above the pedestal (the ADC floors, so ~½ DN below it) and what the
        file's clip at 0 adds to that mean, per channel in DN; and the camera's rendering of the patch (its
        conversion, as :attr:`camera`) from the unclipped and from the clipped mean codes, as ΔL*, Δa*, Δb*
        against its rendering of the noise-free signal.  None for a CFA DNG."""
        from spectracam.architecture.base import PlanesLayout
        from spectracam.io.dng import camera_patches, linear_raw_pedestal

        raw = self.raw
        if not isinstance(raw.layout, PlanesLayout):
            return None
        s = raw.camera.sensor
        off = linear_raw_pedestal(raw)
        rows, cols = self.ref.boxes[23]
        dn = np.asarray(raw.digital, np.float64)[:, rows, cols].reshape(len(raw.layout.channels), -1)
        code = (dn - s.black_level_dn).mean(axis=1)
        clip = np.clip(dn - off, 0, None).mean(axis=1) - (dn - off).mean(axis=1)
        cam = camera_patches(raw, self.ref)
        expected = cam[23] * s.system_gain_dn_per_e
        lab = []
        for black in (expected, code, code + clip):
            c = cam.copy()
            c[23] = black / s.system_gain_dn_per_e
            lab.append(self.lab(c @ self.B.T @ self.cat.T)[23])
        return {"expected": expected, "code": code, "clip": clip, "unclipped": lab[1] - lab[0],
                "clipped": lab[2] - lab[0]}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--designs", default="cfa/single,prism/optimal,fsc/optimal", help="comma-separated capture.design")
    ap.add_argument("--temperatures", default="3000,6500", help="comma-separated blackbody temperatures, K")
    ap.add_argument("--size", default="320x240", help="image WIDTHxHEIGHT")
    ap.add_argument("--developers", default=",".join(DEVELOPERS), help=f"comma-separated, of {', '.join(DEVELOPERS)}")
    ap.add_argument("--repeat", type=int, default=30, help="darktable runs of one file for the repeatability count "
                                                             "(0: skip)")
    ap.add_argument("--repeat-design", default="prism/optimal")
    ap.add_argument("--repeat-temperature", type=float, default=3000.0)
    ap.add_argument("--judge", default="19-24",
                    help="the greys (1-based chart patch numbers, FIRST-LAST) the pass/fail judges; all six by default "
                         "(19: white 9.5 ... 24: black 2)")
    ap.add_argument("--detail", action="store_true", help="print every grey's a*, b* (developed and scene)")
    ap.add_argument("--keep", type=Path, help="keep the captures and developed images in this directory")
    ap.add_argument("--set", dest="sets", action="append", default=[], metavar="PATH=VALUE",
                    help="a further scene override for every capture (repeatable), e.g. sensor.adc_bits=12")
    a = ap.parse_args()

    designs = [d.strip() for d in a.designs.split(",") if d.strip()]
    temps = [float(t) for t in a.temperatures.split(",") if t.strip()]
    size = tuple(int(v) for v in a.size.lower().split("x"))
    developers = [d.strip() for d in a.developers.split(",") if d.strip()]
    lo, _, hi = a.judge.partition("-")
    a.judged = [k for k, g in enumerate(GREYS) if int(lo) <= g + 1 <= int(hi or lo)]
    if not a.judged:
        ap.error(f"--judge {a.judge!r}: no grey among 19-24")
    for d in developers:
        if d not in DEVELOPERS:
            ap.error(f"--developers: unknown {d!r} (known: {', '.join(DEVELOPERS)})")

    work = a.keep or Path(tempfile.mkdtemp(prefix="dng_developers_"))
    work.mkdir(parents=True, exist_ok=True)
    try:
        return run(a, designs, temps, size, developers, work)
    finally:
        if not a.keep:
            shutil.rmtree(work, ignore_errors=True)


def run(a, designs, temps, size, developers, work: Path) -> int:
    available = []
    for d in developers:
        why = missing(d)
        if why:
            print(f"skipped {d}: {why}")
        else:
            available.append(d)
            print(f"{d}: {version(d)}")
    judged = ", ".join(str(GREYS[k] + 1) for k in a.judged)
    print(f"scene {SCENE.relative_to(ROOT)} at {size[0]}x{size[1]} px, analytic renderer; greys 19-24 "
          f"(white 9.5 ... black 2); pass: |Δa*|, |Δb*| ≤ {LIMIT:g} against the scene's own greys on greys {judged}\n")

    dngs = {}
    t0 = time.perf_counter()
    for design in designs:
        for T in temps:
            out = work / f"{design.replace('/', '_')}_{T:g}K"
            dngs[design, T] = simulate(out, design, T, size, a.sets)
    print(f"{len(dngs)} captures in {time.perf_counter() - t0:.1f} s\n")

    charts = {key: Chart(dng) for key, dng in dngs.items()}
    clips = [(key, c.pedestal_clip()) for key, c in charts.items()]
    clips = [(key, v) for key, v in clips if v is not None]
    if clips:
        print("LinearRaw pixels hold DN minus the pedestal, clipped at 0 (darktable ignores a LinearRaw BlackLevel). "
              "On the chart's\ndarkest grey (black 2), per channel: noise-free signal / mean code above the pedestal "
              "/ what the clip adds, DN;\nthe camera's rendering of the patch from the unclipped and from the clipped "
              "codes against its noise-free rendering:")
        for (design, T), c in clips:
            chans = "  ".join(f"{e:.2f}/{m:.2f}/{b:+.3f}" for e, m, b in zip(c["expected"], c["code"], c["clip"]))
            u, k = c["unclipped"], c["clipped"]
            print(f"  {design:<15}{T:>6g}K  {chans}  unclipped ΔL* {u[0]:+.2f} Δa* {u[1]:+.2f} Δb* {u[2]:+.2f}; "
                  f"clipped ΔL* {k[0]:+.2f} Δa* {k[1]:+.2f} Δb* {k[2]:+.2f}")
        print()

    failures = 0
    head = f"{'developer':<17}{'design':<15}{'light':>7} | vs scene: {'max|Δa*|':>8} {'grey':>4} " \
           f"{'max|Δb*|':>8} {'grey':>4} | vs camera: {'|Δa*|':>5} {'|Δb*|':>5} | {'black L* dev/scene':>18} | result"
    print("vs scene: the developed greys' a*, b* against the scene's own (largest of the six); vs camera: against "
          "the camera's\nown noise-free rendering (camera → XYZ fitted under the scene's light, Bradford to D65): "
          "what no DNG can do better\n")
    print(head)
    print("-" * len(head))
    for dev in available:
        for (design, T), dng in dngs.items():
            chart = charts[design, T]
            try:
                lab = chart.developed(develop(dev, dng, dng.parent, dev))
            except Exception as e:  # noqa: BLE001 - report and go on
                print(f"{dev:<17}{design:<15}{T:>6g}K  error: {e}")
                failures += 1
                continue
            scene, cam = chart.scene, chart.camera
            da, db = np.abs(lab[:, 1] - scene[:, 1]), np.abs(lab[:, 2] - scene[:, 2])
            ca, cb = np.abs(lab[:, 1] - cam[:, 1]).max(), np.abs(lab[:, 2] - cam[:, 2]).max()
            ok = bool(np.all(da[a.judged] <= LIMIT) and np.all(db[a.judged] <= LIMIT))
            failures += not ok
            ia, ib = int(np.argmax(da)), int(np.argmax(db))
            print(f"{dev:<17}{design:<15}{T:>6g}K | {'':>9} {da[ia]:>8.2f} {GREYS[ia] + 1:>4} {db[ib]:>8.2f} "
                  f"{GREYS[ib] + 1:>4} | {'':>10} {ca:>5.2f} {cb:>5.2f} | {lab[5, 0]:>8.2f} / {scene[5, 0]:<7.2f} | "
                  f"{'PASS' if ok else 'FAIL'}")
            if a.detail:
                for k, g in enumerate(GREYS):
                    print(f"{'':<19}grey {g + 1}: L* {lab[k, 0]:6.2f}  a* {lab[k, 1]:+6.2f} (scene {scene[k, 1]:+6.2f},"
                          f" camera {cam[k, 1]:+6.2f})  b* {lab[k, 2]:+6.2f} (scene {scene[k, 2]:+6.2f}, "
                          f"camera {cam[k, 2]:+6.2f})")
        print()

    if a.repeat > 0:
        key = (a.repeat_design, a.repeat_temperature)
        dng = dngs.get(key) or simulate(work / "repeat", *key, size, a.sets)
        white = Chart(dng).ref.boxes[18]
        for dev in (d for d in available if d in DARKTABLE_MODES):
            t0 = time.perf_counter()
            outputs = {}
            hashes = []
            for i in range(a.repeat):
                rgb = develop(dev, dng, dng.parent, f"{dev}_repeat")
                h = hashlib.sha256(np.ascontiguousarray(rgb).tobytes()).hexdigest()
                outputs.setdefault(h, rgb)
                hashes.append(h)
            count = collections.Counter(hashes)
            top, same = count.most_common(1)[0]
            failures += same != a.repeat
            print(f"{dev} ({version(dev).split(', ')[-1]}): {key[0]} {key[1]:g} K developed {a.repeat} times, each "
                  f"with a fresh config: {same}/{a.repeat} identical outputs ({len(count)} distinct; "
                  f"{(time.perf_counter() - t0) / a.repeat:.2f} s a run)")
            for h, rgb in outputs.items():
                if h == top:
                    continue
                diff = np.any(rgb != outputs[top], axis=-1)
                ys, xs = np.nonzero(diff)
                near = sum(white[0].start - 4 <= y < white[0].stop + 4 and white[1].start - 4 <= x < white[1].stop + 4
                           for y, x in zip(ys, xs))
                print(f"  {count[h]} run(s) differ from the majority in {diff.sum()} pixel(s), {near} of them in or "
                      f"within 4 px of the white patch; largest difference {np.abs(rgb - outputs[top]).max():.4f} "
                      "(of 1)")
    print(f"\n{'all checks passed' if not failures else f'{failures} check(s) failed'}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
