"""``DIR/index.html``: one self-contained page (Bokeh's scripts inlined, every figure embedded; it works
from ``file://`` offline) showing what an output directory holds (:mod:`.contents`):

* each case (:mod:`.cases`) as four linked images — scene preview, raw digital numbers, rendered
  image, ΔE*ab map — sharing zoom and pan; moving over or clicking a pixel shows its radiance
  spectrum beside the camera's responsivities R_k(λ) (filter × QE × IR cut) and its digital numbers
  and scene and rendered L*a*b* (``window.spectracam.probe`` in :file:`page.js`);
* the patch table of report.json, the reports (report.md as HTML, results tables), every figure and
  per-case image, and the parameters that made them.
"""
from __future__ import annotations

import base64
import html
import json
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from spectracam._version import __version__
from spectracam.core.errors import SpectracamError
from spectracam.io.report import DELTA_E_VMAX  # the ΔE*ab colour scale of the scores' delta_e.png
from spectracam.view.cases import CHANNEL_COLOURS, Case, load_case
from spectracam.view.contents import Contents, find_contents

if TYPE_CHECKING:
    from collections.abc import Callable

    from bokeh.models import Column

__all__ = ["BOKEH_COMPONENTS", "BOTH_WAYS_ROWS", "EMBED_BYTES", "IMAGE_ROLES", "JSON_CHARS", "PROFILE_MODES",
           "TABLE_ROWS", "both_ways_table", "build_page", "case_json", "curve_colours", "exact_dtype", "interactive",
           "markdown_html", "packed", "patch_table", "table_html", "write_page"]

#: Figure bytes a page embeds at most; later figures are linked (relative, so they open beside it).
EMBED_BYTES = 40_000_000
#: The parts of BokehJS a page inlines.
BOKEH_COMPONENTS = ("bokeh", "bokeh-widgets")
#: Rows of a table shown (the rest counted).
TABLE_ROWS = 200
#: Characters of a JSON file shown.
JSON_CHARS = 200_000
IMAGE_ROLES = (("scene", "scene (sRGB preview of the radiance)"), ("raw", "raw digital numbers (channel colours)"),
               ("rendered", "rendered (display → sRGB)"), ("error", "ΔE*ab, rendered against the scene"))

_CSS = """
body{font-family:system-ui,sans-serif;margin:1.2em;max-width:1500px;color:#222}
h1{font-size:1.4em} h2{font-size:1.15em;border-bottom:1px solid #ccc;margin-top:1.6em}
table{border-collapse:collapse;font-size:0.85em} td,th{border:1px solid #ddd;padding:2px 6px;text-align:right}
th{background:#f4f4f4} td.name{text-align:left} .sw{width:1.4em;height:1em;display:inline-block;border:1px solid #888}
figure{display:inline-block;margin:0.4em;vertical-align:top;max-width:48%} figure img{max-width:100%;border:1px solid #ddd}
figcaption{font-size:0.8em;color:#555;word-break:break-all} pre{background:#f8f8f8;padding:0.6em;overflow:auto;max-height:30em}
.note{color:#555;font-size:0.9em} table.probe th{text-align:left}
.missing{background:#fff4d6;border-left:4px solid #E69F00;padding:0.4em 0.8em}
"""


def exact_dtype(a: np.ndarray) -> str:
    """The smallest little-endian type holding every value of ``a`` exactly: ``u1`` or ``u2`` for whole numbers
    from 0 to 255 or 65535 (digital numbers of an ADC up to 16 bits, 8-bit pictures), else ``f4`` (float32).

    Parameters
    ----------
    a : ndarray
        The values.

    Returns
    -------
    str
        ``"u1"``, ``"u2"`` or ``"f4"``.
    """
    if a.dtype.kind in "ui" or (a.size and np.isfinite(a).all() and np.array_equal(a, np.round(a))):
        top = float(a.max()) if a.size else 0.0
        low = float(a.min()) if a.size else 0.0
        if low >= 0 and top <= 255:
            return "u1"
        if low >= 0 and top <= 65535:
            return "u2"
    return "f4"


