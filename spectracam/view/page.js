// spectracam view: the pixel probe and the case selector of index.html (spectracam/view/page.py).
// Each case's per-pixel data sit in <script type="application/json" id="case-N"> as base64 float32
// (little-endian) arrays of every stride-th pixel, top row first; the Bokeh models are found by name.
(function () {
  "use strict";
  const decoded = {};

  function b64floats(text) {
    const bin = atob(text);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Float32Array(bytes.buffer);
  }

  function caseData(i) {
    if (decoded[i]) return decoded[i];
    const el = document.getElementById("case-" + i);
    if (!el) return null;
    const c = JSON.parse(el.textContent);
    for (const key of ["spectra", "dn", "scene_lab", "rendered_lab", "error"]) {
      c[key] = c[key] ? b64floats(c[key]) : null;
    }
    decoded[i] = c;
    return c;
  }

  function model(name) {
    const docs = (window.Bokeh && window.Bokeh.documents) || [];
    for (const doc of docs) {
      const m = doc.get_model_by_name(name);
      if (m) return m;
    }
    return null;
  }

  function fmt(x, digits) {
    return (x === null || x === undefined || Number.isNaN(x)) ? "–" : x.toFixed(digits);
  }

  function slice(arr, index, n) {
    return arr ? Array.from(arr.subarray(index * n, index * n + n)) : null;
  }

  const spectracam = {
    current: 0,
    pinned: false,
    last: null,
    caseCount: function () { return document.querySelectorAll("script[id^=case-]").length; },
    data: caseData,

    // The probe at data coordinates (x, y) of the linked image figures (x right, y up, pixel units
    // of the full-size files): the kept pixel under it, its spectrum, digital numbers and CIELAB.
    probe: function (x, y) {
      const c = caseData(this.current);
      if (!c) return null;
      const s = c.stride;
      const col = Math.floor(x / s), row = Math.floor((c.height - y) / s);
      if (col < 0 || row < 0 || col >= c.cols || row >= c.rows) return null;
      const k = row * c.cols + col;
      const out = {
        case: c.name, x: col * s, y: row * s, stride: s,
        wavelengths_nm: c.wavelengths_nm,
        spectrum: slice(c.spectra, k, c.bands),
        channels: c.channels, dn: slice(c.dn, k, c.channels.length),
        scene_lab: slice(c.scene_lab, k, 3), rendered_lab: slice(c.rendered_lab, k, 3),
        delta_e: c.error ? c.error[k] : null,
        patch: patchAt(c, col * s, row * s),
      };
      this.last = out;
      this.show(out, c);
      return out;
    },

    show: function (p, c) {
      const spec = model("probe_spectrum");
      if (spec) {
        spec.data = p.spectrum ? {wavelength_nm: c.wavelengths_nm, radiance: p.spectrum}
                               : {wavelength_nm: [], radiance: []};
        const yr = model("spectrum_y"), top = p.spectrum ? Math.max(...p.spectrum) : 0;
        if (yr && top > 0) { yr.start = 0; yr.end = 1.1 * top; }
      }
      const mark = model("probe_mark");
      if (mark) mark.data = {x: [p.x + p.stride / 2], y: [c.height - p.y - p.stride / 2]};
      const info = model("probe_info");
      if (!info) return;
      const lab = (v) => v ? `${fmt(v[0], 2)}, ${fmt(v[1], 2)}, ${fmt(v[2], 2)}` : "–";
      const dn = p.dn ? p.channels.map((ch, i) => Number.isNaN(p.dn[i]) ? "" : `${ch} ${fmt(p.dn[i], 0)}`)
                          .filter((t) => t).join(", ") : "–";
      const csv = p.spectrum ? `<a download="spectrum_${p.x}_${p.y}.csv" href="data:text/csv;charset=utf-8,` +
        `${encodeURIComponent(spectracam.csv(p))}">spectrum as CSV</a>` : "";
      info.text = `<table class="probe"><tr><th>case</th><td>${p.case}</td></tr>` +
        `<tr><th>pixel (x, y)</th><td>${p.x}, ${p.y}</td></tr>` +
        `<tr><th>patch</th><td>${p.patch || "–"}</td></tr>` +
        `<tr><th>digital numbers</th><td>${dn}</td></tr>` +
        `<tr><th>scene L*, a*, b*</th><td>${lab(p.scene_lab)}</td></tr>` +
        `<tr><th>rendered L*, a*, b*</th><td>${lab(p.rendered_lab)}</td></tr>` +
        `<tr><th>ΔE*ab</th><td>${fmt(p.delta_e, 2)}</td></tr>` +
        `<tr><th>radiance at 550 nm</th><td>${p.spectrum ? fmt(interp(c.wavelengths_nm, p.spectrum, 550), 5) + " W·m⁻²·sr⁻¹·nm⁻¹" : "– (no radiance.exr)"}</td></tr></table>` + csv;
    },

    // The probed pixel's spectrum as CSV: one header row, one band a line (the file's float32 values).
    csv: function (p) {
      p = p || this.last;
      if (!p || !p.spectrum) return "";
      const lines = ["wavelength_nm,radiance_W_m2_sr_nm"];
      p.wavelengths_nm.forEach((w, i) => lines.push(`${w},${p.spectrum[i]}`));
      return lines.join("\n") + "\n";
    },

    // Show case i: its images in the linked figures, its camera's responsivities.
    select: function (i) {
      const c = caseData(i);
      if (!c) return false;
      this.current = i;
      const sel = model("case_select");
      if (sel && sel.value !== String(i)) sel.value = String(i);
      for (const role of ["scene", "raw", "rendered", "error"]) {
        const src = model("image_" + role), from = model("case_" + i + "_" + role);
        if (src && from) src.data = Object.assign({}, from.data);
      }
      const xr = model("image_x"), yr = model("image_y");
      if (xr && yr) { xr.start = 0; xr.end = c.width; yr.start = 0; yr.end = c.height; }
      const resp = model("responsivities");
      if (resp) {
        const names = Object.keys(c.responsivities);
        resp.data = {xs: names.map(() => c.wavelengths_nm), ys: names.map((n) => c.responsivities[n]),
                     color: names.map((n) => c.colours[n] || "#444444"), label: names};
      }
      const title = model("case_title");
      if (title) title.text = `<b>${c.name}</b> ${c.design ? "(" + c.design + ")" : ""} — ${c.width} × ${c.height} px` +
        (c.notes.length ? "<br><i>" + c.notes.join("; ") + "</i>" : "");
      return true;
    },
  };

  // The name of the chart patch whose scored box holds pixel (x, y) of the files, or null.
  function patchAt(c, x, y) {
    for (const [name, x0, y0, x1, y1] of (c.patches || [])) {
      if (x >= x0 && x < x1 && y >= y0 && y < y1) return name;
    }
    return null;
  }

  function interp(xs, ys, x) {
    if (!xs.length) return NaN;
    if (x <= xs[0]) return ys[0];
    for (let i = 1; i < xs.length; i++) {
      if (x <= xs[i]) return ys[i - 1] + (ys[i] - ys[i - 1]) * (x - xs[i - 1]) / (xs[i] - xs[i - 1]);
    }
    return ys[ys.length - 1];
  }

  window.spectracam = spectracam;
})();
