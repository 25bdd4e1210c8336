"""Time-resolved rendering: the scene at time slices, each channel integrating the slices in its window.

A :class:`MovingScene` renders a spatial target (:mod:`spectracam.experiments.spatial.targets`) at any pose. With
Mitsuba the scene is built once by the spatial renderer's builder and every slice only assigns new
``to_world`` transforms (rectangles) or vertex positions (meshes) and calls ``params.update()`` — the
compiled kernel is reused. Each slice is rendered into a small *basis* whose linear combination is the
band radiance:

* ``materials`` (default): one render per material, its reflectance 1 and the others' 0, under a light
  of irradiance π — the fraction of every sub-pixel each material covers (through the perspective and,
  where needed, the thin lens); the band radiance is ``Σ_m coverage_m · E·S_m/π`` with the exact band
  averages of :func:`spectracam.experiments.spatial.render.material_radiance`. This is exact for the spatial
  targets (Lambertian materials, one light along their normal: the spectrum and the geometry separate),
  and costs ``M`` renders per slice instead of one per band (2 for the edge and the star);
* ``bands``: one render per band, as the static spatial renderer does (``B`` renders per slice).

:func:`integrate` places slices in time (``t = 0`` the middle of the capture): slice j at
``t_j = j·Δt`` with ``Δt = max_step_px / (fastest image speed)`` so the image moves at most
``max_step_px`` between slices (or a set number over the capture), halved as often as needed for the
shortest window to hold :data:`MIN_SLICES_PER_WINDOW` slices; for a uniform translation every
speed then samples the same positions (a lattice of ``max_step_px / 2^k``) and shares their renders. Slices share the sample budget:
``samples_per_subpixel // slices`` each (at least 1). Each channel's window — per row with a rolling
shutter — weights the slices by the time of their cell ``[t_j − Δt/2, t_j + Δt/2]`` inside it (the
midpoint rule of ``∫ rate dt``), and the weighted sum divided by the window's length is the channel's
*time-averaged* basis. :func:`channel_rates` takes it through the spatial optics (diffraction, defocus,
pixel aperture, sampling; linear, so the time average commutes with them) to photo-electrons per
second, which the architecture's own ``record`` multiplies by the exposure time (charge is linear in
time), so the sensor model is reused unchanged.

Rolling shutter: a row's window applies to the sub-pixel rows of that pixel row before the optics;
the optics then mix a few neighbouring rows whose windows differ by one line time (30 µs): the image
moves ``speed × line time`` (≤ 0.01 px here) between them, far below anything measured.
"""
from __future__ import annotations

import math
import zlib
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import scipy.fft as sfft

from spectracam.camera import CameraSpec, band_weights
from spectracam.core.errors import ConfigError, SpectracamError
from spectracam.experiments.spatial import optics as sopt
from spectracam.experiments.spatial.geometry import CameraGeometry
from spectracam.experiments.spatial.render import material_radiance, needs_thinlens
from spectracam.experiments.spatial.targets import SiemensStar, SlantedEdge, Target, object_points
from spectracam.experiments.motion.motion import Motion, pose_key, pose_matrix
from spectracam.experiments.motion.timing import CaptureTiming

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from spectracam.core.spectra import WavelengthGrid
    from spectracam.scene.illuminant import IlluminantSpec

RENDER_MODES = ("materials", "bands")
#: Fewest slices in the shortest exposure window (issue 34).  A window's cells at its two ends are partly
#: inside it, and each is rendered at its cell's middle, so the window's mean pose is off by up to
#: Δt²/(4·window) of time: with a few slices per window that is below 1/64 of the window, and a channel's
#: edge (breakup measured to 0.01 px) is where the window's middle puts it.  Before, at 0.0025 px/ms a
#: 40 ms window could hold one 100 ms cell: its edge was 10 ms (25 % of the breakup) off.  The step is
#: halved, not set, so the positions stay on the shared lattice of ``max_step_px``.
MIN_SLICES_PER_WINDOW = 4
#: Rendered poses kept for reuse by the next capture at the same speed (the designs share their slice
#: positions), least recently used dropped first: enough for every pose of the default run (161 of
#: 2.6 MB), and a bound so that a run of 100 000 slices does not grow without end.
BASIS_CACHE_BYTES = 1 << 30
#: Reflectance of the materials not being rendered: Mitsuba refuses a spectrum of zeros (no probability
#: mass); 1e-9 leaves a bias below float32 resolution.
_OFF = 1e-9


