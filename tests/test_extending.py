"""Adding a contact law is adding one class, and adding a reader is adding one file and its test.

The laws below are defined in this file and registered for its tests only (the registry-wide tests of
tests/test_laws.py run on them too, through its own functions); the toy reader is ``tests/toy_run.py``, one
file, registered when a test imports it. Nothing else in demsplit is told about them: the LIGGGHTS word map
(``model toy_spring``), the script property the law reads (``toySpringStiffness``), ``open_run``, the
pipeline, the store and the exports find them through the registries.
"""

from __future__ import annotations

import importlib
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import test_laws
from demsplit import analyze, load_results
from demsplit.cli import main
from demsplit.physics import laws
from demsplit.physics.elastic import hooke_energy, overlap
from demsplit.physics.laws import ContactLaw, ContactRows, LawEnergy
from demsplit.physics.laws._liggghts import LiggghtsNormalModel
from demsplit.readers import REGISTRY, open_run
from demsplit.results.exports.tables import export_tables
from reader_contract import ReaderContract

SAMPLES = Path(__file__).resolve().parent.parent / "sample_dumps"


class ToyLinear(ContactLaw):
    """A linear normal spring and nothing else: u_n = k delta^2/2 (J), F_n = k delta (N)."""

    key = "toy:linear"
    summary = "a toy linear spring, u_n = k delta^2/2"
    modes = ("u_n",)
    parameters = {"stiffness": (ContactLaw.REQUIRED, "the spring's stiffness k (N/m)")}
    example_params = {"stiffness": 2e4}

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        return LawEnergy({"u_n": hooke_energy(rows.delta, self.params["stiffness"])})

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return self.params["stiffness"] * overlap(rows.delta)


class ToySpring(LiggghtsNormalModel):
    """A LIGGGHTS-style normal model with the sub-models of every LIGGGHTS model: u_n = k delta^2/2, the tangential
    history with kt = k, k from the script's ``fix property/global toySpringStiffness scalar K``."""

    key = "liggghts:toy_spring"
    summary = "a toy LIGGGHTS spring, u_n = k delta^2/2, kt = k"
    parameters = {
        **LiggghtsNormalModel.parameters,
        "toy_stiffness": (ContactLaw.REQUIRED, "toySpringStiffness k (N/m)"),
    }
    simulator_parameters = {**LiggghtsNormalModel.simulator_parameters, "toySpringStiffness": "toy_stiffness"}
    example_params = {"toy_stiffness": 3e4}

    def kn(self, rows: ContactRows) -> np.ndarray:
        return np.full(rows.delta.shape, float(self.params["toy_stiffness"]))

    kt = kn

    def normal_energy(self, rows: ContactRows) -> np.ndarray:
        return hooke_energy(rows.delta, self.kn(rows))

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return self.kn(rows) * overlap(rows.delta)


@pytest.fixture(scope="module", autouse=True)
def registered():
    """The two laws and the toy reader registered while this module's tests run, and removed after."""
    for law in (ToyLinear, ToySpring):
        laws.register(law)
    toy = importlib.import_module("toy_run")
    REGISTRY[toy.ToyRun.format_name] = toy.ToyRun  # registered when first imported; again after a teardown
    yield toy
    for law in (ToyLinear, ToySpring):
        del laws._REGISTRY[law.key]
    del REGISTRY[toy.ToyRun.format_name]


def toy_file(path: Path, stiffness: float = 2e4) -> Path:
    """Two frames of three spheres in a row, the middle one pressed into both others."""
    lines = ["TOY 1", f"law toy:linear stiffness={stiffness!r}", "material 1 7e10 0.22", "material 2 3e9 0.35"]
    for step, squeeze in ((100, 1e-5), (200, 3e-5)):
        lines += [
            f"step {step}",
            "p 1 1 0.0 0.0 0.0 0.001",
            f"p 2 2 {0.0025 - squeeze!r} 0.0 0.0 0.0015",
            f"p 3 1 {0.005 - 2 * squeeze!r} 0.0 0.0 0.001",
            "c 1 2",
            "c 2 3",
        ]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("key", ["toy:linear", "liggghts:toy_spring"])