def packed(a: np.ndarray | None, dtype: str | None = None) -> dict | None:
    """``a`` losslessly compressed for the page: ``{"dtype", "shape", "shuffle", "data"}``, ``data`` the base64 of
    zlib's deflate of the array's bytes (little-endian ``dtype``, :func:`exact_dtype` when not given), or — where it
    compresses better, as smooth float32 data does — of its bytes regrouped by byte position (``shuffle``: every
    value's first byte, then every second byte …, as HDF5's shuffle filter).  page.js inflates it with the
    browser's own ``DecompressionStream`` and gets the very same values back (no lossy step anywhere).

    Parameters
    ----------
    a : ndarray or None
        The values (any shape).
    dtype : str or None
        Their type on the page (``"u1"``, ``"u2"``, ``"f4"`` …); None: :func:`exact_dtype`.

    Returns
    -------
    dict or None
        ``{"dtype", "shape", "shuffle", "data"}``; None for None.
    """
    import zlib

    if a is None:
        return None
    dtype = dtype or exact_dtype(np.asarray(a))
    v = np.ascontiguousarray(np.asarray(a).astype("<" + dtype))
    plain = zlib.compress(v.tobytes(), 9)
    shuffled = plain
    if v.itemsize > 1:
        shuffled = zlib.compress(np.ascontiguousarray(v.view(np.uint8).reshape(-1, v.itemsize).T).tobytes(), 9)
    shuffle = len(shuffled) < len(plain)
    return {"dtype": dtype, "shape": list(v.shape), "shuffle": bool(shuffle),
            "data": base64.b64encode(shuffled if shuffle else plain).decode()}


def _hex(rgb) -> str:
    return "#%02x%02x%02x" % tuple(int(round(255 * v)) for v in rgb)


def curve_colours(case: Case) -> dict:
    """The colour of each responsivity curve: its channel's, black for QE × IR cut.

    Parameters
    ----------
    case : Case
        The case (its channels).

    Returns
    -------
    dict
        Channel name (and ``"QE × IR cut"``) → ``"#rrggbb"`` (:data:`~spectracam.view.cases.CHANNEL_COLOURS`).
    """
    return {**{c: _hex(CHANNEL_COLOURS.get(c, (0.45, 0.45, 0.45))) for c in case.channels}, "QE × IR cut": "#000000"}


def _rgb_bytes(image: np.ndarray | None) -> np.ndarray | None:
    """``(h, w)`` uint32 RGBA (opaque) → ``(h, w, 3)`` uint8: the alpha byte is always 255, not carried."""
    return None if image is None else np.ascontiguousarray(image).view(np.uint8).reshape(image.shape + (4,))[..., :3]


def case_json(case: Case) -> dict:
    """The per-pixel data the probe, the profiles and the regions read (see page.js), each array :func:`packed`.

    Carried once each: a mosaic's digital numbers as one plane (``dn``) with the channel of each pixel
    (``dn_channel``), not ``N`` planes mostly NaN; the rendering as rendered.exr's linear display RGB
    (``rendered_rgb``), whose L*a*b* (``display_to_xyz``, white = the display's) and ΔE*ab against ``scene_lab``
    page.js computes; the three pictures as 8-bit RGB.

    Parameters
    ----------
    case : Case
        The case.

    Returns
    -------
    dict
        JSON-ready: its name, size, stride, bands, channels, colours, responsivities, notes, patches and packed arrays.
    """
    rows, cols = case.images[next(iter(case.images))].shape[:2] if case.images else (0, 0)
    mosaic = case.dn is not None and case.dn_channel is not None
    dn = (np.take_along_axis(case.dn, case.dn_channel[..., None].astype(np.intp), axis=-1)[..., 0] if mosaic
          else case.dn)
    return {"name": case.name, "design": case.design, "width": case.width, "height": case.height,
            "stride": case.stride, "rows": int(rows), "cols": int(cols),
            "bands": 0 if case.spectra is None else int(case.spectra.shape[-1]),
            "wavelengths_nm": [float(w) for w in case.wavelengths_nm], "channels": list(case.channels),
            "colours": curve_colours(case), "responsivities": case.responsivities, "notes": case.notes,
            "patches": case.patches, "display_to_xyz": case.display_to_xyz,
            "arrays": {"spectra": packed(case.spectra, "f4"), "dn": packed(dn),
                       "dn_channel": packed(case.dn_channel, "u1") if mosaic else None,
                       "scene_lab": packed(case.scene_lab, "f4"), "rendered_rgb": packed(case.rendered_rgb, "f4"),
                       **{f"image_{role}": packed(_rgb_bytes(case.images.get(role)), "u1")
                          for role in ("scene", "raw", "rendered")}}}