# ------------------------------------------------------------------------------------------------
# the closed form at a pose

def posed_edge(edge: SlantedEdge, geometry: CameraGeometry, pose: Sequence[float]) -> SlantedEdge:
    """The slanted edge moved by a pose: an edge of angle ``a + θ`` through the moved point.

    Parameters
    ----------
    edge : SlantedEdge
        The edge at the reference pose.
    geometry : CameraGeometry
        Its object pixel, mm.
    pose : sequence of float
        ``(dx_mm, dy_mm, angle_deg)`` on the object plane.

    Returns
    -------
    SlantedEdge
        The moved edge: its angle and its crossing ``x0_px`` of the middle row.
    """
    from dataclasses import replace

    dx, dy, th = (float(x) for x in pose)
    x0 = edge.x0_px * geometry.object_pixel_mm
    P = pose_matrix(pose) @ np.array([x0, 0.0, 1.0])
    a = edge.angle_deg + th
    x0n = P[0] + math.tan(math.radians(a)) * P[1]
    return replace(edge, angle_deg=a, x0_px=x0n / geometry.object_pixel_mm)


def posed_coverage(target: Target, geometry: CameraGeometry, supersampling: int,
                   pose: Sequence[float]) -> np.ndarray:
    """``(M, Hs, Ws)`` coverage of the target moved by ``pose``: the edge exactly (its closed form at
    the moved line), the star by its point sampling at the inversely moved points.

    Parameters
    ----------
    target : Target
        A :class:`SlantedEdge` or a :class:`SiemensStar`.
    geometry : CameraGeometry
        The image and its object pixel, mm.
    supersampling : int
        Sub-pixels per pixel along each axis.
    pose : sequence of float
        ``(dx_mm, dy_mm, angle_deg)`` on the object plane.

    Returns
    -------
    ndarray, shape (M, Hs, Ws)
        The fraction of every sub-pixel each material covers.

    Raises
    ------
    ConfigError
        For another target (it moves with Mitsuba only).
    """
    if isinstance(target, SlantedEdge):
        return posed_edge(target, geometry, pose).coverage(geometry, supersampling)
    if isinstance(target, SiemensStar):
        inv = np.linalg.inv(pose_matrix(pose))
        X, Y = object_points(geometry, supersampling, target.oversampling)
        R = target.radius_px * geometry.object_pixel_mm
        o = target.oversampling
        dark = np.zeros((Y.shape[0], X.shape[0]))
        for i in range(o):
            for j in range(o):
                x, y = X[None, :, j], Y[:, i, None]
                xs = inv[0, 0] * x + inv[0, 1] * y + inv[0, 2]
                ys = inv[1, 0] * x + inv[1, 1] * y + inv[1, 2]
                dark += target._dark(xs, ys, R)
        dark /= o * o
        return np.stack([dark, 1.0 - dark])
    raise ConfigError("renderer", "analytic", f"moves the edge and the star only; the {target.name} moves with mitsuba")


# ------------------------------------------------------------------------------------------------

