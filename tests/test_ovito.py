"""The LAMMPS-style dump export opened by OVITO's Python module: the recipe of docs/visualization.md, and every
frame's positions and energies against the store."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from demsplit.cli import main
from demsplit.results import load_results
from demsplit.results.tables import with_not_computed_as_nan

ovito_io = pytest.importorskip("ovito.io")
from ovito.modifiers import ColorCodingModifier  # noqa: E402

SAMPLES = Path(__file__).resolve().parent.parent / "sample_dumps"


@pytest.mark.parametrize("run", ["liggghts/packing/in.packing", "yade/cundall_periodic.h5"])
def test_ovito_colours_the_particles_by_their_energy(run, tmp_path):
    store, dump = tmp_path / "out.h5", tmp_path / "particles.dump"
    assert main(["run", str(SAMPLES / run), "-o", str(store), "-q"]) == 0
    assert main(["export", str(store), "--dump", str(dump), "-q"]) == 0
    res = load_results(store)

    pipeline = ovito_io.import_file(str(dump))  # the recipe of docs/visualization.md
    pipeline.modifiers.append(ColorCodingModifier(property="u", gradient=ColorCodingModifier.Viridis()))
    assert pipeline.source.num_frames == len(res.steps)
    for k, step in enumerate(res.steps):
        data = pipeline.compute(k)
        frame = with_not_computed_as_nan(res.particles)[lambda df, s=step: df["step"] == s]  # nan: not computed
        p = data.particles
        np.testing.assert_array_equal(np.asarray(p["Particle Identifier"]), frame["id"].to_numpy())
        # %.17g text round-trips exactly in Python; OVITO's own number parser lands within an ulp or two
        np.testing.assert_allclose(np.asarray(p["Position"]), frame[["x", "y", "z"]].to_numpy(), rtol=1e-15)
        np.testing.assert_allclose(np.asarray(p["u"]), frame["u"].to_numpy(), rtol=1e-15)
        np.testing.assert_allclose(np.asarray(p["Radius"]), frame["radius"].to_numpy(), rtol=2**-23)  # float32
        colors = np.asarray(p["Color"])
        assert colors.shape == (len(frame), 3)
        u = frame["u"].to_numpy()
        if np.nanmax(u) > np.nanmin(u):  # the most and the least energetic particle get different colours
            assert not np.array_equal(colors[np.nanargmax(u)], colors[np.nanargmin(u)])
