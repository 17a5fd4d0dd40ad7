"""The split's expected error in the results (issue "[7 of 7]"): per contact a/R1, a/R2 and the fitted
finite-element model's expected share error, per particle the expected error of its normal energy,
``--split corrected``, and the summary's accuracy line."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import SAMPLES
from demsplit import analyze
from demsplit.cli import main
from demsplit.compute import Options
from demsplit.physics.accuracy import corrected_share, expected_share_error

PACKING = SAMPLES / "liggghts" / "packing" / "in.packing"


@pytest.fixture(scope="module")
def material():
    return analyze(PACKING)


@pytest.mark.slow
def test_contact_radius_ratios_and_expected_error(material):
    c = material.contacts  # (ids and delta; the radii come from the particles table)
    p = material.particles.set_index(["step", "id"])
    r1 = p.loc[list(zip(c["step"], c["id1"])), "radius"].to_numpy()
    pair = c["wall"].to_numpy() < 0
    rb = np.full(len(c), np.inf)
    rb[pair] = p.loc[list(zip(c["step"][pair], c["id2"][pair])), "radius"].to_numpy()
    a = np.sqrt(np.maximum(c["delta"], 0) / (1 / r1 + 1 / rb))
    np.testing.assert_allclose(c["a_over_r1"], a / r1, rtol=1e-13)
    np.testing.assert_allclose(c["a_over_r2"], np.where(pair, a / rb, 0.0), rtol=1e-13, atol=0)
    assert (c["share_n1_error"] != 0).any() and np.all(np.abs(c["share_n1_error"]) < 0.05)


def test_equal_bodies_have_no_expected_error():
    x = np.array([0.05, 0.1])
    assert np.all(expected_share_error(x, x, 0.3, 0.3, 1e9, 1e9) == 0)
    assert np.all(corrected_share(x, x, 0.3, 0.3, 1e9, 1e9) == 0.5)


def test_particle_errors_add_up_to_the_wall_side(material):
    c, pt = material.contacts, material.particles
    wall = c["wall"] >= 0
    for step in material.steps:
        on_walls = (c["share_n1_error"] * c["u_n"])[wall & (c["step"] == step)].sum()
        assert pt.loc[pt["step"] == step, "u_n_error"].sum() == pytest.approx(on_walls, rel=1e-9, abs=1e-25)


@pytest.mark.slow
def test_corrected_split_moves_exactly_the_expected_error(material):
    corrected = analyze(PACKING, options=Options(split="corrected"))
    np.testing.assert_allclose(
        corrected.particles["u"], material.particles["u"] + material.particles["u_n_error"], rtol=1e-12, atol=1e-24
    )
    np.testing.assert_array_equal(corrected.contacts["u_n"], material.contacts["u_n"])  # energies unchanged
    assert corrected.provenance["options"]["split"] == "corrected"
    f = corrected.frames
    total = f["u_n"] + f["u_t"]
    assert np.all(np.abs(f["u_particles"] + f["u_walls"] - total) <= 1e-12 * total)


@pytest.mark.slow
def test_summary_says_how_far_the_split_can_be_trusted(tmp_path, capsys):
    out = tmp_path / "r.h5"
    assert main(["run", str(PACKING), "-o", str(out), "-q"]) == 0
    assert main(["report", str(out)]) == 0
    text = capsys.readouterr().out
    assert "Accuracy of the split (material" in text and "beyond the Hertz range a/R > 0.1" in text
    assert "0 beyond the model's fit a/R > 0.3" in text
    assert main(["run", str(PACKING), "-o", str(tmp_path / "n.h5"), "-q", "--no-accuracy"]) == 0


def test_accuracy_line_counts_the_contacts_beyond_the_fit():
    """A contact with a/R > 0.3 (the fit's edge) gets the model's value at the edge: the summary says how many."""
    import pandas as pd
    from demsplit.results.report import accuracy_line

    contacts = pd.DataFrame(
        {
            "u_n": [1.0, 2.0, 3.0],
            "share_n1_error": [0.001, -0.02, 0.03],
            "a_over_r1": [0.05, 0.2, 0.31],
            "a_over_r2": [0.05, 0.35, 0.0],
        }
    )
    line = accuracy_line(contacts, "material")
    assert "2 contact(s) beyond the Hertz range" in line and "2 beyond the model's fit a/R > 0.3" in line
    assert "83.3% of the normal energy in contacts beyond 1 % expected error" in line


def test_per_type_expected_error_is_energy_weighted(material):
    t = material.per_type()
    p = material.raw.particles  # the statistics sum what is known of each particle
    for _, row in t.iterrows():
        sub = p[(p["step"] == row["step"]) & (p["type"] == row["type"])]
        assert row["expected_error"] == pytest.approx(sub["u_n_error"].sum() / sub["u"].sum(), rel=1e-12)
