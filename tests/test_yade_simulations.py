"""YADE saved states as users give them: one run is one simulation, every file given is read or refused by name, the
converted-state cache is keyed and checked by content, YADE has a time limit, and the messages and the report name
the user's states (docs/yade.md, "One run, one simulation"; docs/reliability.md).

sample_dumps/yade/simulations.py saves the states of several small YADE simulations (its header lists them): a
facet box to which a lid is added and from which a facet is erased, a state of it saved twice and one changed
after it was saved, the same box with other radii, a box of clumps, and a law demsplit does not analyse.
"""

from __future__ import annotations

import bz2
import gzip
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import demsplit
import pytest
from conftest import require_program
from demsplit.cli import main
from demsplit.errors import InputFormatError
from demsplit.physics.shares import normal_share
from demsplit.readers import open_run
from demsplit.readers.yade_snapshot import _open_store
from demsplit.readers.yade_state import cache_key, convert_states, state_files
from demsplit.results.report import write_html
from demsplit.runtime.hashing import file_digest
from demsplit.yade import write_snapshot
from test_yade_simulator import SAMPLE_SCRIPTS, run_yade

pytestmark = pytest.mark.simulator

DIGEST = r"[0-9a-f]{64}"


@pytest.fixture(scope="module")
def sims(tmp_path_factory) -> Path:
    """The states of simulations.py, each converted once (one YADE process) into ``sims/cache``."""
    yade = require_program("yade")
    out = tmp_path_factory.mktemp("simulations")
    run_yade(yade, SAMPLE_SCRIPTS / "simulations.py", out)
    converted, failed = convert_states(state_files(out), out / "cache")
    assert len(converted) == 9 and not failed
    return out


def run(sims: Path, out: Path, *inputs: str | Path, cache: Path | None = None, extra: tuple = ()) -> int:
    """``demsplit run`` of ``inputs`` (names in ``sims``, or paths) into ``out/r.h5`` with the converted states of
    ``cache`` (default: those of the fixture)."""
    out.mkdir(exist_ok=True)
    return main(
        [
            "run",
            *(str(sims / i) for i in inputs),
            "-o",
            str(out / "r.h5"),
            "-q",
            "--state-cache",
            str(cache or sims / "cache"),
            *extra,
        ]
    )


def one_error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("demsplit: error: ") and err.count("\n") == 1, err
    return err


def test_the_states_of_two_simulations_are_refused_naming_both(sims, tmp_path, capsys):
    """A box of clumps and a box of facets (the same law and materials; other bodies under the same ids), and the
    facet box built again with other radii: each pair is refused, naming both states and the body that differs;
    nothing is written."""
    for k, (other, differs) in enumerate((("clumps-004500.yade.gz", "in clump"), ("seed-003000.yade.gz", "radius"))):
        out = tmp_path / str(k)
        assert run(sims, out, "facets-003000.yade.gz", other) == 2
        err = one_error(capsys)
        assert "facets-003000.yade.gz" in err and other in err and "two simulations" in err and differs in err
        assert "body 0 is a Sphere" in err
        assert list(out.iterdir()) == []


def test_one_simulation_whose_bodies_change_is_one_run(sims, tmp_path):
    """A lid (a Wall of an inline material) added after iteration 6000 and a facet erased after 9000: one run, each
    wall in exactly the frames whose state has it, the lid named, of its kind and material, its share of a
    contact that of its own material."""
    assert run(sims, tmp_path, "facets-*") == 0
    res = demsplit.load_results(tmp_path / "r.h5")
    assert res.steps.tolist() == [3000, 6000, 9000, 12000]
    scene = res.provenance["scene"]
    walls = scene["walls"]
    kinds = [w["kind"] for w in walls]
    assert kinds == ["facet"] * 10 + ["yade_wall"]
    lid, erased = len(walls) - 1, 0  # the Wall has the largest id; the box's first facet is erased
    assert walls[lid]["name"].endswith("(yade_wall)")
    lid_material = scene["materials"][str(walls[lid]["type"])]
    assert (lid_material["E"], lid_material["nu"]) == (5e8, 0.25)
    assert lid_material["name"].startswith("inline FrictMat of body")
    present = {int(s): sorted(g["wall"].tolist()) for s, g in res.walls.groupby("step")}
    every = list(range(1, 10))
    assert present == {3000: [0, *every], 6000: [0, *every], 9000: [0, *every, lid], 12000: [*every, lid]}
    assert not res.walls.isna().any().any()
    at_lid = res.contacts[(res.contacts["step"] == 9000) & (res.contacts["wall"] == lid)]
    assert len(at_lid) > 0 and (at_lid["u_n"] > 0).all()
    particles = res.particles[res.particles["step"] == 9000].set_index("id")
    for _, c in at_lid.iterrows():
        own = scene["materials"][str(int(particles.loc[int(c["id1"]), "type"]))]
        assert c["share_n1"] == pytest.approx(float(normal_share(own["E"], own["nu"], 5e8, 0.25)), rel=1e-12)
    notes = " ".join(res.provenance["notes"])
    assert f"{walls[lid]['name']} at iterations 9000..12000" in notes
    assert f"{walls[erased]['name']} at iterations 3000..9000" in notes