def _image_data(role: str) -> dict:
    """A placeholder image of one role (page.js fills it with the selected case's picture, bottom row first)."""
    img = np.full((1, 1), np.nan, np.float32) if role == "error" else np.zeros((1, 1), np.uint32)
    return {"image": [img], "x": [0], "y": [0], "dw": [1], "dh": [1]}


def interactive(cases: list[Case]) -> Column:
    """The Bokeh layout: case selector, linked images, spectrum and probe read-out, line profile and region.

    Parameters
    ----------
    cases : list of Case
        The cases, at least one (the first shown; a selector where there are several).

    Returns
    -------
    bokeh.models.Column
        The layout, for ``bokeh.embed.components``.
    """
    from bokeh.layouts import column, gridplot, row
    from bokeh.models import Button, CustomJS, Div, RadioButtonGroup

    figures = _image_figures(cases)
    spectrum = _spectrum_figure(cases[0])
    info = Div(text="<i>move over or click an image to probe a pixel</i>", name="probe_info", width=480)
    follow = Button(label="follow the pointer again", width=200)
    follow.js_on_click(CustomJS(code="window.spectracam.pinned = false;"))
    title = Div(text="", name="case_title", width=1200)
    mode = RadioButtonGroup(labels=list(PROFILE_MODES), active=0, name="profile_mode", width=330)
    profile_info = Div(text="<i>click an image: the profile along its row (or column, or a line between two "
                            "clicks)</i>", name="profile_info", width=480)
    region_info = Div(text="<i>drag a box with the box-select tool (dashed square) for a region's mean and σ</i>",
                      name="region_info", width=480)
    parts = [_case_select(cases)] if len(cases) > 1 else []
    parts += [title, gridplot(figures, ncols=2, toolbar_location="right"),
              row(spectrum, column(info, follow)), row(_profile_figure(), column(mode, profile_info, region_info))]
    return column(*parts)


#: What a click on an image draws the line profile along (:data:`PROFILE_MODES` order is the buttons').
PROFILE_MODES = ("row", "column", "line (two clicks)")


