"""Statistics against values computed by hand on a small constructed frame.

Frame 10 (frame 20 is the same with every energy doubled):

    type 1: u = 1, 2, 3, 4   radius 1, 1, 2, 2 mm   u_equal = 1.5, 2, 3, 4   u_radius = 1, 2, 3, 3
    type 2: u = 0, 10        radius 4, 4 mm         u_equal = 0, 9.5         u_radius = 0, 11
    contacts: u_n sum 24, u_t sum 4 (28 J); wall 0 holds 8 J

Type 1 by hand: total 10, mean 2.5, std sqrt((1.5^2+0.5^2+0.5^2+1.5^2)/4) = sqrt(1.25);
quantiles (type 7, position 3p): p05 1.15, p25 1.75, p50 2.5, p75 3.25, p95 3.85;
top 1% and top 10% = the largest value (ceil(0.04) = ceil(0.4) = 1): 4/10;
Gini = ((-3)1 + (-1)2 + (1)3 + (3)4)/(4*10) = 10/40 = 0.25.
Type 2: total 10, mean 5, std 5, quantiles at position p: 0.5, 2.5, 5, 7.5, 9.5;
top shares 10/10 = 1; Gini = 10/(2*10) = 0.5 = (n-1)/n.
Misattribution: type 1 equal (10.5-10)/10 = +5 %, radius (9-10)/10 = -10 %;
type 2 equal (9.5-10)/10 = -5 %, radius (11-10)/10 = +10 %.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from demsplit.errors import DemsplitError
from demsplit.results import Results
from demsplit.results.aggregate import gini, size_bins, top_share

U = np.array([1.0, 2, 3, 4, 0, 10])
TYPE = np.array([1, 1, 1, 1, 2, 2])
RADIUS = np.array([1e-3, 1e-3, 2e-3, 2e-3, 4e-3, 4e-3])
U_EQUAL = np.array([1.5, 2, 3, 4, 0, 9.5])
U_RADIUS = np.array([1.0, 2, 3, 3, 0, 11])


def frame(step: int, scale: float) -> dict:
    n = len(U)
    d = np.array([1e-6, 2e-6, 1e-6, 1e-6])
    cp = np.zeros((4, 3))
    sim = np.array([[0.5e-6, 0, 0], [0, 0, 0], [0.6 * 0.3e-6, 0.8 * 0.3e-6, 0], [np.nan] * 3])
    return {
        "particles": {
            "step": np.full(n, step),
            "id": np.arange(1, n + 1),
            "type": TYPE,
            "radius": RADIUS,
            "u": scale * U,
            "u_n": 0.8 * scale * U,
            "u_t": 0.2 * scale * U,
            "u_equal": scale * U_EQUAL,
            "u_radius": scale * U_RADIUS,
            "n_contacts": np.ones(n, int),
        },
        "contacts": {
            "step": np.full(4, step),
            "id1": np.array([1, 2, 3, 4]),
            "id2": np.array([2, 3, 4, -1]),
            "wall": np.array([-1, -1, -1, 0]),
            "delta": d,
            "u_n": np.full(4, 6.0 * scale),
            "u_t": np.full(4, 1.0 * scale),
            "cpx": cp[:, 0],
            "cpy": cp[:, 1],
            "cpz": cp[:, 2],
            "cpx_sim": sim[:, 0],
            "cpy_sim": sim[:, 1],
            "cpz_sim": sim[:, 2],
        },
        "walls": {
            "step": np.array([step]),
            "wall": np.array([0]),
            "u": np.array([8.0 * scale]),
            "u_n": np.array([7.0 * scale]),
            "u_t": np.array([1.0 * scale]),
            "n_contacts": np.array([1]),
        },
        "frames": {
            "step": np.array([step]),
            "time": np.array([step * 1e-5]),
            "n_particles": np.array([n]),
            "n_contacts": np.array([3]),
            "n_wall_contacts": np.array([1]),
            "u_n": np.array([24.0 * scale]),
            "u_t": np.array([4.0 * scale]),
            "overlap_max_rel_error": np.array([np.nan]),
        },
    }


@pytest.fixture
def results() -> Results:
    return Results.from_frames(
        [frame(10, 1.0), frame(20, 2.0)], walls_meta=[{"wall": 0, "name": "floor", "kind": "plane", "type": 3}]
    )


def test_per_type_by_hand(results):
    t = results.per_type().set_index(["step", "type"])
    one = t.loc[(10, 1)]
    assert one["count"] == 4 and one["total"] == 10 and one["mean"] == 2.5
    assert one["std"] == pytest.approx(math.sqrt(1.25), rel=1e-15)
    assert [one[q] for q in ("p05", "p25", "p50", "p75", "p95")] == pytest.approx(
        [1.15, 1.75, 2.5, 3.25, 3.85], rel=1e-14
    )
    assert one["top1_share"] == one["top10_share"] == pytest.approx(0.4, rel=1e-15)
    assert one["gini"] == pytest.approx(0.25, rel=1e-15)
    assert one["share_of_total"] == pytest.approx(0.5, rel=1e-15)
    two = t.loc[(10, 2)]
    assert (two["total"], two["mean"], two["std"]) == (10, 5, 5)
    assert [two[q] for q in ("p05", "p25", "p50", "p75", "p95")] == pytest.approx([0.5, 2.5, 5, 7.5, 9.5], rel=1e-14)
    assert two["top1_share"] == 1 and two["gini"] == pytest.approx(0.5, rel=1e-15)
    assert t.loc[(20, 1), "total"] == 20 and t.loc[(20, 1), "gini"] == pytest.approx(0.25, rel=1e-15)
    pooled = results.per_type(by_frame=False).set_index("type")
    assert pooled.loc[1, "count"] == 8 and pooled.loc[1, "total"] == 30
    assert results.per_type("u_t").set_index(["step", "type"]).loc[(10, 1), "total"] == pytest.approx(2.0)


def test_gini_and_top_share_definitions():
    x = np.arange(1.0, 21.0)
    assert top_share(x, 0.10) == pytest.approx(39 / 210, rel=1e-15)  # ceil(2) = 2 largest
    assert top_share(x, 0.01) == pytest.approx(20 / 210, rel=1e-15)
    mean_abs_diff = np.abs(x[:, None] - x[None, :]).mean()
    assert gini(x) == pytest.approx(mean_abs_diff / (2 * x.mean()), rel=1e-14)
    assert gini(np.full(7, 3.0)) == 0
    assert math.isnan(gini(np.zeros(3))) and math.isnan(top_share(np.array([]), 0.1))


def test_split_comparison_by_hand(results):
    s = results.split_comparison().set_index(["step", "type"])
    assert s.loc[(10, 1), "total_material"] == 10 and s.loc[(10, 1), "total_equal"] == 10.5
    assert s.loc[(10, 1), "misattribution_equal_pct"] == pytest.approx(5.0, rel=1e-13)
    assert s.loc[(10, 1), "misattribution_radius_pct"] == pytest.approx(-10.0, rel=1e-13)
    assert s.loc[(20, 2), "misattribution_equal_pct"] == pytest.approx(-5.0, rel=1e-13)
    assert s.loc[(20, 2), "misattribution_radius_pct"] == pytest.approx(10.0, rel=1e-13)
    assert s.loc[(10, 2), "gini_radius"] == pytest.approx(0.5, rel=1e-15)


def test_per_size_explicit_and_default_bins(results):
    p = results.per_size(bins=[0.5e-3, 1.5e-3, 3e-3, 5e-3]).set_index(["step", "size_class"])
    assert p.loc[(10, 0), "total"] == 3 and p.loc[(10, 1), "total"] == 7 and p.loc[(10, 2), "total"] == 10
    assert (p.loc[(10, 1), "r_lo"], p.loc[(10, 1), "r_hi"]) == (1.5e-3, 3e-3)
    edges = size_bins(RADIUS)
    assert len(edges) == 9 and edges[0] == 1e-3 and edges[-1] == pytest.approx(4e-3, rel=1e-15)
    np.testing.assert_allclose(np.diff(np.log(edges)), np.log(4) / 8, rtol=1e-12)
    d = results.per_size()
    assert d.groupby("step")["total"].sum().tolist() == [20, 40]  # every particle in a class
    assert d.groupby("step")["count"].sum().tolist() == [6, 6]
    # sorted radii 1 1 2 2 4 4 mm, quantile k/4 at position 5k/4: 1, 1.25, 2, 3.5, 4 mm
    np.testing.assert_allclose(size_bins(RADIUS, "quantile:4"), [1e-3, 1.25e-3, 2e-3, 3.5e-3, 4e-3], rtol=1e-14)
    with pytest.raises(DemsplitError, match="outside the size bins"):
        results.per_size(bins=[1e-3, 2e-3])


def test_per_frame_balance_and_walls(results):
    f = results.per_frame().set_index("step")
    assert f.loc[10, "u_contacts"] == 28 and f.loc[10, "u_particles"] == 20 and f.loc[10, "u_walls"] == 8
    assert f.loc[10, "balance_rel_error"] == 0 and f.loc[20, "u_contacts"] == 56
    assert f.loc[20, "gini"] == pytest.approx(gini(U), rel=1e-15)
    w = results.wall_energy()
    assert w["name"].tolist() == ["floor", "floor"]
    assert w["share"].tolist() == pytest.approx([8 / 28, 16 / 56], rel=1e-15)


def test_contact_point_shift_by_hand(results):
    c = results.contact_point_shift().set_index(["step", "kind"])
    pair = c.loc[(10, "pair")]
    assert pair["count"] == 3 and pair["n_missing"] == 0
    assert pair["median"] == pytest.approx(0.3, rel=1e-12)
    assert pair["p95"] == pytest.approx(0.48, rel=1e-12)  # sorted 0, 0.3, 0.5 at position 1.9
    assert pair["max"] == pytest.approx(0.5, rel=1e-12)
    wall = c.loc[(10, "wall")]
    assert wall["count"] == 0 and wall["n_missing"] == 1 and math.isnan(wall["median"])
    no_sim = Results.from_frames(
        [
            {
                k: ({c: v for c, v in t.items() if not c.endswith("_sim")} if k == "contacts" else t)
                for k, t in frame(10, 1.0).items()
            }
        ]
    )
    with pytest.raises(DemsplitError, match="no simulator contact point"):
        no_sim.contact_point_shift()


def test_printed_half_unit_reads_the_dump_precision_from_the_values():
    from demsplit.results.aggregate import printed_half_unit

    g = np.array([0.0123457, -1.5, 2.5e-5, 0.0])  # as %g prints them: 6 significant digits at most
    np.testing.assert_allclose(printed_half_unit(g), [5e-8, 5e-6, 5e-11, 0.0], rtol=1e-12)
    full = np.array([0.1 + 0.2, 1 / 3])  # 17 digits: full precision, no print bound
    assert np.all(printed_half_unit(full) == 0)
