// spectracam view: the pixel probe, the line profile, the region statistics and the case selector of index.html
// (spectracam/view/page.py).  Each case's per-pixel data sit in <script type="application/json" id="case-N">, every
// array losslessly packed (page.py: packed): zlib's deflate of its little-endian bytes (float32, uint8 or uint16),
// perhaps regrouped by byte position, base64 — inflated here by the browser's own DecompressionStream into the very
// values the files hold, every stride-th pixel, top row first.  The Bokeh models are found by name.
(function () {
  "use strict";
  const decoded = {};
  const TYPES = {f4: [Float32Array, 4], u1: [Uint8Array, 1], u2: [Uint16Array, 2]};
  const ROLES = ["scene", "raw", "rendered", "error"];
  const RGB_COLOURS = ["#e6261a", "#1acc26", "#264dff"];

  async function inflate(text) {
    const bin = atob(text);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
    return new Uint8Array(await new Response(stream).arrayBuffer());
  }

  // A packed array (page.py: packed) back to its typed array, flat, C order.
  async function unpack(p) {
    if (!p) return null;
    const bytes = await inflate(p.data);
    const [Type, size] = TYPES[p.dtype];
    let out = bytes;
    if (p.shuffle && size > 1) {
      const n = bytes.length / size;
      out = new Uint8Array(bytes.length);
      for (let b = 0; b < size; b++) {
        for (let i = 0; i < n; i++) out[i * size + b] = bytes[b * n + i];
      }
    }
    return new Type(out.buffer, out.byteOffset, out.length / size);
  }

  // CIE 1976 L*a*b* of XYZ relative to a white (as spectracam.core.cielab.xyz_to_lab), float64.
  function lab(x, y, z, w) {
    const f = (t) => t > 216 / 24389 ? Math.cbrt(t) : (24389 / 27 * t + 16) / 116;
    const fx = f(x / w[0]), fy = f(y / w[1]), fz = f(z / w[2]);
    return [116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)];
  }

  // (rows, cols, 3) uint8, top row first -> (rows * cols) uint32 RGBA, bottom row first (Bokeh draws row 0 at y = 0).
  function rgbaBottomUp(rgb, rows, cols) {
    if (!rgb) return null;
    const out = new Uint8Array(rows * cols * 4);
    for (let r = 0; r < rows; r++) {
      const from = r * cols * 3, to = (rows - 1 - r) * cols * 4;
      for (let k = 0; k < cols; k++) {
        out[to + 4 * k] = rgb[from + 3 * k];
        out[to + 4 * k + 1] = rgb[from + 3 * k + 1];
        out[to + 4 * k + 2] = rgb[from + 3 * k + 2];
        out[to + 4 * k + 3] = 255;
      }
    }
    return new Uint32Array(out.buffer);
  }

  function bottomUp(values, rows, cols) {
    const out = new Float32Array(rows * cols);
    for (let r = 0; r < rows; r++) out.set(values.subarray(r * cols, (r + 1) * cols), (rows - 1 - r) * cols);
    return out;
  }

  // Rendered L*a*b* (the display's XYZ of rendered.exr's RGB, white = the display's) and ΔE*ab against the scene's.
  function colorimetry(c) {
    const n = c.rows * c.cols;
    c.rendered_lab = null;
    c.error = null;
    if (!c.rendered_rgb || !c.display_to_xyz) return;
    const M = c.display_to_xyz, w = M.map((row) => row[0] + row[1] + row[2]);
    c.rendered_lab = new Float32Array(3 * n);
    for (let k = 0; k < n; k++) {
      const r = c.rendered_rgb[3 * k], g = c.rendered_rgb[3 * k + 1], b = c.rendered_rgb[3 * k + 2];
      const v = lab(M[0][0] * r + M[0][1] * g + M[0][2] * b, M[1][0] * r + M[1][1] * g + M[1][2] * b,
                    M[2][0] * r + M[2][1] * g + M[2][2] * b, w);
      c.rendered_lab.set(v, 3 * k);
    }
    if (!c.scene_lab) return;
    c.error = new Float32Array(n);
    for (let k = 0; k < n; k++) {
      let s = 0;
      for (let j = 0; j < 3; j++) s += (c.rendered_lab[3 * k + j] - c.scene_lab[3 * k + j]) ** 2;
      c.error[k] = Math.sqrt(s);
    }
  }

  async function decodeCase(i) {
    const el = document.getElementById("case-" + i);
    if (!el) return null;
    const c = JSON.parse(el.textContent);
    const a = {};
    for (const [key, p] of Object.entries(c.arrays)) a[key] = await unpack(p);
    delete c.arrays;
    const n = c.rows * c.cols, N = c.channels.length;
    c.spectra = a.spectra;
    c.scene_lab = a.scene_lab;
    c.rendered_rgb = a.rendered_rgb;
    c.dn = null;
    if (a.dn) {   // N digital numbers a pixel, NaN where a mosaic's pixel records another channel
      c.dn = new Float32Array(n * N);
      if (a.dn_channel) {
        c.dn.fill(NaN);
        for (let k = 0; k < n; k++) c.dn[k * N + a.dn_channel[k]] = a.dn[k];
      } else {
        c.dn.set(a.dn);
      }
    }
    colorimetry(c);
    c.pictures = {scene: rgbaBottomUp(a.image_scene, c.rows, c.cols), raw: rgbaBottomUp(a.image_raw, c.rows, c.cols),
                  rendered: rgbaBottomUp(a.image_rendered, c.rows, c.cols),
                  error: c.error ? bottomUp(c.error, c.rows, c.cols) : null};
    return c;
  }

  function caseData(i) {
    return decoded[i] || null;
  }

  function model(name) {
    const docs = (window.Bokeh && window.Bokeh.documents) || [];
    for (const doc of docs) {
      const m = doc.get_model_by_name(name);
      if (m) return m;
    }
    return null;
  }

  function ndarray(values, shape) {
    return window.Bokeh.require("core/util/ndarray").ndarray(values, {shape: shape});
  }

  function fmt(x, digits) {
    return (x === null || x === undefined || Number.isNaN(x)) ? "–" : x.toFixed(digits);
  }

  function slice(arr, index, n) {
    return arr ? Array.from(arr.subarray(index * n, index * n + n)) : null;
  }

  function nearestBand(c, nm) {
    let best = 0;
    c.wavelengths_nm.forEach((w, i) => { if (Math.abs(w - nm) < Math.abs(c.wavelengths_nm[best] - nm)) best = i; });
    return best;
  }

  // The channels a profile or a region of the panel `role` reports: name, CSV column, colour and value at kept pixel k.
  //   scene: the radiance of the band nearest the read-out wavelength (550 nm until chosen in the probe's table,
  //          setWavelength), radiance.exr's own float32
  //          values in W·m⁻²·sr⁻¹·nm⁻¹ — an engineer checks a scene against the physics, not the 8-bit sRGB preview,
  //          which is tone-mapped, clipped and quantised; without radiance.exr, the scene's L*, a*, b*;
  //   raw: each channel's digital numbers, in its channel's colour (a mosaic: only that channel's pixels);
  //   rendered: rendered.exr's linear display R, G, B;  error: ΔE*ab.
  function channelsOf(c, role) {
    if (role === "scene" && c.spectra) {
      const b = nearestBand(c, spectracam.wavelength_nm), w = c.wavelengths_nm[b];
      return [{name: `L(${w} nm)`, column: `radiance_${w}nm_W_m2_sr_nm`, colour: "#222222",
               value: (k) => c.spectra[k * c.bands + b]}];
    }
    if (role === "scene" || (role === "error" && !c.error)) {
      return c.scene_lab ? ["L*", "a*", "b*"].map((name, j) => ({name: name, column: ["L", "a", "b"][j] + "_star",
        colour: RGB_COLOURS[j], value: (k) => c.scene_lab[3 * k + j]})) : [];
    }
    if (role === "raw") {
      const N = c.channels.length;
      return c.dn ? c.channels.map((ch, j) => ({name: ch, column: `${ch}_DN`, colour: ink(c.colours[ch]),
                                                value: (k) => c.dn[k * N + j]})) : [];
    }
    if (role === "rendered") {
      return c.rendered_rgb ? ["R", "G", "B"].map((ch, j) => ({name: ch, column: `${ch}_display_linear`,
        colour: RGB_COLOURS[j], value: (k) => c.rendered_rgb[3 * k + j]})) : [];
    }
    return [{name: "ΔE*ab", column: "delta_E_ab", colour: "#222222", value: (k) => c.error[k]}];
  }

  // The kept pixel (col, row) under data coordinates (x, y) (x right, y up, pixels of the files), clamped to the image.
  function keptPixel(c, x, y) {
    const clamp = (v, n) => Math.min(n - 1, Math.max(0, v));
    return [clamp(Math.floor(x / c.stride), c.cols), clamp(Math.floor((c.height - y) / c.stride), c.rows)];
  }

  function meanSd(values) {
    const v = values.filter((x) => !Number.isNaN(x));
    const n = v.length;
    if (!n) return [0, NaN, NaN];
    const mean = v.reduce((s, x) => s + x, 0) / n;
    const sd = n > 1 ? Math.sqrt(v.reduce((s, x) => s + (x - mean) ** 2, 0) / (n - 1)) : NaN;
    return [n, mean, sd];
  }

  function csvCell(v) {
    return Number.isNaN(v) || v === null || v === undefined ? "" : String(v);
  }

  const spectracam = {
    current: 0,
    pinned: false,
    last: null,
    loaded: false,
    lastProfile: null,
    lastRegion: null,
    lineStart: null,
    wavelength_nm: 550,
    caseCount: function () { return document.querySelectorAll("script[id^=case-]").length; },
    data: caseData,

    // Inflate every case's data, then show the first.
    start: async function () {
      const n = this.caseCount();
      for (let i = 0; i < n; i++) decoded[i] = await decodeCase(i);
      this.loaded = true;
      this.select(0);
    },

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
        rendered_rgb: slice(c.rendered_rgb, k, 3),
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
      const lab3 = (v) => v ? `${fmt(v[0], 2)}, ${fmt(v[1], 2)}, ${fmt(v[2], 2)}` : "–";
      const dn = p.dn ? p.channels.map((ch, i) => Number.isNaN(p.dn[i]) ? "" : `${ch} ${fmt(p.dn[i], 0)}`)
                          .filter((t) => t).join(", ") : "–";
      const csv = p.spectrum ? `<a download="spectrum_${p.x}_${p.y}.csv" href="data:text/csv;charset=utf-8,` +
        `${encodeURIComponent(spectracam.csv(p))}">spectrum as CSV</a>` : "";
      info.text = `<table class="probe"><tr><th>case</th><td>${p.case}</td></tr>` +
        `<tr><th>pixel (x, y)</th><td>${p.x}, ${p.y}</td></tr>` +
        `<tr><th>patch</th><td>${p.patch || "–"}</td></tr>` +
        `<tr><th>digital numbers</th><td>${dn}</td></tr>` +
        `<tr><th>scene L*, a*, b*</th><td>${lab3(p.scene_lab)}</td></tr>` +
        `<tr><th>rendered L*, a*, b*</th><td>${lab3(p.rendered_lab)}</td></tr>` +
        `<tr><th>ΔE*ab</th><td>${fmt(p.delta_e, 2)}</td></tr>` +
        `<tr><th>radiance at ${this.wavelengthChoice(c)}</th><td>${p.spectrum ? fmt(p.spectrum[nearestBand(c, this.wavelength_nm)], 5) + " W·m⁻²·sr⁻¹·nm⁻¹" : "– (no radiance.exr)"}</td></tr></table>` + csv;
    },

    // The read-out wavelength's chooser: the case's bands, the one nearest wavelength_nm selected.
    wavelengthChoice: function (c) {
      if (!c.spectra) return `${this.wavelength_nm} nm`;
      const b = nearestBand(c, this.wavelength_nm);
      return `<select id="spectracam-wavelength" onchange="window.spectracam.setWavelength(this.value)">` +
        c.wavelengths_nm.map((w, i) => `<option value="${w}"${i === b ? " selected" : ""}>${w} nm</option>`).join("") +
        "</select>";
    },

    // Read the scene's radiance at the band nearest `nm` (nm): the probe's table, and the scene panel's last profile
    // and region drawn again.  Returns the band's wavelength, nm.
    setWavelength: function (nm) {
      const v = Number(nm);
      if (!Number.isFinite(v)) return null;
      this.wavelength_nm = v;
      const c = caseData(this.current);
      if (this.last && c) this.show(this.last, c);
      if (this.lastProfile && this.lastProfile.role === "scene" && this.profileArgs) this.profile(...this.profileArgs);
      if (this.lastRegion && this.lastRegion.role === "scene" && this.regionArgs) this.region(...this.regionArgs);
      return c && c.spectra ? c.wavelengths_nm[nearestBand(c, v)] : v;
    },

    // The probed pixel's spectrum as CSV: one header row, one band a line (the file's float32 values).
    csv: function (p) {
      p = p || this.last;
      if (!p || !p.spectrum) return "";
      const lines = ["wavelength_nm,radiance_W_m2_sr_nm"];
      p.wavelengths_nm.forEach((w, i) => lines.push(`${w},${p.spectrum[i]}`));
      return lines.join("\n") + "\n";
    },

    // A click on panel `role` at (x, y): the profile along its row or column, or (third mode) a line from the
    // previous click to this one.
    tapped: function (role, x, y) {
      const c = caseData(this.current);
      if (!c) return null;
      const mode = model("profile_mode") ? model("profile_mode").active : 0;
      if (mode === 0) return this.profile(role, 0, y, c.cols * c.stride - 1e-6, y);
      if (mode === 1) return this.profile(role, x, c.height, x, c.height - c.rows * c.stride + 1e-6);
      if (!this.lineStart || this.lineStart.role !== role) {
        this.lineStart = {role: role, x: x, y: y};
        const info = model("profile_info");
        if (info) info.text = "<i>click the line's end</i>";
        return null;
      }
      const s = this.lineStart;
      this.lineStart = null;
      return this.profile(role, s.x, s.y, x, y);
    },

    // The values of panel `role`'s channels (channelsOf) at the kept pixels along the line from data coordinates
    // (x0, y0) to (x1, y1): one sample per kept pixel along its longer axis (a digital differential analyser).
    profile: function (role, x0, y0, x1, y1) {
      const c = caseData(this.current);
      if (!c) return null;
      this.profileArgs = [role, x0, y0, x1, y1];
      const s = c.stride, [c0, r0] = keptPixel(c, x0, y0), [c1, r1] = keptPixel(c, x1, y1);
      const steps = Math.max(Math.abs(c1 - c0), Math.abs(r1 - r0));
      const xs = [], ys = [], distance = [], ks = [];
      for (let t = 0; t <= steps; t++) {
        const col = steps ? Math.round(c0 + (c1 - c0) * t / steps) : c0;
        const row = steps ? Math.round(r0 + (r1 - r0) * t / steps) : r0;
        xs.push(col * s); ys.push(row * s); ks.push(row * c.cols + col);
        distance.push(Math.hypot((col - c0) * s, (row - r0) * s));
      }
      const chans = channelsOf(c, role);
      const out = {case: c.name, role: role, stride: s, x: xs, y: ys, distance_px: distance,
                   channels: chans.map((ch) => ch.name), columns: chans.map((ch) => ch.column),
                   values: chans.map((ch) => ks.map((k) => ch.value(k)))};
      this.lastProfile = out;
      this.showProfile(out, c, chans);
      return out;
    },

    showProfile: function (p, c, chans) {
      const lines = model("profile_lines"), points = model("profile_points");
      const keep = (j) => p.distance_px.map((d, i) => [d, p.values[j][i]]).filter((v) => !Number.isNaN(v[1]));
      if (lines) {
        lines.data = {xs: chans.map((_, j) => keep(j).map((v) => v[0])), ys: chans.map((_, j) => keep(j).map((v) => v[1])),
                      color: chans.map((ch) => ch.colour), label: chans.map((ch) => ch.name)};
      }
      if (points) {
        const all = chans.flatMap((ch, j) => keep(j).map((v) => [v[0], v[1], ch.colour]));
        points.data = {x: all.map((v) => v[0]), y: all.map((v) => v[1]), color: all.map((v) => v[2])};
      }
      const finite = p.values.flat().filter((v) => !Number.isNaN(v));
      const xr = model("profile_x"), yr = model("profile_y"), n = p.x.length;
      if (xr) { xr.start = 0; xr.end = Math.max(1, p.distance_px[n - 1]); }
      if (yr && finite.length) {
        const lo = Math.min(...finite), hi = Math.max(...finite), pad = 0.05 * (hi - lo || Math.abs(hi) || 1);
        yr.start = lo - pad; yr.end = hi + pad;
      }
      const mark = model("profile_mark");
      if (mark) mark.data = {x: [p.x[0] + p.stride / 2, p.x[n - 1] + p.stride / 2],
                             y: [c.height - p.y[0] - p.stride / 2, c.height - p.y[n - 1] - p.stride / 2]};
      const fig = model("figure_profile");
      if (fig && fig.title) fig.title.text = `line profile: ${p.role} panel, (${p.x[0]}, ${p.y[0]}) → ` +
        `(${p.x[n - 1]}, ${p.y[n - 1]}), ${n} kept pixels`;
      const info = model("profile_info");
      if (info) info.text = `profile of the ${p.role} panel: ${p.channels.join(", ")} — ` +
        `<a download="profile_${p.role}_${p.x[0]}_${p.y[0]}_${p.x[n - 1]}_${p.y[n - 1]}.csv" ` +
        `href="data:text/csv;charset=utf-8,${encodeURIComponent(this.profileCsv(p))}">profile as CSV</a>`;
    },

    // The profile as CSV: one header row (the files' pixel x, y, the distance, each channel with its unit), one kept
    // pixel a line; an empty cell where a mosaic's pixel records another channel.
    profileCsv: function (p) {
      p = p || this.lastProfile;
      if (!p) return "";
      const lines = [["x_px", "y_px", "distance_px", ...p.columns].join(",")];
      p.x.forEach((x, i) => lines.push([x, p.y[i], p.distance_px[i], ...p.values.map((v) => csvCell(v[i]))].join(",")));
      return lines.join("\n") + "\n";
    },

    // The kept pixels of panel `role` whose centres lie in the rectangle of data coordinates (x0, y0)–(x1, y1): per
    // channel the number of pixels that record it, their mean and sample standard deviation (ddof = 1).
    region: function (role, x0, y0, x1, y1) {
      const c = caseData(this.current);
      if (!c) return null;
      this.regionArgs = [role, x0, y0, x1, y1];
      const s = c.stride;
      const xa = Math.min(x0, x1), xb = Math.max(x0, x1);
      const ya = c.height - Math.max(y0, y1), yb = c.height - Math.min(y0, y1);   // the files' y, down
      const colA = Math.max(0, Math.ceil((xa - s / 2) / s)), colB = Math.min(c.cols - 1, Math.ceil((xb - s / 2) / s) - 1);
      const rowA = Math.max(0, Math.ceil((ya - s / 2) / s)), rowB = Math.min(c.rows - 1, Math.ceil((yb - s / 2) / s) - 1);
      const ks = [];
      for (let r = rowA; r <= rowB; r++) for (let k = colA; k <= colB; k++) ks.push(r * c.cols + k);
      const chans = channelsOf(c, role);
      const stats = chans.map((ch) => { const [n, mean, sd] = meanSd(ks.map((k) => ch.value(k)));
                                        return {name: ch.name, n: n, mean: mean, sd: sd}; });
      const out = {case: c.name, role: role, stride: s, cols: [colA, colB], rows: [rowA, rowB],
                   x: [colA * s, colB * s], y: [rowA * s, rowB * s], pixels: ks.length, channels: stats};
      this.lastRegion = out;
      const box = model("region_mark");
      if (box) box.data = ks.length ? {left: [colA * s], right: [(colB + 1) * s], top: [c.height - rowA * s],
                                       bottom: [c.height - (rowB + 1) * s]} : {left: [], right: [], top: [], bottom: []};
      const info = model("region_info");
      if (info) info.text = `<b>region of the ${role} panel</b>: x ${colA * s}–${colB * s}, y ${rowA * s}–${rowB * s} ` +
        `(${ks.length} kept pixels)<table class="probe"><tr><th>channel</th><th>pixels</th><th>mean</th>` +
        `<th>σ (sample, n − 1)</th></tr>` + stats.map((st) => `<tr><td>${st.name}</td><td>${st.n}</td>` +
        `<td>${fmt(st.mean, 5)}</td><td>${fmt(st.sd, 5)}</td></tr>`).join("") + "</table>";
      return out;
    },

    // Show case i: its images in the linked figures, its camera's responsivities.
    select: function (i) {
      const c = caseData(i);
      if (!c) return false;
      this.current = i;
      this.lineStart = null;
      const sel = model("case_select");
      if (sel && sel.value !== String(i)) sel.value = String(i);
      const s = c.stride;
      for (const role of ROLES) {
        const src = model("image_" + role);
        if (!src) continue;
        const img = c.pictures[role];
        src.data = img ? {image: [ndarray(img, [c.rows, c.cols])], x: [0], y: [c.height - c.rows * s],
                          dw: [c.cols * s], dh: [c.rows * s]}
                       : {image: [ndarray(role === "error" ? new Float32Array([NaN]) : new Uint32Array(1), [1, 1])],
                          x: [0], y: [0], dw: [c.width], dh: [c.height]};
      }
      const xr = model("image_x"), yr = model("image_y");
      if (xr && yr) { xr.start = 0; xr.end = c.width; yr.start = 0; yr.end = c.height; }
      const resp = model("responsivities");
      if (resp) {
        const names = Object.keys(c.responsivities);
        resp.data = {xs: names.map(() => c.wavelengths_nm), ys: names.map((n) => c.responsivities[n]),
                     color: names.map((n) => ink(c.colours[n])), label: names};
      }
      const title = model("case_title");
      if (title) title.text = `<b>${c.name}</b> ${c.design ? "(" + c.design + ")" : ""} — ${c.width} × ${c.height} px` +
        (c.notes.length ? "<br><i>" + c.notes.join("; ") + "</i>" : "");
      return true;
    },
  };

  // A channel's colour as a line on the figures' white: scaled down to a relative luminance (Rec. 709 weights of the
  // sRGB values, a plain approximation) of at most 0.45, so white (W) and yellow (Y) channels stay visible; "#444444"
  // for a channel without a colour.
  function ink(hex) {
    if (!hex || !/^#[0-9a-f]{6}$/i.test(hex)) return "#444444";
    const v = [1, 3, 5].map((i) => parseInt(hex.slice(i, i + 2), 16));
    const y = (0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2]) / 255;
    if (y <= 0.45) return hex.toLowerCase();
    return "#" + v.map((x) => Math.round(x * 0.45 / y).toString(16).padStart(2, "0")).join("");
  }

  // The name of the chart patch whose scored box holds pixel (x, y) of the files, or null.
  function patchAt(c, x, y) {
    for (const [name, x0, y0, x1, y1] of (c.patches || [])) {
      if (x >= x0 && x < x1 && y >= y0 && y < y1) return name;
    }
    return null;
  }

  spectracam.ink = ink;
  window.spectracam = spectracam;
})();