def _image_figures(cases: list[Case]) -> list:
    """One figure per image role any case has, sharing zoom and pan, each probing the pixel under the pointer;
    a click also draws a line profile, the box-select tool a region (page.js)."""
    from bokeh.models import ColumnDataSource, CustomJS, Range1d

    first = cases[0]
    x_range, y_range = Range1d(0, first.width, name="image_x"), Range1d(0, first.height, name="image_y")
    mark = ColumnDataSource({"x": [], "y": []}, name="probe_mark")
    line = ColumnDataSource({"x": [], "y": []}, name="profile_mark")
    box = ColumnDataSource({"left": [], "right": [], "bottom": [], "top": []}, name="region_mark")
    size = 420
    h = int(size * first.height / max(first.width, 1))
    on_move = CustomJS(code="if (!window.spectracam.pinned) window.spectracam.probe(cb_obj.x, cb_obj.y);")
    figures = []
    for role, title in IMAGE_ROLES:
        if not any(role in c.images for c in cases):
            continue
        f = _image_figure(first, role, title, x_range, y_range, size, h)
        f.scatter("x", "y", source=mark, size=14, marker="circle_cross", fill_alpha=0, line_color="#00e5ff",
                  line_width=2)
        f.line("x", "y", source=line, line_color="#00e5ff", line_width=2, line_dash="dotted")
        f.quad(left="left", right="right", bottom="bottom", top="top", source=box, fill_alpha=0,
               line_color="#ffd400", line_width=2)
        f.js_on_event("mousemove", on_move)
        f.js_on_event("tap", CustomJS(code=f"window.spectracam.pinned = true; window.spectracam.probe(cb_obj.x, "
                                           f"cb_obj.y); window.spectracam.tapped('{role}', cb_obj.x, cb_obj.y);"))
        f.js_on_event("selectiongeometry", CustomJS(code=(
            f"const g = cb_obj.geometry; if (g.type === 'rect' && cb_obj.final) "
            f"window.spectracam.region('{role}', g.x0, g.y0, g.x1, g.y1);")))
        f.axis.visible = False
        f.grid.visible = False
        figures.append(f)
    return figures


def _image_figure(case: Case, role: str, title: str, x_range, y_range, size: int, h: int):
    """The figure of one image role of ``case``: RGBA, or the ΔE*ab map on the scores' colour scale."""
    from bokeh.models import ColorBar, ColumnDataSource, LinearColorMapper
    from bokeh.palettes import Inferno256
    from bokeh.plotting import figure

    f = figure(title=title, x_range=x_range, y_range=y_range, width=size, height=h + 40, match_aspect=True,
               tools="pan,wheel_zoom,box_zoom,box_select,reset,tap,save", active_scroll="wheel_zoom",
               name=f"figure_{role}")
    src = ColumnDataSource(_image_data(role), name=f"image_{role}")
    if role == "error":
        mapper = LinearColorMapper(palette=Inferno256, low=0.0, high=DELTA_E_VMAX, nan_color="#bbbbbb")
        f.image(image="image", x="x", y="y", dw="dw", dh="dh", source=src, color_mapper=mapper)
        f.add_layout(ColorBar(color_mapper=mapper, title="ΔE*ab", width=8), "right")
    else:
        f.image_rgba(image="image", x="x", y="y", dw="dw", dh="dh", source=src)
    return f


def _spectrum_figure(case: Case):
    """The probed pixel's radiance spectrum (filled by page.js) beside the camera's responsivities R_k(λ)."""
    from bokeh.models import ColumnDataSource, LinearAxis, Range1d
    from bokeh.plotting import figure

    wl = [float(w) for w in case.wavelengths_nm]
    lo, hi = (min(wl), max(wl)) if wl else (380.0, 780.0)
    spectrum = figure(title="radiance at the probe, and the camera's responsivities", width=780, height=330,
                      x_axis_label="wavelength (nm)", y_axis_label="radiance (W·m⁻²·sr⁻¹·nm⁻¹)",
                      x_range=Range1d(lo - 5, hi + 5), y_range=Range1d(0, 1, name="spectrum_y"),
                      name="figure_spectrum", tools="pan,wheel_zoom,box_zoom,reset,save")
    spectrum.line("wavelength_nm", "radiance", source=ColumnDataSource({"wavelength_nm": [], "radiance": []},
                                                                       name="probe_spectrum"),
                  line_width=2.5, color="#222222", legend_label="radiance L(λ)")
    spectrum.extra_y_ranges = {"resp": Range1d(0, 1.05 * max([max(v) for v in case.responsivities.values()] + [1e-3]))}
    spectrum.add_layout(LinearAxis(y_range_name="resp", axis_label="R_k(λ) = filter × QE × IR cut (e⁻/photon)"),
                        "right")
    names = list(case.responsivities)
    colour_of = curve_colours(case)
    resp = ColumnDataSource({"xs": [wl] * len(names), "ys": [case.responsivities[n] for n in names],
                             "color": [colour_of.get(n, "#444444") for n in names], "label": names},
                            name="responsivities")
    spectrum.multi_line("xs", "ys", color="color", legend_field="label", source=resp, y_range_name="resp",
                        line_dash="dashed", line_width=1.5)
    # outside the plot, right of the responsivity axis: inside, it covered 400–490 nm, where a blue patch peaks
    spectrum.add_layout(spectrum.legend[0], "right")
    return spectrum


