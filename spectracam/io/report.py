"""Scoring outputs: rendered EXR (linear display RGB), an sRGB PNG preview, a ΔE map, JSON and CSV."""
from __future__ import annotations

import csv
import io
import json
import os
import tempfile
from pathlib import Path

import numpy as np

from .. import __version__
from .exr import write_exr


def _atomic_bytes(path: Path, data: bytes) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=path.suffix, dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return path


def srgb_preview(rendered_rgb: np.ndarray, display: str) -> np.ndarray:
    """8-bit sRGB of linear display RGB: display RGB → XYZ → sRGB, clipped, sRGB-encoded."""
    import colour

    from ..color import display_rgb_to_xyz

    xyz = rendered_rgb @ display_rgb_to_xyz(display).T
    lin = xyz @ np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB).T
    return (np.clip(colour.cctf_encoding(np.clip(lin, 0, 1), "sRGB"), 0, 1) * 255 + 0.5).astype(np.uint8)


def _png(path: Path, figure_or_rgb) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    if isinstance(figure_or_rgb, np.ndarray):
        plt.imsave(buf, figure_or_rgb, format="png")
    else:
        figure_or_rgb.savefig(buf, format="png", dpi=120, bbox_inches="tight")
        plt.close(figure_or_rgb)
    return _atomic_bytes(path, buf.getvalue())


def delta_e_figure(delta_e_map: np.ndarray, title: str):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5))
    vmax = max(10.0, float(np.nanpercentile(delta_e_map, 99)))
    im = ax.imshow(delta_e_map, cmap="magma", vmin=0, vmax=vmax, interpolation="nearest")
    ax.set_axis_off()
    ax.set_title(title, fontsize=9)
    fig.colorbar(im, ax=ax, label="ΔE*ab per pixel (patch masks only)")
    return fig


def _num(x) -> str:
    return "inf" if x is None else f"{x:.3f}"


def write_rendered_exr(path: str | Path, result) -> Path:
    """The displayed image (linear display RGB) with every parameter of the score that made it."""
    params = result.report["parameters"]
    attrs = {"spectracamVersion": __version__, "spectracamKind": "rendered",
             "spectracamUnits": f"linear RGB of the display ({params['processing']['display']}), white = 1",
             "spectracamParameters": json.dumps(params, sort_keys=True), "spectracamSeed": int(params["seed"])}
    rgb = result.rendered_rgb
    return write_exr(path, {"R": rgb[..., 0], "G": rgb[..., 1], "B": rgb[..., 2]}, attrs)


def write_score_outputs(out_dir: str | Path, result, processing) -> list[Path]:
    out = Path(out_dir)
    rep = result.report
    params = rep["parameters"]
    paths = [write_rendered_exr(out / "rendered.exr", result),
             _png(out / "rendered.png", srgb_preview(result.rendered_rgb, processing.display))]
    chart = rep["chart"]
    cam = params["camera"]
    snr = "∞" if chart["snr_combined_db"] is None else f"{chart['snr_combined_db']:.1f}"
    title = (f"{cam['architecture']}/{cam['exposure']}, {params['scene']['name']}: mean ΔE*ab {chart['delta_e_mean']:.2f}, "
             f"SNR {snr} dB")
    paths.append(_png(out / "delta_e.png", delta_e_figure(result.delta_e_map, title)))
    paths.append(_atomic_bytes(out / "report.json", json.dumps(rep, indent=1).encode()))
    buf = io.StringIO()
    wr = csv.writer(buf)
    wr.writerow(["patch", "name", "scene_L", "scene_a", "scene_b", "rendered_L", "rendered_a", "rendered_b",
                 "delta_e_mean", "delta_e_of_mean", "delta_e_conversion", "snr_R_db", "snr_G_db", "snr_B_db",
                 "snr_combined_db"])
    for r in rep["patches"]:
        wr.writerow([r["patch"], r["name"], *r["scene_lab"], *r["rendered_lab"], f"{r['delta_e_mean']:.4f}",
                     f"{r['delta_e_of_mean']:.4f}", f"{r['delta_e_conversion']:.4f}",
                     *(_num(r["snr_db"][k]) for k in "RGB"), _num(r["snr_combined_db"])])
    wr.writerow(["chart", "average", "", "", "", "", "", "", f"{chart['delta_e_mean']:.4f}",
                 f"{chart['delta_e_of_mean']:.4f}", f"{chart['delta_e_conversion']:.4f}",
                 *(_num(chart["snr_db"][k]) for k in "RGB"), _num(chart["snr_combined_db"])])
    paths.append(_atomic_bytes(out / "report.csv", buf.getvalue().encode()))
    return paths