class MovingScene:
    """A target that can be rendered at any pose: a basis ``(K, Hs, Ws)`` per pose, and the
    coefficients ``(K, B)`` that turn it into band radiance.

    Parameters
    ----------
    target : Target
        The spatial target.
    geometry : CameraGeometry
        The camera's view of it (margin included).
    illuminant : IlluminantSpec
        The light, along the target's normal.
    grid : WavelengthGrid
        The bands, nm.
    supersampling : int
        Sub-pixels per pixel along each axis.
    renderer : str
        ``"mitsuba"`` or ``"analytic"`` (the edge and the star only; always ``materials`` mode).
    mode : str
        ``"materials"`` (one render per material) or ``"bands"`` (one per band): :data:`RENDER_MODES`.
    variant : str
        Mitsuba's variant (``"auto"``: chosen for this machine).
    seed : int
        Mitsuba's seed (each pose's renders are seeded from it and the pose).
    log : callable or None
        ``log(line)``: Mitsuba's notices.

    Raises
    ------
    ConfigError
        On an unknown renderer or mode.
    """

    def __init__(self, target: Target, geometry: CameraGeometry, illuminant: IlluminantSpec, grid: WavelengthGrid,
                 supersampling: int, renderer: str = "mitsuba", mode: str = "materials", variant: str = "auto",
                 seed: int = 0, log: Callable[[str], object] | None = None):
        if renderer not in ("mitsuba", "analytic"):
            raise ConfigError("renderer", renderer, "must be 'mitsuba' or 'analytic'")
        if mode not in RENDER_MODES:
            raise ConfigError("render_mode", mode, "must be one of " + ", ".join(map(repr, RENDER_MODES)))
        self.target, self.geometry, self.illuminant, self.grid = target, geometry, illuminant, grid
        self.supersampling, self.renderer, self.seed = supersampling, renderer, seed
        self.mode = "materials" if renderer == "analytic" else mode
        self.L = material_radiance(target, illuminant, grid)                       # (M, B)
        self.renders = 0          # basis renders made (cache misses)
        self._cache: OrderedDict = OrderedDict()   # pose → basis, least recently used first
        self._transfer: dict = {}
        self.metadata = {"renderer": renderer, "render_mode": self.mode}
        if renderer == "mitsuba":
            self._build_mitsuba(variant, log)

    # -- Mitsuba ----------------------------------------------------------------------------------
    def _build_mitsuba(self, variant, log):
        from spectracam.render.mitsuba import POINTS_PER_BAND, activate_variant, select_variant
        from spectracam.experiments.spatial.render import build_scene

        name, reason = select_variant(variant)
        mi = self._mi = activate_variant(name)
        widths = self.grid.widths_nm
        self._width = float(widths.max())
        if not np.allclose(widths, self._width):
            raise SpectracamError("wavelengths: Mitsuba renders evenly spaced grids only")
        thin = needs_thinlens(self.target, self.geometry)
        if log:
            log(f"Mitsuba: building the moving {self.target.name} scene ({name}, {'thinlens' if thin else 'perspective'})")
        self._scene, self._params, self._materials = build_scene(mi, self.target, self.geometry, self.supersampling, 1,
                                                            self._width, thin)
        self._base = {}
        for key, shape, _ in self.target.mitsuba_shapes(mi, self.geometry):
            if isinstance(shape, dict):
                self._base[key] = ("to_world", shape["to_world"])
            else:
                self._base[key] = ("vertex_positions", np.asarray(shape[0], float))
        self._Float = type(self._params["light.irradiance.values"])
        self._npts = POINTS_PER_BAND + 1
        self._pose = None
        self.metadata.update(variant=name, variant_reason=reason, camera="thinlens" if thin else "perspective",
                             mitsuba_version=mi.__version__)

    def _set_pose(self, pose):
        if self._pose == pose_key(pose):
            return
        mi, p = self._mi, self._params
        T = mi.ScalarTransform4f
        dx, dy, a = (float(x) for x in pose)
        move = T().translate([dx, dy, 0.0]) @ T().rotate([0, 0, 1], a)
        M = pose_matrix(pose)
        for key, (kind, base) in self._base.items():
            if kind == "to_world":
                p[f"{key}.to_world"] = move @ base
            else:
                V = base.copy()
                V[:, :2] = V[:, :2] @ M[:2, :2].T + M[:2, 2]
                p[f"{key}.vertex_positions"] = mi.Float(np.ascontiguousarray(V, np.float32).ravel())
        p.update()
        self._pose = pose_key(pose)

    def _render_mitsuba(self, pose, spp: int) -> np.ndarray:
        from spectracam.scene.illuminant import spectral_irradiance
        from spectracam.core.spectra import band_sample_points

        mi, p, F = self._mi, self._params, self._Float
        self._set_pose(pose)
        Hs = self.geometry.height_px * self.supersampling
        Ws = self.geometry.width_px * self.supersampling
        base_seed = zlib.crc32(repr((self.seed, pose_key(pose), spp)).encode())
        if self.mode == "materials":
            M = len(self.L)
            out = np.empty((M, Hs, Ws), np.float32)
            p["light.irradiance.values"] = F(np.full(self._npts, np.pi, np.float32))
            for m in range(M):
                for key, mk in self._materials.items():
                    p[f"{key}.bsdf.reflectance.values"] = F(np.full(self._npts, 1.0 if mk == m else _OFF, np.float32))
                p.update()
                out[m] = np.asarray(mi.render(self._scene, p, seed=(base_seed + 7919 * m) & 0x7FFFFFFF, spp=spp))[:, :, 0]
            return out
        E = spectral_irradiance(self.illuminant)
        spectra = [S for _, S in self.target.materials()]
        lam = band_sample_points(self.grid, self._npts - 1)
        out = np.empty((len(self.grid), Hs, Ws), np.float32)
        for b in range(len(self.grid)):
            p["light.irradiance.values"] = F(E(lam[b]).astype(np.float32))
            for key, mk in self._materials.items():
                p[f"{key}.bsdf.reflectance.values"] = F(np.asarray(spectra[mk](lam[b]), np.float32))
            p.update()
            out[b] = np.asarray(mi.render(self._scene, p, seed=(base_seed + 7919 * b) & 0x7FFFFFFF, spp=spp))[:, :, 0]
        return out

    # -- the basis ----------------------------------------------------------------------------------
    @property
    def coefficients(self) -> np.ndarray:
        """``(K, B)``: band radiance = Σ_k basis_k · coefficients[k]."""
        return self.L if self.mode == "materials" else np.eye(len(self.grid))

    def basis(self, pose: Sequence[float], spp: int = 1) -> np.ndarray:
        """``(K, Hs, Ws)`` float32 of the target at ``pose`` (cached by pose and samples).

        Parameters
        ----------
        pose : sequence of float
            ``(dx_mm, dy_mm, angle_deg)`` on the object plane.
        spp : int
            Mitsuba's samples per sub-pixel of each render (the analytic renderer ignores it).

        Returns
        -------
        ndarray, shape (K, Hs, Ws)
            Materials mode: each material's coverage; bands mode: each band's radiance, W·m⁻²·sr⁻¹·nm⁻¹.
        """
        key = (pose_key(pose), int(spp) if self.renderer == "mitsuba" else 0)
        if key in self._cache:
            self._cache.move_to_end(key)
            return self._cache[key]
        if self.renderer == "analytic":
            B = posed_coverage(self.target, self.geometry, self.supersampling, pose).astype(np.float32)
        else:
            B = self._render_mitsuba(pose, int(spp))
        self.renders += 1
        self._cache[key] = B
        while len(self._cache) > 1 and len(self._cache) * B.nbytes > BASIS_CACHE_BYTES:
            self._cache.popitem(last=False)
        return B

    def clear(self) -> None:
        """Drop the cached renders of every pose."""
        self._cache.clear()

    def radiance(self, basis: np.ndarray) -> np.ndarray:
        """``(Hs, Ws, B)`` band radiance of a basis image.

        Parameters
        ----------
        basis : ndarray, shape (K, Hs, Ws)
            From :meth:`basis`, or a time average of such.

        Returns
        -------
        ndarray, shape (Hs, Ws, B)
            W·m⁻²·sr⁻¹·nm⁻¹.
        """
        return np.tensordot(basis, self.coefficients.astype(np.float32), axes=([0], [0]))

    # -- optics ---------------------------------------------------------------------------------------
    def transfer(self, camera: CameraSpec,
                 settings: sopt.OpticsSettings) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[int, int]]:
        """Per basis element and channel, the band-weighted optical transfer ``(K, N, Hs, Wf)``:
        ``Σ_b W[b,k]·c[m,b]·OTF_b`` — the spatial optics of :func:`spectracam.experiments.spatial.optics.channel_spectra`
        applied to a basis instead of a cube (one FFT per basis element instead of one per band).

        Parameters
        ----------
        camera : CameraSpec
            Its band weights, pixel pitch and f-number.
        settings : OpticsSettings
            Diffraction and defocus.

        Returns
        -------
        transfer : ndarray, shape (K, N, Hs, Ws//2+1)
            Per basis element and channel.
        fy, fx : ndarray
            The frequencies, cycles per sub-pixel, ``(Hs, 1)`` and ``(1, Ws//2+1)``.
        shape : tuple of int
            ``(Hs, Ws)``.
        """
        key = (repr(camera.to_dict()), settings)
        if key not in self._transfer:
            Hs, Ws = self.geometry.height_px * self.supersampling, self.geometry.width_px * self.supersampling
            s_um = camera.sensor.pixel_pitch_um / self.supersampling
            fy = sfft.fftfreq(Hs)[:, None]
            fx = sfft.rfftfreq(Ws)[None, :]
            rho = np.sqrt(fx**2 + fy**2) / s_um
            W = band_weights(camera, self.grid).astype(np.float64)            # (B, N)
            C = self.coefficients.astype(np.float64)                           # (K, B)
            common = sopt.defocus_otf(rho, settings.defocus_um) if settings.defocus_um > 0 else 1.0
            Hk = np.zeros((C.shape[0], W.shape[1], Hs, fx.shape[1]))
            for b, lam in enumerate(self.grid.centres_nm):
                otf = (sopt.diffraction_otf(rho, lam, camera.optics.f_number) if settings.diffraction else 1.0) * common
                for k in range(W.shape[1]):
                    for m in range(C.shape[0]):
                        if C[m, b] * W[b, k] != 0.0:
                            Hk[m, k] += (C[m, b] * W[b, k]) * otf
            self._transfer = {key: (Hk, fy, fx, (Hs, Ws))}
        return self._transfer[key]