def _case_select(cases: list[Case]):
    """The case selector (page.js fills the images from the selected case's data)."""
    from bokeh.models import CustomJS, Select

    select = Select(title="case", value="0", options=[(str(i), c.name) for i, c in enumerate(cases)], width=600,
                    name="case_select")
    select.js_on_change("value", CustomJS(code="window.spectracam.select(parseInt(cb_obj.value));"))
    return select


def _profile_figure():
    """The line profile (filled by page.js): each channel of the clicked panel along the line, against the distance
    from its start in the files' pixels."""
    from bokeh.models import ColumnDataSource, Range1d
    from bokeh.plotting import figure

    f = figure(title="line profile (click an image)", width=780, height=300, name="figure_profile",
               x_axis_label="distance along the line (pixels of the files)", y_axis_label="value",
               x_range=Range1d(0, 1, name="profile_x"), y_range=Range1d(0, 1, name="profile_y"),
               tools="pan,wheel_zoom,box_zoom,reset,save")
    lines = ColumnDataSource({"xs": [], "ys": [], "color": [], "label": []}, name="profile_lines")
    f.multi_line("xs", "ys", color="color", legend_field="label", source=lines, line_width=1.5)
    points = ColumnDataSource({"x": [], "y": [], "color": []}, name="profile_points")
    f.scatter("x", "y", color="color", source=points, size=4)
    f.add_layout(f.legend[0], "right")
    return f


def _swatch(lab) -> str:
    import colour

    rgb = colour.XYZ_to_sRGB(colour.Lab_to_XYZ(np.asarray(lab, float), illuminant=colour.CCS_ILLUMINANTS[
        "CIE 1931 2 Degree Standard Observer"]["D65"]))
    return f'<span class="sw" style="background:{_hex(np.clip(rgb, 0, 1))}"></span>'


def patch_table(report: dict) -> str:
    """report.json's patches: scene and rendered L*a*b*, ΔE*ab (per pixel, of the mean, of the
    conversion alone) and the combined SNR.

    Parameters
    ----------
    report : dict
        A ``score`` report.json.

    Returns
    -------
    str
        An HTML table; empty where it has no patches.
    """
    rows = []
    for p in report.get("patches", []):
        s, r = p.get("scene_lab"), p.get("rendered_lab")
        snr = p.get("snr_combined_db")
        rows.append(f"<tr><td>{p.get('patch')}</td><td class=name>{_swatch(s)} {_swatch(r)} "
                    f"{html.escape(str(p.get('name')))}</td><td>{s[0]:.2f}, {s[1]:.2f}, {s[2]:.2f}</td>"
                    f"<td>{r[0]:.2f}, {r[1]:.2f}, {r[2]:.2f}</td><td>{p['delta_e_mean']:.2f}</td>"
                    f"<td>{p['delta_e_of_mean']:.2f}</td><td>{p['delta_e_conversion']:.2f}</td>"
                    f"<td>{'∞' if snr is None else f'{snr:.1f}'}</td></tr>")
    if not rows:
        return ""
    return ("<table><tr><th>patch</th><th>name (scene | rendered)</th><th>scene L*, a*, b*</th>"
            "<th>rendered L*, a*, b*</th><th>ΔE*ab per pixel</th><th>ΔE*ab of the mean</th>"
            "<th>ΔE*ab of the conversion</th><th>SNR (dB)</th></tr>" + "".join(rows) + "</table>")


