"""Issue 35: one architecture object.  Each architecture says what its channels are made of and what the filter
design varies for it; the design asks the object (never its name) and refuses, in one line, an architecture it
cannot model instead of designing it as RGB."""
import numpy as np
import pytest

from spectracam.architecture import ARCHITECTURES, MosaicArchitecture, complementary, make_architecture
from spectracam.architecture.filters import FilterSpec, responsivities
from spectracam.core.errors import SpectracamError
from spectracam.core.spectra import WavelengthGrid
from spectracam.experiments.design.variables import (channels_from_primaries, check_parametrisation,
                                                     design_architecture, designable)

GRID = WavelengthGrid(np.arange(400.0, 701.0, 10.0))
FILTER_ARCHITECTURES = ("cfa", "prism", "fsc", "cmy", "quad_bayer", "rgbw", "ryyb")


def _old_channels(name, R, clear, minimum):
    """design/variables.py's channels before issue 35, by name (every other name fell back to R, G, B)."""
    def pair(a, b):
        return minimum(R[a] + R[b], clear)

    return {"rgbw": lambda: [*R, clear], "ryyb": lambda: [R[0], pair(0, 1), R[2]],
            "cmy": lambda: [pair(1, 2), pair(0, 1), pair(0, 2)]}.get(name, lambda: list(R))()


def _old_responsivities(name, filters, grid):
    """The per-architecture responsivities before issue 35 (cmy.py, ryyb.py, rgbw.py overrode them)."""
    R = responsivities(filters, grid)
    if name == "cmy":
        return complementary(R, filters, grid, "GB", "RG", "RB")
    if name == "ryyb":
        return np.stack([R[0], complementary(R, filters, grid, "RG")[0], R[2]])
    if name == "rgbw":
        return np.concatenate([R, complementary(R, filters, grid, "W")])
    return R


@pytest.fixture
def plug_in():
    """An architecture whose channels are its own (not made of [filters]), registered for one test."""

    @ARCHITECTURES.register("own_curves")
    class OwnCurves(MosaicArchitecture):
        name = "own_curves"

        def responsivities(self, filters, grid):
            return np.ones((3, len(grid.centres_nm)))

    try:
        yield OwnCurves
    finally:
        ARCHITECTURES.unregister("own_curves")


def test_every_architecture_says_what_the_design_varies():
    answers = {n: cls.design_variables() for n, cls in ARCHITECTURES.items()}
    assert answers == {**{n: "filters" for n in FILTER_ARCHITECTURES}, "stacked": "depths"}
    assert designable() == tuple(ARCHITECTURES)
    for n in FILTER_ARCHITECTURES:   # one recipe per channel
        a = make_architecture(n)
        assert len(a.primaries) == len(a.channels)


@pytest.mark.parametrize("filters", [FilterSpec(), FilterSpec(kind="gaussian", ir_cut_nm=650.0)])
@pytest.mark.parametrize("name", FILTER_ARCHITECTURES)
def test_responsivities_from_the_primaries_are_those_of_before(name, filters):
    new = make_architecture(name).responsivities(filters, GRID)
    old = _old_responsivities(name, filters, GRID)
    assert new.dtype == old.dtype and new.shape == old.shape
    np.testing.assert_array_equal(new, old)


@pytest.mark.parametrize("name", FILTER_ARCHITECTURES)
def test_each_modellable_architecture_gives_the_design_variables_of_before(name):
    from spectracam.experiments.design.ad import backend, numpy, tensor

    try:
        dr, _ = backend()
    except SpectracamError as e:
        pytest.skip(str(e))
    rng = np.random.default_rng(7)
    R = [tensor(rng.uniform(0.0, 0.6, 31)) for _ in range(3)]
    clear = tensor(rng.uniform(0.3, 0.8, 31))
    old = _old_channels(name, R, clear, dr.minimum)
    for arch in (make_architecture(name), name):     # the object, or its registered name
        new = channels_from_primaries(arch, R, clear)
        assert len(new) == len(old) == len(make_architecture(name).channels)
        for a, b in zip(new, old):
            np.testing.assert_array_equal(numpy(a), numpy(b))


def test_an_architecture_the_design_cannot_model_is_refused_in_one_line(plug_in):
    for arch in (plug_in(), "own_curves"):
        with pytest.raises(SpectracamError) as e:
            design_architecture(arch)
        msg = str(e.value)
        assert "\n" not in msg and "'own_curves'" in msg and "cannot model" in msg
        assert msg.endswith("; it models " + ", ".join(n for n in ARCHITECTURES if n != "own_curves"))
        for call in (lambda: check_parametrisation("block", arch), lambda: channels_from_primaries(arch, [], None)):
            with pytest.raises(SpectracamError, match="^design: the 'own_curves' architecture makes its channels"):
                call()
    assert "own_curves" not in designable()


def test_an_unknown_architecture_is_refused_in_one_line():
    with pytest.raises(SpectracamError, match=r"^design: architecture 'bayer' is not registered; the design models "
                                              r"cfa, prism, fsc, .*stacked$"):
        check_parametrisation("block", "bayer")


def test_parametrisations_follow_what_the_architecture_is_designed_by():
    check_parametrisation("depths", make_architecture("stacked"))
    for p in ("block", "gaussian", "freeform"):
        check_parametrisation(p, make_architecture("rgbw"))
        with pytest.raises(SpectracamError, match=rf"^design: filters = '{p}' cannot design a stacked camera; "
                                                  r"stacked photodiodes are designed by 'depths'$"):
            check_parametrisation(p, "stacked")
    with pytest.raises(SpectracamError, match=r"^design: filters = 'depths' cannot design a cfa camera; 'depths' "
                                              r"designs stacked photodiodes only; use block, gaussian or freeform$"):
        check_parametrisation("depths", "cfa")


def test_the_stacked_architecture_reads_and_writes_its_depths():
    from spectracam.camera import CameraSpec

    cam = CameraSpec().with_design("stacked/single").replace(
        filters=FilterSpec(stacked_depths_um=(0.2, 0.6, 1.5, 3.0, 5.0)))
    arch = cam.architecture()
    assert arch.depths_um(cam.filters) == (0.2, 0.6, 1.5, 3.0, 5.0) and len(arch.channels) == 4
    f = arch.with_depths(cam.filters, np.array([0.245, 1.15, 2.61, 4.34]))
    assert f.stacked_depths_um == FilterSpec().stacked_depths_um