# ------------------------------------------------------------------------------------------------

@dataclass
class Integrated:
    """Each channel group's time-averaged basis, and how it was sampled in time."""

    groups: list                    # [(channels tuple, (K, Hs, Ws) float64)]
    slice_times_s: np.ndarray
    slice_dt_s: float
    samples_per_slice: int
    info: dict = field(default_factory=dict)


def slice_times(motion: Motion, timing: CaptureTiming, geometry: CameraGeometry, max_step_px: float = 0.25,
                slices: int = 0) -> tuple[np.ndarray, float]:
    """``(t_j, Δt)``: slice centres covering the capture's span (see the module).

    Parameters
    ----------
    motion : Motion
        Its fastest image speed over the span sets the step.
    timing : CaptureTiming
        The capture's windows: their span, and the shortest one.
    geometry : CameraGeometry
        The image (its half-diagonal, px, bounds a rotation's speed) and its object pixel, mm.
    max_step_px : float
        The most the image moves between slices, px (before halving for the shortest window).
    slices : int
        A set number of slices evenly over the span instead (0: by ``max_step_px``).

    Returns
    -------
    t : ndarray
        Slice centres, s (0 = the middle of the capture).
    dt : float
        The slices' spacing, s.
    """
    lo, hi = timing.span_s
    if slices > 0:
        dt = (hi - lo) / slices
        return lo + dt * (np.arange(slices) + 0.5), dt
    radius = 0.5 * math.hypot(geometry.width_px, geometry.height_px)
    speed = motion.max_image_speed_px_per_s(geometry.object_pixel_mm, radius, (lo, hi))
    if speed <= 0 or hi - lo <= 0:
        return np.array([0.0]), max(hi - lo, 1e-12)
    dt = max_step_px / speed
    shortest = float(np.min(timing.duration_s))
    if shortest > 0 and dt > shortest / MIN_SLICES_PER_WINDOW:   # halve the step: its positions stay shared
        dt /= 2.0 ** math.ceil(math.log2(dt * MIN_SLICES_PER_WINDOW / shortest))
    j = np.arange(int(math.floor(lo / dt + 0.5)), int(math.floor(hi / dt + 0.5)) + 1)
    return j * dt, dt