#: The rows of the oracle / developed table (report.json's ``both_ways``; docs/metrics.md).
BOTH_WAYS_ROWS = (("delta_e_mean", "mean ΔE*ab per pixel", 2), ("delta_e_p95", "95th percentile ΔE*ab", 2),
                  ("s_cielab_mean", "mean S-CIELAB (the eye's filters)", 2),
                  ("delta_e2000_mean", "mean CIEDE2000", 2), ("held_out_delta_e", "held-out ΔE*ab (noise-free)", 2),
                  ("awb_recovery_deg", "white's recovery error (°)", 2),
                  ("awb_reproduction_deg", "white's reproduction error (°)", 2),
                  ("metered_exposure_ms", "metered capture time (ms)", 2))


def both_ways_table(report: dict) -> str:
    """report.json's ``both_ways``: the camera told the light (oracle) beside the one that finds its own white.

    Parameters
    ----------
    report : dict
        A ``score`` report.json.

    Returns
    -------
    str
        An HTML table and the metering note; empty where it has no ``both_ways`` block.
    """
    bw = report.get("both_ways")
    if not isinstance(bw, dict) or not isinstance(bw.get("oracle"), dict) or not isinstance(bw.get("developed"), dict):
        return ""

    def cell(v, digits):
        return "–" if not isinstance(v, (int, float)) else f"{v:.{digits}f}"

    rows = "".join(f"<tr><td>{label}</td><td>{cell(bw['oracle'].get(k), d)}</td>"
                   f"<td>{cell(bw['developed'].get(k), d)}</td></tr>" for k, label, d in BOTH_WAYS_ROWS)
    return ("<table><tr><th></th><th>oracle (told the light)</th><th>developed (finds its own white)</th></tr>"
            + rows + f"</table><p class=note>metering: {html.escape(str(bw.get('metering', '')))}</p>")


def _data_uri(path: Path) -> str:
    mime = {".png": "image/png", ".gif": "image/gif", ".svg": "image/svg+xml"}.get(path.suffix.lower(), "image/png")
    return f"data:{mime};base64," + base64.b64encode(path.read_bytes()).decode()


def markdown_html(path: Path, embedded: set | None = None) -> str:
    """report.md as HTML, its local images embedded (each one's resolved path added to ``embedded``, where given:
    the figures section does not carry them a second time).

    Parameters
    ----------
    path : Path
        A Markdown file.
    embedded : set or None
        Where the resolved paths of the images it embeds are added; None: not recorded.

    Returns
    -------
    str
        HTML; images outside the file's directory are left as links.
    """
    import re

    import markdown

    body = markdown.markdown(path.read_text(errors="replace"), extensions=["tables", "fenced_code"])

    def inline(m):
        target = (path.parent / html.unescape(m.group(2))).resolve()
        ok = target.is_file() and path.parent.resolve() in target.parents
        if ok and embedded is not None:
            embedded.add(target)
        return f'{m.group(1)}{_data_uri(target) if ok else m.group(2)}"'

    return re.sub(r'(<img[^>]*src=")([^":]+)"', inline, body)


def table_html(path: Path) -> str:
    """A CSV or Parquet table as HTML: its first :data:`TABLE_ROWS` rows, four significant digits.

    Parameters
    ----------
    path : Path
        ``.parquet`` or ``.csv`` (one header row).

    Returns
    -------
    str
        The HTML table, and a note where rows were left out.
    """
    import pandas as pd

    frame = pd.read_parquet(path) if path.suffix == ".parquet" else pd.read_csv(path)
    more = "" if len(frame) <= TABLE_ROWS else f"<p class=note>first {TABLE_ROWS} of {len(frame)} rows</p>"
    return frame.head(TABLE_ROWS).to_html(index=False, float_format=lambda v: f"{v:.4g}", border=0) + more


