"""The reference packing fractions a 3D run's φ is read against."""

from __future__ import annotations

from regopack.packing.phi_references import PHI_REFERENCES_3D, references_3d, references_row


def test_the_references_run_from_loosest_to_densest_and_read_as_ranges_or_values() -> None:
    lows = [r.low for r in PHI_REFERENCES_3D]
    assert lows == sorted(lows) and all(0 < r.low <= r.high < 0.75 for r in PHI_REFERENCES_3D)
    assert PHI_REFERENCES_3D[0].text() == "random sequential addition 0.36–0.40"
    assert PHI_REFERENCES_3D[-1].text() == "random close packing 0.64"
    assert references_3d()[1] == {
        "label": "Williams–Philipse", "low": 0.61, "high": 0.61, "particles": "spheres"
    }  # fmt: skip
    assert references_row().count(";") == len(PHI_REFERENCES_3D) - 1