def test_a_law_defined_here_keeps_the_registry_wide_properties(key):
    assert key in laws.supported()
    for check in (
        test_laws.test_declarations,
        test_laws.test_model_round_trips_through_the_scene_dict,
        test_laws.test_energy_is_finite_and_not_negative,
        test_laws.test_no_energy_without_overlap,
        test_laws.test_normal_force_is_the_derivative_of_the_normal_energy,
        test_laws.test_swapping_the_bodies_swaps_the_shares,
        test_laws.test_conservation_per_mode,
        test_laws.test_a_mode_the_law_lacks_is_zero_and_said,
    ):
        check(key)


@pytest.mark.slow
def test_the_toy_reader_and_law_are_read_computed_stored_and_exported(tmp_path):
    path = toy_file(tmp_path / "run.toy")
    with open_run(path) as run:
        assert type(run).format_name == "toy" and run.scene.model.law == "toy:linear"
        delta = np.concatenate([f.contacts["delta"] for f in run])
    out = tmp_path / "out.h5"
    assert main(["run", str(path), "-o", str(out), "-q"]) == 0
    res = load_results(out)
    np.testing.assert_allclose(res.contacts["u_n"], 0.5 * 2e4 * delta**2, rtol=1e-14)
    assert (res.contacts["u_t"] == 0).all()  # the law has no tangential spring: 0, and said
    # the split is the materials': body 1 (E 7e10) takes c1/(c1 + c2) of each contact's energy
    c1, c2 = (1 - 0.22**2) / 7e10, (1 - 0.35**2) / 3e9
    share = np.where(res.contacts["id1"] == 1, c1 / (c1 + c2), c2 / (c1 + c2))
    np.testing.assert_allclose(res.contacts["u1"], share * res.contacts["u_n"], rtol=1e-14)
    written = export_tables(res, tmp_path / "csv", "csv")
    back = pd.read_csv(next(p for p in written if p.name == "contacts.csv"))
    np.testing.assert_array_equal(back["u_n"].to_numpy(), res.contacts["u_n"].to_numpy())


def test_the_command_line_takes_a_readers_options_from_the_reader(tmp_path, capsys):
    """The toy reader's one option is on the command line, reaches its constructor, and is refused for an input
    of another reader, by name."""
    path = toy_file(tmp_path / "run.toy")
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    assert "--toy-stiffness K" in capsys.readouterr().out
    assert main(["run", str(path), "-o", str(tmp_path / "k.h5"), "-q", "--toy-stiffness", "5000"]) == 0
    res = load_results(tmp_path / "k.h5")
    np.testing.assert_allclose(res.contacts["u_n"], 0.5 * 5000 * res.contacts["delta"] ** 2, rtol=1e-14)
    packing = SAMPLES / "liggghts" / "packing" / "in.packing"
    assert main(["check", str(packing), "-q", "--toy-stiffness", "5000"]) == 2
    assert "--toy-stiffness does not apply to a LIGGGHTS input script" in capsys.readouterr().err


@pytest.mark.slow
def test_a_liggghts_law_is_found_by_its_word_and_reads_its_script_property(tmp_path):
    """``pair_style gran model toy_spring`` in a copy of the packing sample: the pairs are the new law's, with
    k from the script; the walls keep their own hertz fixes."""
    run = tmp_path / "packing"
    shutil.copytree(SAMPLES / "liggghts" / "packing", run)
    script = run / "in.packing"
    text = script.read_text()
    assert "pair_style      gran model hertz tangential history" in text
    script.write_text(
        text.replace(
            "pair_style      gran model hertz tangential history",
            "fix toy all property/global toySpringStiffness scalar 1500.0\n"
            "pair_style      gran model toy_spring tangential history",
        )
    )
    res = analyze(script)
    assert res.provenance["model"]["law"] == "liggghts:toy_spring"
    assert res.provenance["model"]["params"]["toy_stiffness"] == 1500.0
    pairs = res.contacts[res.contacts["wall"] < 0]
    np.testing.assert_allclose(pairs["u_n"], 0.5 * 1500.0 * pairs["delta"].clip(lower=0) ** 2, rtol=1e-14)
    assert main(["check", str(script), "-q"]) in (0, 1)  # the check runs on the new law (its verdict is the run's)


class TestToyRunContract(ReaderContract):
    """The shared reader contract, held by the toy reader of tests/toy_run.py."""

    @pytest.fixture
    def run_path(self, registered, tmp_path) -> Path:
        type(self).reader = registered.ToyRun
        return toy_file(tmp_path / "run.toy")