def test_an_iteration_given_twice(sims, tmp_path, capsys):
    """Two different states of iteration 6000 (a velocity changed after the save): refused naming both, nothing
    left, and --resume finds nothing to resume. The same state saved twice (binary, then XML): read once, with a
    note."""
    assert run(sims, tmp_path / "a", "facets-006000.yade.gz", "changed-006000.yade.gz") == 2
    err = one_error(capsys)
    assert "iteration 6000 is in two different states" in err
    assert "facets-006000.yade.gz" in err and "changed-006000.yade.gz" in err and "done_steps" not in err
    assert list((tmp_path / "a").iterdir()) == []
    assert run(sims, tmp_path / "a", "facets-006000.yade.gz", "changed-006000.yade.gz", extra=("--resume",)) == 2
    assert "two different states" in one_error(capsys)
    assert run(sims, tmp_path / "b", "facets-006000.yade.gz", "again-006000.xml.bz2", "facets-003000.yade.gz") == 0
    res = demsplit.load_results(tmp_path / "b" / "r.h5")
    assert res.steps.tolist() == [3000, 6000]
    assert any(
        "again-006000.xml.bz2 is the same state as" in n and "facets-006000.yade.gz" in n
        for n in res.provenance["notes"]
    )


def test_a_bad_file_among_the_states_is_refused_by_name_or_skipped_and_listed(sims, tmp_path, capsys):
    """In a glob of states: an empty file, a gzip stream cut in half and a gzip of text, all named like states, and
    an XML state cut in half that YADE fails to load: the run is refused naming the first, or with --on-bad-frame
    skip each is left out and listed with why (an ingest cache keeps them as frames that raise it); a file not
    named like a state (notes.txt) is not one. An empty state given alone is said to be one."""
    d = tmp_path / "states"
    d.mkdir()
    for name in ("facets-003000.yade.gz", "facets-006000.yade.gz"):
        shutil.copy(sims / name, d / name)
    data = (sims / "facets-009000.yade.gz").read_bytes()
    (d / "facets-007000.yade.gz").write_bytes(b"")
    (d / "facets-008000.yade.gz").write_bytes(data[: len(data) // 2])
    (d / "facets-010000.yade.gz").write_bytes(gzip.compress(b"not a state\n" * 20))
    (d / "notes.txt").write_text("run by hand\n")
    assert run(sims, tmp_path / "a", d / "facets-*") == 2
    err = one_error(capsys)
    assert err.startswith(f"demsplit: error: {d / 'facets-007000.yade.gz'}: the file is empty")
    assert list((tmp_path / "a").iterdir()) == []
    ingest = tmp_path / "ingest.h5"  # the ingest cache keeps the bad states as frames that raise their error
    assert main(["convert", str(d / "facets-*"), "-o", str(ingest), "-q", "--state-cache", str(sims / "cache")]) == 0
    with open_run(ingest) as cached:
        assert len(cached) == 5 and cached.steps.tolist() == [3000, 6000]
        with pytest.raises(InputFormatError, match="facets-007000.yade.gz: the file is empty"):
            cached.frame(2)
    text = bz2.decompress((sims / "again-006000.xml.bz2").read_bytes())
    (d / "facets-011000.xml").write_bytes(text[: len(text) // 2])
    assert run(sims, tmp_path / "b", d, extra=("--on-bad-frame", "skip")) == 0
    res = demsplit.load_results(tmp_path / "b" / "r.h5")
    assert res.steps.tolist() == [3000, 6000]
    bad = {b["error"].split(":")[0]: b["error"] for b in res.provenance["bad_frames"]}
    assert sorted(bad) == [
        str(d / f"facets-{n}") for n in ("007000.yade.gz", "008000.yade.gz", "010000.yade.gz", "011000.xml")
    ]
    assert "the file is empty" in bad[str(d / "facets-007000.yade.gz")]
    assert "gzip stream is cut short" in bad[str(d / "facets-008000.yade.gz")]
    assert "is not a boost archive" in bad[str(d / "facets-010000.yade.gz")]
    assert "YADE could not load" in bad[str(d / "facets-011000.xml")]
    assert run(sims, tmp_path / "c", d / "facets-007000.yade.gz") == 2
    err = one_error(capsys)
    assert "the file is empty: it is not a YADE saved state" in err and "LIGGGHTS" not in err


def _cached_copy(cache: Path, state: Path) -> Path:
    (path,) = cache.glob(f"{cache_key(state)}-*.npys")
    return path


@pytest.mark.parametrize("damage", ["edited", "cut"])
def test_the_cache_is_keyed_and_checked_by_content(sims, tmp_path, damage):
    """A converted state edited in the cache (radii x 1.01, the file rewritten valid), or cut short as a full disk
    leaves it: it is not trusted but converted again, and the results and their provenance are those of the first
    run."""
    cache = tmp_path / "cache"
    shutil.copytree(sims / "cache", cache)
    states = ("facets-003000.yade.gz", "facets-006000.yade.gz")
    assert run(sims, tmp_path / "a", *states, cache=cache) == 0
    first = demsplit.load_results(tmp_path / "a" / "r.h5")
    copy = _cached_copy(cache, sims / states[1])
    if damage == "edited":
        meta, tables = _open_store(copy).snapshot(0)
        tables["bodies"]["radius"] = tables["bodies"]["radius"] * 1.01
        copy.unlink()
        write_snapshot(copy, meta, tables, format="npy")
    else:
        copy.write_bytes(copy.read_bytes()[: copy.stat().st_size // 2])
    assert run(sims, tmp_path / "b", *states, cache=cache) == 0
    again = demsplit.load_results(tmp_path / "b" / "r.h5")
    for table in ("particles", "contacts", "walls"):
        a, b = getattr(first, table), getattr(again, table)
        assert a.equals(b), table
    assert again.provenance["run"]["converted"] == first.provenance["run"]["converted"]
    for path in cache.iterdir():
        assert path.name.endswith(f"-{file_digest(path)}.npys")


@pytest.mark.skipif(
    not hasattr(os, "geteuid") or os.geteuid() != 0 or not shutil.which("mount"),
    reason="mounts a small tmpfs (root only)",
)
def test_a_cache_on_a_full_disk_leaves_nothing_a_later_run_trusts(sims, tmp_path, capsys):
    """The cache on a tmpfs too small for a converted state: exit 2 naming the cache's file and the cause, nothing
    left on the file system; with space, the rerun converts the state again and keeps it whole."""
    full = tmp_path / "full"
    full.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=16k", "tmpfs", str(full)]).returncode:
        pytest.skip("cannot mount a tmpfs here")
    try:
        assert run(sims, tmp_path / "a", "facets-003000.yade.gz", cache=full) == 2
        err = one_error(capsys)
        assert f"{full}/{cache_key(sims / 'facets-003000.yade.gz')}-" in err and "No space left on device" in err
        assert list(full.iterdir()) == []
        assert subprocess.run(["mount", "-t", "tmpfs", "-o", "remount,size=1m", "tmpfs", str(full)]).returncode == 0
        assert run(sims, tmp_path / "b", "facets-003000.yade.gz", cache=full) == 0
        (kept,) = full.iterdir()
        assert kept.name.endswith(f"-{file_digest(kept)}.npys")
    finally:
        subprocess.run(["umount", str(full)])


def test_yade_has_a_time_limit(sims, tmp_path, capsys):
    """A YADE that never returns, before its first state or inside one, and Debian's yade given less time than it
    needs to start: each is one message naming the state and --yade-timeout, in about the time given; the process
    is killed."""
    hang = tmp_path / "hang"
    hang.write_text(f"#!/bin/sh\necho $$ > {tmp_path / 'pid'}\nexec sleep 600\n")
    inside = tmp_path / "inside"
    inside.write_text("#!/bin/sh\necho DEMSPLIT-START 0 >&2\nexec sleep 600\n")
    for exe in (hang, inside):
        exe.chmod(0o755)
    fresh = tmp_path / "fresh"
    for k, (exe, limit, says) in enumerate(
        (
            (hang, "2", "before it loaded a state"),
            (inside, "1", "while it loaded and converted this state"),
            ("yade", "0.2", "before it loaded a state"),
        )
    ):
        start = time.monotonic()
        assert (
            run(
                sims,
                tmp_path / str(k),
                "facets-003000.yade.gz",
                cache=fresh,
                extra=("--yade", str(exe), "--yade-timeout", limit),
            )
            == 2
        )
        assert time.monotonic() - start < float(limit) + 15
        err = one_error(capsys)
        assert err.startswith(f"demsplit: error: {sims / 'facets-003000.yade.gz'}: ")
        assert f"timed out after {limit} s (--yade-timeout)" in err and says in err
    with pytest.raises(ProcessLookupError):
        os.kill(int((tmp_path / "pid").read_text()), 0)
    assert not fresh.exists()


def test_an_output_states_path_that_is_a_file_is_named(sims, tmp_path, capsys):
    """``OUTPUT.states``, where run keeps the converted states, is a file: one message naming it and the fix; the
    file is left as it was."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "r.h5.states").write_text("mine\n")
    assert main(["run", str(sims / "facets-003000.yade.gz"), "-o", str(out / "r.h5"), "-q"]) == 2
    err = one_error(capsys)
    assert err.startswith(f"demsplit: error: {out / 'r.h5.states'}: the directory of converted YADE states is a file")
    assert "--state-cache" in err
    assert (out / "r.h5.states").read_text() == "mine\n" and sorted(p.name for p in out.iterdir()) == ["r.h5.states"]


def test_messages_and_the_report_name_the_users_states(sims, tmp_path, capsys):
    """A state of a law demsplit does not analyse is refused naming the state, not its converted copy; the report's
    header names the states analysed."""
    assert run(sims, tmp_path / "a", "viscelcap-000020.yade.gz") == 2
    err = one_error(capsys)
    assert err.startswith(f"demsplit: error: {sims / 'viscelcap-000020.yade.gz'}, timestep 20: the InteractionLoop")
    assert not re.search(DIGEST, err)
    assert run(sims, tmp_path / "b", "facets-003000.yade.gz", "facets-006000.yade.gz") == 0
    write_html(demsplit.load_results(tmp_path / "b" / "r.h5"), tmp_path / "report.html")
    header = re.search(r"Run: ([^;]*);", (tmp_path / "report.html").read_text()).group(1)
    assert "facets-003000.yade.gz" in header and "facets-006000.yade.gz" in header
    assert not re.search(DIGEST, header) and ".npys" not in header


def test_a_refused_run_leaves_nothing_in_the_way(sims, tmp_path, capsys):
    """Refused before any state was converted (no yade): nothing is left. Refused after (two simulations): only the
    converted states stay next to the output, each named by its content, and the message says where; the next
    run reads them without YADE."""
    out = tmp_path / "out"
    out.mkdir()
    state = sims / "facets-003000.yade.gz"
    no_yade = str(Path(sys.executable).parent)  # this Python's bin: no yade on this PATH
    cli = [sys.executable, "-m", "demsplit.cli", "run", str(state), "-o", str(out / "r.h5"), "-q"]
    proc = subprocess.run(cli, capture_output=True, text=True, env={**os.environ, "PATH": no_yade}, timeout=300)
    assert proc.returncode == 2 and "apt-get install yade" in proc.stderr
    assert list(out.iterdir()) == []
    assert main(["run", str(state), str(sims / "clumps-004500.yade.gz"), "-o", str(out / "r.h5"), "-q"]) == 2
    assert f"(Converted states are kept in {out / 'r.h5.states'}.)" in one_error(capsys)
    assert [p.name for p in out.iterdir()] == ["r.h5.states"]
    kept = sorted((out / "r.h5.states").iterdir())
    assert len(kept) == 2 and all(p.name.endswith(f"-{file_digest(p)}.npys") for p in kept)
    proc = subprocess.run(cli, capture_output=True, text=True, env={**os.environ, "PATH": no_yade}, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in out.iterdir()) == ["r.h5", "r.h5.states"]


def test_info_describes_a_state_of_a_law_demsplit_does_not_analyse(sims, tmp_path, capsys, monkeypatch):
    """info says what the state holds (its iteration, bodies, interactions, law, materials, YADE build) and why
    run refuses it, instead of refusing to describe it."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    shutil.copytree(sims / "cache", tmp_path / "demsplit" / "yade-states")
    assert main(["info", str(sims / "viscelcap-000020.yade.gz")]) == 0
    text = capsys.readouterr().out
    for words in (
        "iteration 20",
        "2 spheres, walls 1 wall",
        "interactions: 2 real",
        "Law2_ScGeom_ViscElCapPhys_Basic (not one demsplit analyses)",
        "0: ViscElCapMat",
        "YADE:       2023.02a",
        "analysis:   refused",
        "exactly one of",
    ):
        assert words in text, words
