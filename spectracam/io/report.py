"""Scoring outputs: rendered EXR (linear display RGB), an sRGB PNG preview, a ΔE map, JSON and CSV."""
from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from .. import __version__
from ..color import display_rgb_to_xyz
from ..score import ChartScore
from .exr import write_exr
from .files import atomic_write
from .plots import save_figure


def srgb_preview(rendered_rgb: np.ndarray, display: str) -> np.ndarray:
    """8-bit sRGB of linear display RGB: display RGB → XYZ → sRGB, clipped, sRGB-encoded."""
    import colour

    xyz = rendered_rgb @ display_rgb_to_xyz(display).T
    lin = xyz @ np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB).T
    return (np.clip(colour.cctf_encoding(np.clip(lin, 0, 1), "sRGB"), 0, 1) * 255 + 0.5).astype(np.uint8)


def write_png(path: Path, rgb8: np.ndarray) -> Path:
    """An 8-bit image as PNG."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    plt.imsave(buf, rgb8, format="png")
    return atomic_write(path, buf.getvalue())


def delta_e_figure(delta_e_map: np.ndarray, title: str):
    from .plots import pyplot

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 5))
    vmax = max(10.0, float(np.nanpercentile(delta_e_map, 99)))
    im = ax.imshow(delta_e_map, cmap="magma", vmin=0, vmax=vmax, interpolation="nearest")
    ax.set_axis_off()
    ax.set_title(title, fontsize=9)
    fig.colorbar(im, ax=ax, label="ΔE*ab per pixel (patch masks only)")
    return fig


def _num(x) -> str:
    return "inf" if x is None else f"{x:.3f}"


def write_rendered_exr(path: str | Path, result: ChartScore) -> Path:
    """The displayed image (linear display RGB) with every parameter of the score that made it."""
    params = result.parameters
    attrs = {"spectracamVersion": __version__, "spectracamKind": "rendered",
             "spectracamUnits": f"linear RGB of the display ({params['processing']['display']}), white = 1",
             "spectracamParameters": json.dumps(params, sort_keys=True), "spectracamSeed": int(params["seed"])}
    rgb = result.rendered_rgb
    return write_exr(path, {"R": rgb[..., 0], "G": rgb[..., 1], "B": rgb[..., 2]}, attrs)


def report_csv(result: ChartScore) -> bytes:
    """One row per patch and a chart-average row."""
    buf = io.StringIO()
    wr = csv.writer(buf)
    wr.writerow(["patch", "name", "scene_L", "scene_a", "scene_b", "rendered_L", "rendered_a", "rendered_b",
                 "delta_e_mean", "delta_e_of_mean", "delta_e_conversion", "snr_R_db", "snr_G_db", "snr_B_db",
                 "snr_combined_db"])
    for p in result.patches:
        wr.writerow([p.patch, p.name, *p.scene_lab, *p.rendered_lab, f"{p.delta_e_mean:.4f}",
                     f"{p.delta_e_of_mean:.4f}", f"{p.delta_e_conversion:.4f}",
                     *(_num(getattr(p, f"snr_{k}_db")) for k in "RGB"), _num(p.snr_combined_db)])
    c = result.summary
    wr.writerow(["chart", "average", "", "", "", "", "", "", f"{c.delta_e_mean:.4f}", f"{c.delta_e_of_mean:.4f}",
                 f"{c.delta_e_conversion:.4f}", *(_num(getattr(c, f"snr_{k}_db")) for k in "RGB"),
                 _num(c.snr_combined_db)])
    return buf.getvalue().encode()


def write_score_outputs(out_dir: str | Path, result: ChartScore) -> list[Path]:
    """rendered.exr, rendered.png, delta_e.png, report.json and report.csv in ``out_dir``."""
    out = Path(out_dir)
    params = result.parameters
    display = params["processing"]["display"]
    paths = [write_rendered_exr(out / "rendered.exr", result),
             write_png(out / "rendered.png", srgb_preview(result.rendered_rgb, display))]
    c = result.summary
    snr = "∞" if c.snr_combined_db is None else f"{c.snr_combined_db:.1f}"
    name = (params.get("scene") or {}).get("name", "")
    title = f"{params['camera']['capture']['architecture']}/{params['camera']['capture']['exposure']}, {name}: " \
            f"mean ΔE*ab {c.delta_e_mean:.2f}, SNR {snr} dB"
    paths.append(save_figure(delta_e_figure(result.delta_e_map, title), out / "delta_e.png"))
    paths.append(atomic_write(out / "report.json", json.dumps(result.to_dict(), indent=1, allow_nan=False).encode()))
    paths.append(atomic_write(out / "report.csv", report_csv(result)))
    return paths
