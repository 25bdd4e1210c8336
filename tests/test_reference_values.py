"""Option tests against published reference values that do not come from the library spectracam uses.

* CIEDE2000: the 34 test pairs of G. Sharma, W. Wu, E. N. Dalal, "The CIEDE2000 color-difference
  formula: implementation notes, supplementary test data, and mathematical observations",
  Color Res. Appl. 30(1):21-30, 2005, Table 1 (``tests/data/ciede2000_sharma2005.csv``).
* Chromatic adaptation: the von Kries adaptation M⁻¹·diag(ρ'/ρ)·M built here by hand from the
  published cone-response matrices, written below as literals.
"""
from pathlib import Path

import numpy as np

from spectracam.processing.color import adaptation_matrix
from spectracam.core.cielab import delta_e

SHARMA_2005 = Path(__file__).parent / "data" / "ciede2000_sharma2005.csv"

# Bradford cone-response matrix: K. M. Lam, "Metamerism and colour constancy", PhD thesis, University
# of Bradford, 1985; as given in R. W. G. Hunt, M. R. Pointer, "Measuring Colour", and by
# B. Lindbloom, "Chromatic Adaptation" (brucelindbloom.com), linear (von Kries) form.
M_BRADFORD = np.array(
    [
        [0.8951, 0.2664, -0.1614],
        [-0.7502, 1.7135, 0.0367],
        [0.0389, -0.0685, 1.0296],
    ]
)

# CAT02: CIE 159:2004, "A colour appearance model for colour management systems: CIECAM02"
# (N. Moroney et al., IS&T/SID 10th Color Imaging Conference, 2002).
M_CAT02 = np.array(
    [
        [0.7328, 0.4296, -0.1624],
        [-0.7036, 1.6975, 0.0061],
        [0.0030, 0.0136, 0.9834],
    ]
)


def load_sharma_table() -> np.ndarray:
    """``(34, 7)`` array: L1, a1, b1, L2, a2, b2, ΔE00 (the CSV's ``pair`` column dropped)."""
    lines = [ln for ln in SHARMA_2005.read_text().splitlines() if ln.strip() and not ln.startswith("#")]
    header, body = lines[0].split(","), lines[1:]
    assert header == ["pair", "L1", "a1", "b1", "L2", "a2", "b2", "dE00"]
    table = np.array([[float(v) for v in ln.split(",")] for ln in body])
    assert table.shape == (34, 8)
    assert np.array_equal(table[:, 0], np.arange(1, 35))
    return table[:, 1:]


def von_kries_by_hand(cone: np.ndarray, white_from: np.ndarray, white_to: np.ndarray) -> np.ndarray:
    """M⁻¹ · diag(ρ_to / ρ_from) · M, the matrix carrying XYZ (column vectors) from white_from to white_to."""
    rho_from, rho_to = cone @ white_from, cone @ white_to
    return np.linalg.inv(cone) @ np.diag(rho_to / rho_from) @ cone


def test_ciede2000_sharma_table():
    table = load_sharma_table()
    lab1, lab2, expected = table[:, 0:3], table[:, 3:6], table[:, 6]

    got = np.asarray(delta_e(lab1, lab2, "ciede2000"))
    assert got.shape == (34,)
    bad = np.flatnonzero(np.abs(got - expected) > 1e-4)
    assert bad.size == 0, [(int(i) + 1, float(got[i]), float(expected[i])) for i in bad]

    euclid = np.sqrt(((lab1 - lab2) ** 2).sum(axis=1))
    np.testing.assert_allclose(np.asarray(delta_e(lab1, lab2, "cie1976")), euclid, rtol=0, atol=1e-12)


def test_bradford_adaptation_by_hand():
    import colour

    ccs = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]
    white_from = np.asarray(colour.xy_to_XYZ(ccs["A"]), float)
    white_to = np.asarray(colour.xy_to_XYZ(ccs["D65"]), float)
    assert np.isclose(white_from[1], 1.0) and np.isclose(white_to[1], 1.0)

    bradford = von_kries_by_hand(M_BRADFORD, white_from, white_to)
    cat02 = von_kries_by_hand(M_CAT02, white_from, white_to)
    # The hand-built matrix maps the source white onto the destination white.
    np.testing.assert_allclose(bradford @ white_from, white_to, rtol=0, atol=1e-12)
    assert np.abs(bradford - cat02).max() > 1e-3  # the two transforms are told apart at this tolerance

    got = np.asarray(adaptation_matrix(white_from, white_to, "bradford"), float)
    assert got.shape == (3, 3)
    np.testing.assert_allclose(got, bradford, rtol=0, atol=1e-9)
    assert np.abs(got - cat02).max() > 1e-3

    scaling = np.asarray(adaptation_matrix(white_from, white_to, "xyz_scaling"), float)
    np.testing.assert_allclose(scaling, np.diag(white_to / white_from), rtol=0, atol=1e-12)