def integrate(scene: MovingScene, motion: Motion, timing: CaptureTiming, max_step_px: float = 0.25,
              slices: int = 0, samples_per_subpixel: int = 16) -> Integrated:
    """Render the slices and integrate each channel group's window (see the module). ``timing`` must
    cover the rows of ``scene.geometry`` (margin included).

    Parameters
    ----------
    scene : MovingScene
        Renders the target at each slice's pose.
    motion : Motion
        The target's poses in time.
    timing : CaptureTiming
        The channels' windows, per row.
    max_step_px : float
        The most the image moves between slices, px (:func:`slice_times`).
    slices : int
        A set number of slices instead (0: by ``max_step_px``).
    samples_per_subpixel : int
        Mitsuba's samples per sub-pixel, shared among the slices (at least 1 each).

    Returns
    -------
    Integrated
        Each channel group's time-averaged basis, the slice times and spacing, s, and the samples per slice.

    Raises
    ------
    SpectracamError
        When ``timing``'s rows are not the rendered image's.
    """
    g = scene.geometry
    ss = scene.supersampling
    if timing.row_delay_s.size != g.height_px:
        raise SpectracamError(f"timing: {timing.row_delay_s.size} rows, the rendered image has {g.height_px}")
    t, dt = slice_times(motion, timing, g, max_step_px, slices)
    spp = max(1, samples_per_subpixel // t.size)
    lo, hi = t - dt / 2, t + dt / 2
    if t.size == 1:
        lo, hi = np.array([timing.span_s[0]]), np.array([timing.span_s[1]])
    poses = motion.poses(t, timing.span_s, g.object_pixel_mm)
    groups = timing.groups()
    accs = [None] * len(groups)
    for j in range(t.size):
        # each group's share of slice j per image row (a row's shares over all slices sum to 1); one
        # slice at a time, so that memory does not grow with the number of slices
        cols = [np.repeat(timing.overlap_s(chans[0], lo[j:j + 1], hi[j:j + 1])[:, 0] / timing.duration_s[chans[0]],
                          ss) for chans in groups]
        if not any(col.any() for col in cols):
            continue
        B = scene.basis(poses[j], spp)
        for i, col in enumerate(cols):
            if not col.any():
                continue
            term = B * col[None, :, None].astype(np.float32)
            accs[i] = term.astype(np.float64) if accs[i] is None else accs[i] + term
    out = list(zip(groups, accs))
    return Integrated(out, t, dt, spp, {"slices": int(t.size), "slice_dt_ms": 1e3 * dt, "samples_per_slice": spp})


def channel_rates(scene: MovingScene, integrated: Integrated, camera: CameraSpec,
                  settings: sopt.OpticsSettings, margin_px: int,
                  workers: int | None = -1) -> np.ndarray:
    """``(H, W, N)`` time-averaged photo-electrons per second per pixel of each channel (the margin cut).

    Parameters
    ----------
    scene : MovingScene
        Its optical transfer per basis element (:meth:`MovingScene.transfer`).
    integrated : Integrated
        The channel groups' time-averaged bases (:func:`integrate`).
    camera : CameraSpec
        The camera.
    settings : OpticsSettings
        Its spatial optics.
    margin_px : int
        Pixels cut from every side.
    workers : int or None
        scipy.fft's workers (−1: every core).

    Returns
    -------
    ndarray, shape (H, W, N)
        e⁻/s.
    """
    Hk, fy, fx, shape = scene.transfer(camera, settings)
    spectra = np.zeros((Hk.shape[1], shape[0], fx.shape[1]), np.complex128)
    for chans, acc in integrated.groups:
        Fm = sfft.rfft2(acc, axes=(1, 2), workers=workers)                   # (K, Hs, Wf)
        for k in chans:
            spectra[k] = np.einsum("mij,mij->ij", Fm, Hk[:, k])
    return sopt.sample_channels(spectra, fy, fx, shape, scene.supersampling, camera.sensor.fill_factor,
                                settings.shifts_px, margin_px, workers, settings.olpf_separation_px)


def ideal_radiance(scene: MovingScene, spp: int, margin_px: int) -> np.ndarray:
    """``(H, W, B)``: the static target at the reference pose (t = 0), each pixel's footprint (no optics).

    Parameters
    ----------
    scene : MovingScene
        The target.
    spp : int
        Mitsuba's samples per sub-pixel.
    margin_px : int
        Pixels cut from every side.

    Returns
    -------
    ndarray, shape (H, W, B)
        Band radiance averaged over each pixel, W·m⁻²·sr⁻¹·nm⁻¹.
    """
    B = scene.basis((0.0, 0.0, 0.0), spp)
    ss = scene.supersampling
    K, Hs, Ws = B.shape
    px = B.reshape(K, Hs // ss, ss, Ws // ss, ss).mean(axis=(2, 4), dtype=np.float64)
    px = px[:, margin_px:px.shape[1] - margin_px, margin_px:px.shape[2] - margin_px]
    return np.tensordot(px, scene.coefficients, axes=([0], [0]))


__all__ = ["Integrated", "MovingScene", "RENDER_MODES", "channel_rates", "ideal_radiance", "integrate",
           "posed_coverage", "posed_edge", "slice_times"]