def _figures_html(c: Contents, shown: set = frozenset()) -> str:
    """Every figure, embedded up to :data:`EMBED_BYTES` (later ones linked) — but those a report.md above shows
    already (``shown``, resolved paths), named only: a page carried each of them twice (issue 39: pages under 10 MB)."""
    parts, embedded, folder, linked = [], 0, None, False
    again = [p for p in c.figures if p.resolve() in shown]
    if again:
        parts.append("<p class=note>shown in the report above: " + ", ".join(
            html.escape(str(p.relative_to(c.directory))) for p in again) + "</p>")
    for p in (p for p in c.figures if p.resolve() not in shown):
        rel = p.relative_to(c.directory)
        if rel.parent != folder:
            folder = rel.parent
            parts.append(f"<h3>{html.escape(str(folder)) if str(folder) != '.' else 'figures'}</h3>")
        size = p.stat().st_size
        if embedded + size <= EMBED_BYTES:
            embedded += size
            src = _data_uri(p)
        else:
            src, linked = html.escape(str(rel)), True
        parts.append(f'<figure><img loading="lazy" src="{src}" alt="{html.escape(str(rel))}">'
                     f"<figcaption>{html.escape(str(rel))}</figcaption></figure>")
    if linked:
        parts.insert(0, f"<p class=note>figures past {EMBED_BYTES // 1_000_000} MB are linked beside the page, "
                        "not embedded</p>")
    if c.more_figures:
        parts.append(f"<p class=note>{len(c.more_figures)} more figures are not shown: "
                     + ", ".join(html.escape(str(p.relative_to(c.directory))) for p in c.more_figures[:20]) + "…</p>")
    return "".join(parts)


def _missing_spectra(cases: list[Case]) -> list[str]:
    """The note at the top of a page whose cases carry no radiance.exr (issue 39: said first, not only in each
    case's notes far below)."""
    bare = [case for case in cases if any(n.startswith("no radiance.exr") for n in case.notes)]
    if not bare:
        return []
    return [f"<p class=missing><b>No spectrum in the probe for {len(bare)} of {len(cases)} cases:</b> they carry no "
            "radiance.exr (a paper run writes it with <code>--save-cubes</code>; architectures and design write their captures "
            "only), so their scene colours are the chart "
            "reference's patch colours, inside the patches only.</p>"]


def build_page(c: Contents, cases: list[Case]) -> str:
    """The whole page as one HTML string.

    Parameters
    ----------
    c : Contents
        What the directory holds (:func:`~spectracam.view.contents.find_contents`).
    cases : list of Case
        Its cases, loaded (:func:`~spectracam.view.cases.load_case`).

    Returns
    -------
    str
        A self-contained HTML page: Bokeh and page.js inlined, every case's data and figure embedded.
    """
    from bokeh.embed import components
    from bokeh.resources import Resources

    title = f"spectracam {c.kind}: {c.directory.name}"
    body = [f"<h1>{html.escape(title)}</h1>",
            f"<p class=note>written by spectracam {__version__} from {html.escape(str(c.directory))}; "
            "see docs/metrics.md for every score's definition</p>"]
    script, shown = "", set()
    body += _missing_spectra(cases)
    if cases:
        script, div = components(interactive(cases))
        body += ["<h2>images and pixel probe</h2>",
                 "<p class=note>the four images share zoom and pan (wheel, drag, box); moving over an image probes "
                 "the pixel under the pointer, a click pins it. Scene L*a*b*: CIE 1931, white = a perfect diffuser "
                 "under the scene's light; rendered L*a*b*: the display's colours, white = the display's white; "
                 "ΔE*ab = CIE 1976 distance of the two.</p>", div]
        if c.more_cases:
            body.append(f"<p class=note>{len(c.more_cases)} more cases are not loaded into the probe (their "
                        "figures are below): " + ", ".join(map(html.escape, c.more_cases[:20])) + "…</p>")
    body += _report_tables(c)
    for p in c.markdown:
        body += [f"<h2>{html.escape(str(p.relative_to(c.directory)))}</h2>", markdown_html(p, shown)]
    for p in c.tables:
        try:
            body += [f"<h2>{html.escape(str(p.relative_to(c.directory)))}</h2>", table_html(p)]
        except Exception as e:  # noqa: BLE001 - a damaged table is named on the page, not fatal
            body.append(f"<p class=note>{html.escape(str(p.name))}: not readable ({html.escape(str(e))[:200]})</p>")
    if c.figures:
        body += ["<h2>figures and per-case images</h2>", _figures_html(c, shown)]
    for p in c.json_files:
        text = p.read_text(errors="replace")
        more = "" if len(text) <= JSON_CHARS else f"\n… ({len(text) - JSON_CHARS} more characters in the file)"
        body.append(f"<details><summary>{html.escape(str(p.relative_to(c.directory)))}</summary>"
                    f"<pre>{html.escape(text[:JSON_CHARS] + more)}</pre></details>")
    data = "".join(f'<script type="application/json" id="case-{i}">{json.dumps(case_json(k))}</script>'
                   for i, k in enumerate(cases))
    js = (Path(__file__).with_name("page.js")).read_text()
    start = "<script>window.addEventListener('load', function () { window.spectracam.start(); });</script>" \
        if cases else ""
    # Bokeh's own scripts, inlined: the core and the widgets (the case selector, buttons); not MathJax, GL or the
    # tables (2.3 MB the page does not use)
    resources = Resources(mode="inline", components=list(BOKEH_COMPONENTS)).render()
    return (f"<!DOCTYPE html><html lang=en><head><meta charset=utf-8><title>{html.escape(title)}</title>"
            f"<style>{_CSS}</style>{resources}<script>{js}</script>{data}{start}</head>"
            f"<body>{''.join(body)}{script}</body></html>")


def _report_tables(c: Contents) -> list[str]:
    """Headings and tables (the two cameras, the patches) of each report.json; a report that is not one shows none."""
    body = []
    for p in c.json_files:
        if p.name == "report.json":
            try:
                report = json.loads(p.read_text())
                if not isinstance(report, dict):   # a case's report.json that is not one: its text is still shown
                    raise TypeError("not a JSON object")
                both = both_ways_table(report)
                table = patch_table(report)
            except (ValueError, KeyError, TypeError, IndexError, AttributeError):
                both = table = ""
            if both:
                body += [f"<h2>two cameras ({html.escape(str(p.relative_to(c.directory)))})</h2>", both]
            if table:
                body += [f"<h2>patches ({html.escape(str(p.relative_to(c.directory)))})</h2>", table]
    return body


def write_page(directory: Path, log: Callable[[str], object] | None = None) -> Path:
    """Find what ``directory`` holds, build the page and write ``directory/index.html`` (atomically).

    Parameters
    ----------
    directory : Path
        An output directory a spectracam command wrote.
    log : callable or None
        Given one line (the page's path, size, cases and figures) once it is written; None: silent.

    Returns
    -------
    Path
        ``directory/index.html``.

    Raises
    ------
    SpectracamError
        What :func:`~spectracam.view.contents.find_contents` refuses, or a case whose files cannot be read (named).
    """
    from spectracam.core.files import atomic_write

    c = find_contents(directory)
    cases = []
    share = 1.0 / max(1, len(c.cases))  # many cases: each coarser, the page no larger
    for name, files in c.cases:
        try:
            cases.append(load_case(name, files.get("radiance"), files.get("raw"), files.get("rendered"), share))
        except SpectracamError as e:
            raise SpectracamError(f"case {name}: {e}" if name != "." else str(e)) from None
    page = build_page(c, cases)
    out = atomic_write(Path(directory) / "index.html", page.encode())
    if log:
        log(f"wrote {out} ({len(page) / 1e6:.1f} MB; {len(cases)} case{'s' if len(cases) != 1 else ''}, "
            f"{len(c.figures)} figures)")
    return out
