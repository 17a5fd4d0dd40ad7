"""The output-path policy, for every command that writes: an output that is (or leads to) an input, a
directory, a device or an empty name is refused before anything is written, and the input is untouched."""

from __future__ import annotations

import hashlib
import os
import shutil
from pathlib import Path

import pytest
from demsplit.cli import main

SAMPLES = Path(__file__).resolve().parent.parent / "sample_dumps"


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture
def packing(tmp_path):
    shutil.copytree(SAMPLES / "liggghts" / "packing", tmp_path / "packing")
    return tmp_path / "packing"


def aliases(tmp_path: Path, target: Path) -> dict[str, Path]:
    """Other names of ``target``: a symbolic link, a hard link and a path through '..'."""
    (tmp_path / "link.h5").symlink_to(target)
    os.link(target, tmp_path / "hard.h5")
    return {
        "itself": target,
        "symlink": tmp_path / "link.h5",
        "hard link": tmp_path / "hard.h5",
        "dot-dot": target.parent / ".." / target.parent.name / target.name,
    }


INPUTS = ["in.packing", "atoms_full.txt.gz", "pairs_full.txt.gz", "wall_full.txt.gz"]


def test_the_inputs_are_what_the_run_reads(packing):
    from demsplit.readers import open_run

    with open_run(packing / "in.packing") as run:
        assert sorted(Path(s).name for s in run.sources) == sorted(INPUTS)


@pytest.mark.parametrize("which", INPUTS)
@pytest.mark.parametrize("alias", ["itself", "symlink", "hard link", "dot-dot"])
def test_run_never_writes_over_an_input(packing, tmp_path, capsys, which, alias):
    target = packing / which
    before = digest(target)
    out = aliases(tmp_path, target)[alias]
    assert main(["run", str(packing / "in.packing"), "-o", str(out), "-q"]) == 2
    assert "one of the run's inputs" in capsys.readouterr().err
    assert digest(target) == before and not (tmp_path / ".link.h5.partial").exists()


@pytest.mark.parametrize("command", ["run", "convert"])
@pytest.mark.parametrize(
    "out, message",
    [
        ("", "empty"),
        ("/dev/null", "not a regular file"),
        ("{dir}", "a directory"),
        ("{dir}/no/such/dir/x.h5", "does not exist"),
    ],
)
def test_outputs_that_are_not_new_or_regular_files_are_refused(packing, tmp_path, capsys, command, out, message):
    out = out.format(dir=tmp_path)
    assert main([command, str(packing / "in.packing"), "-o", out, "-q"]) == 2
    assert message in capsys.readouterr().err
    assert os.path.exists("/dev/null") and not Path("/dev/null").is_file()  # the device is still a device


def test_convert_report_and_export_never_write_over_their_input(packing, tmp_path, capsys):
    run_input = packing / "in.packing"
    before = digest(run_input)
    assert main(["convert", str(run_input), "-o", str(run_input), "-q"]) == 2
    assert digest(run_input) == before
    store = tmp_path / "out.h5"
    assert main(["run", str(run_input), "-o", str(store), "-q"]) == 0
    stored = digest(store)
    assert main(["report", str(store), "-o", str(store), "-q"]) == 2
    os.link(store, tmp_path / "particles.csv")
    assert main(["export", str(store), "--csv", str(tmp_path), "-q"]) == 2
    assert "one of the run's inputs" in capsys.readouterr().err
    assert digest(store) == stored


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux /proc")
def test_a_system_error_on_the_output_side_is_one_message_naming_the_path(packing, capsys):
    """/proc refuses new files: an OSError of the system, exit 2 with the path, not an internal error."""
    assert main(["run", str(packing / "in.packing"), "-o", "/proc/demsplit-out.h5", "-q"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("demsplit: error: /proc/") and "internal error" not in err and err.count("\n") == 1


def test_a_second_run_on_a_live_output_is_told_another_run_writes_it(packing, tmp_path, capsys):
    """Not to delete the live run's work (which it used to suggest): the lock's owner is alive."""
    import subprocess
    import sys

    from demsplit.results.store import work_dir_of

    out = tmp_path / "out.h5"
    live = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        work = work_dir_of(out)
        work.mkdir()
        (work / "lock").write_text(str(live.pid))
        assert main(["run", str(packing / "in.packing"), "-o", str(out), "-q"]) == 2
        err = capsys.readouterr().err
        assert f"another demsplit process (pid {live.pid}) is writing this store" in err and "delete" not in err
        assert (work / "lock").read_text() == str(live.pid)  # the live run's work is untouched
    finally:
        live.kill()
        live.wait()


@pytest.mark.parametrize("which", ["floor.stl", "atoms.txt", "atoms.bin", "pairs.txt", "wall.txt", "extra.in"])
def test_run_and_convert_never_write_over_a_file_the_script_names_but_does_not_read(packing, tmp_path, capsys, which):
    """The mesh file, the dumps of lower precision the run does not read, an included file: files of the run,
    protected like its inputs (they were replaced by the store, exit 0)."""
    (packing / "extra.in").write_text("variable extra equal 1\n")
    script = packing / "in.packing"
    script.write_text("include extra.in\n" + script.read_text())
    target = packing / which
    before = digest(target)
    names = aliases(tmp_path, target)
    for command in ("run", "convert"):
        for out in names.values():
            assert main([command, str(script), "-o", str(out), "-q"]) == 2
            assert "one of the run's inputs" in capsys.readouterr().err
    assert digest(target) == before


# --- a full disk ---------------------------------------------------------------------------------------------

H5_NO_SPACE = (
    "Can't synchronously write data (file write failed: time = Thu Nov 26 04:21:00 2026, filename = "
    "'store.h5', file descriptor = 7, errno = 28, error message = 'No space left on device', buf = "
    "0x55d0, total write size = 8192, bytes this sub-write = 8192, bytes actually written = "
    "18446744073709551615, offset = 0)"
)
"""What h5py raises when the disk fills under HDF5: an OSError without errno, the cause inside its text."""


@pytest.mark.parametrize("failing_commit", [1, 2])
def test_a_full_disk_is_one_message_with_the_path_and_a_rerun_works(
    packing, tmp_path, capsys, monkeypatch, failing_commit
):
    """ENOSPC inside HDF5 at the first frame's commit: exit 2 naming the output and the cause, nothing left
    behind, and a plain rerun works (it was refused as 'interrupted'). At a later commit: the committed frames
    are kept for --resume, said so, and --resume completes."""
    from demsplit.results import store, writer

    real, calls = writer.ResultWriter._commit, []

    def full(self):
        self._fill_digests(wait=True)  # every frame committed, whatever the pace of the background hashing
        calls.append(1)
        if len(calls) == failing_commit:
            raise OSError(H5_NO_SPACE)
        return real(self)

    out = tmp_path / "out.h5"
    monkeypatch.setattr(writer.ResultWriter, "_commit", full)
    assert main(["run", str(packing / "in.packing"), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"demsplit: error: {out}: cannot write the store: No space left on device")
    assert err.count("\n") == 1 and "internal error" not in err
    monkeypatch.setattr(writer.ResultWriter, "_commit", real)
    if failing_commit == 1:
        assert sorted(p.name for p in tmp_path.iterdir()) == ["packing"]  # nothing left behind
        assert main(["run", str(packing / "in.packing"), "-o", str(out), "-q"]) == 0
    else:
        assert f"the 1 frame(s) committed before it are kept in {store.work_dir_of(out)} for --resume" in err
        assert main(["run", str(packing / "in.packing"), "-o", str(out), "-q"]) == 2  # not silently discarded
        assert "--resume" in capsys.readouterr().err
        assert main(["run", str(packing / "in.packing"), "-o", str(out), "-q", "--resume"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.h5", "packing"]


def _mount_tmpfs(where: Path, size: str, remount: bool = False) -> bool:
    import subprocess

    options = f"remount,size={size}" if remount else f"size={size}"
    return (
        subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(where)], capture_output=True).returncode
        == 0
    )


@pytest.mark.skipif(
    not hasattr(os, "geteuid") or os.geteuid() != 0 or not shutil.which("mount"),
    reason="mounts a small tmpfs (root only)",
)
@pytest.mark.parametrize("size", ["200k", "400k"])
def test_a_real_full_file_system(packing, tmp_path, capsys, size):
    """The output on a tmpfs too small for the store: exit 2 naming the output and the cause; nothing left
    behind, or the committed frames for --resume; with space, the rerun (or --resume) writes the store."""
    import subprocess

    full = tmp_path / "full"
    full.mkdir()
    if not _mount_tmpfs(full, size):
        pytest.skip("cannot mount a tmpfs here")
    try:
        out = full / "out.h5"
        run = ["run", str(packing / "in.packing"), "-o", str(out), "-q"]
        assert main(run) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"demsplit: error: {out}: cannot write the store: ") and err.count("\n") == 1
        assert "No space left on device" in err or "the file system is full" in err
        left = sorted(p.name for p in full.iterdir())
        # whether a frame was committed before the disk filled depends on when the inputs' digests were known
        # (the first commit waits for them); the simulated ENOSPC test covers both cases deterministically
        kept = "for --resume" in err
        assert left == ([".out.h5.partial"] if kept else [])
        assert _mount_tmpfs(full, "50m", remount=True)
        assert main(run + (["--resume"] if kept else [])) == 0
        assert sorted(p.name for p in full.iterdir()) == ["out.h5"]
    finally:
        subprocess.run(["umount", str(full)], capture_output=True)


@pytest.mark.skipif(
    not hasattr(os, "geteuid") or os.geteuid() != 0 or not shutil.which("mount"),
    reason="mounts a read-only tmpfs and makes a device node (root only)",
)
def test_a_read_only_file_system_and_a_device_node_are_one_message(packing, tmp_path, capsys):
    """-o on a read-only file system: exit 2 naming the output and the cause (an OSError of the system, not
    an internal error); -o onto a device node with /dev/null's numbers in a temporary directory: refused, the
    node stays a node (it was replaced by a regular file, as /dev/full was)."""
    import stat
    import subprocess

    ro = tmp_path / "ro"
    ro.mkdir()
    if not _mount_tmpfs(ro, "1m,ro"):
        pytest.skip("cannot mount a tmpfs here")
    try:
        assert main(["run", str(packing / "in.packing"), "-o", str(ro / "out.h5"), "-q"]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"demsplit: error: {ro}") and "Read-only file system" in err and err.count("\n") == 1
        assert list(ro.iterdir()) == []
    finally:
        subprocess.run(["umount", str(ro)], capture_output=True)
    node = tmp_path / "null.h5"
    os.mknod(node, stat.S_IFCHR | 0o666, os.makedev(1, 3))
    for argv in (["run", str(packing / "in.packing")], ["convert", str(packing / "in.packing")]):
        assert main([*argv, "-o", str(node), "-q"]) == 2
        assert "not a regular file" in capsys.readouterr().err
    st = os.lstat(node)
    assert stat.S_ISCHR(st.st_mode) and st.st_rdev == os.makedev(1, 3)


# --- one policy for every file a command writes (issue [6 of 7] and the outputs of [5 of 7]) --------------------


@pytest.fixture(scope="module")
def analysed(tmp_path_factory):
    """The packing run (a copy) and its store, made once: ``(run directory, store)``."""
    root = tmp_path_factory.mktemp("analysed")
    shutil.copytree(SAMPLES / "liggghts" / "packing", root / "packing")
    store = root / "out.h5"
    assert main(["run", str(root / "packing" / "in.packing"), "-o", str(store), "-q"]) == 0
    return root / "packing", store


def tree(directory: Path) -> dict[str, str]:
    """Every file below ``directory`` -> its sha256."""
    return {str(p.relative_to(directory)): digest(p) for p in sorted(directory.rglob("*")) if p.is_file()}


@pytest.mark.parametrize(
    "argv",
    [
        ["report", "{store}", "-o", "{run}/in.packing"],
        ["report", "{store}", "-o", "{run}/atoms.txt"],
        ["export", "{store}", "--dump", "{run}/atoms.txt"],
        ["export", "{store}", "--dump", "{run}/in.packing"],
        ["export", "{store}", "--dump", "{run}/floor.stl"],
    ],
    ids=[
        "report over the script",
        "report over a dump the script names",
        "export --dump over that dump",
        "export --dump over the script",
        "export --dump over the mesh",
    ],
)
@pytest.mark.parametrize("overwrite", [[], ["--overwrite"]], ids=["", "--overwrite"])
def test_report_and_export_never_write_over_a_file_of_the_run(analysed, capsys, argv, overwrite):
    """The run's inputs and every file its script names, as the store's provenance lists them, are never
    written, --overwrite or not (they were turned into HTML or a dump, exit 0)."""
    run, store = analysed
    before = tree(run)
    assert main([a.format(store=store, run=run) for a in argv] + overwrite + ["-q"]) == 2
    err = capsys.readouterr().err
    assert "one of the run's inputs or files its script names" in err and err.count("\n") == 1
    assert tree(run) == before


def _without_dumps(packing: Path) -> Path:
    """The packing script with its dump lines removed: prepare then adds its own."""
    script = packing / "in.packing"
    script.write_text("".join(line for line in script.read_text().splitlines(True) if not line.startswith("dump")))
    return script


@pytest.mark.parametrize("target", ["floor.stl", "in.packing"])
def test_prepare_never_writes_over_a_file_the_script_names(packing, capsys, target):
    """prepare -o onto the mesh the script names (it was replaced by the prepared script, exit 0)."""
    script = _without_dumps(packing)
    before = tree(packing)
    for overwrite in ([], ["--overwrite"]):
        assert main(["prepare", str(script), "-o", str(packing / target), "-q", *overwrite]) == 2
        assert "one of the run's inputs or files its script names" in capsys.readouterr().err
    assert tree(packing) == before


def test_prepare_replaces_its_own_output_but_not_an_edited_one(packing, capsys):
    """A prepared script demsplit wrote is replaced by the next prepare; once edited, it is refused (it was
    replaced without a word) unless --overwrite."""
    script = _without_dumps(packing)
    out = packing / "in.packing.demsplit"
    assert main(["prepare", str(script), "-q"]) == 0
    assert "compute dsPair" in out.read_text()
    assert main(["prepare", str(script), "-q"]) == 0  # its own, unedited: replaced
    out.write_text(out.read_text() + "# my own edit\n")
    edited = digest(out)
    assert main(["prepare", str(script), "-q"]) == 2
    err = capsys.readouterr().err
    assert "not a script written by demsplit prepare and not edited since" in err and "--overwrite" in err
    assert digest(out) == edited
    assert main(["prepare", str(script), "-q", "--overwrite"]) == 0
    assert "# my own edit" not in out.read_text()


@pytest.mark.parametrize("command", ["run", "convert", "report", "export --dump"])
def test_an_existing_file_that_is_not_of_the_commands_kind_is_refused(analysed, tmp_path, capsys, command):
    """-o onto a file that is no file of the run but not one demsplit writes either (the user's original
    script, beside the prepared copy that is the run; their notes): refused, named, untouched, exit 2; with
    --overwrite it is replaced. A file of the command's own kind is replaced without --overwrite."""
    run, store = analysed
    original = tmp_path / "in.original"
    original.write_text("# the user's original script\n")
    argv = {
        "run": ["run", str(run / "in.packing"), "-o"],
        "convert": ["convert", str(run / "in.packing"), "-o"],
        "report": ["report", str(store), "-o"],
        "export --dump": ["export", str(store), "--dump"],
    }[command]
    assert main([*argv, str(original), "-q"]) == 2
    err = capsys.readouterr().err
    assert str(original) in err and "exists and is not a" in err and "--overwrite" in err and err.count("\n") == 1
    assert original.read_text() == "# the user's original script\n"
    assert main([*argv, str(original), "-q", "--overwrite"]) == 0
    assert main([*argv, str(original), "-q"]) == 0  # now the command's own kind: replaced
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.original"]


@pytest.mark.parametrize("fmt", ["--csv", "--vtk"])
def test_an_export_into_a_folder_of_other_files_is_refused(analysed, tmp_path, capsys, fmt):
    """export --csv DIR into a folder of STL files wrote its tables among them; refused unless --overwrite,
    which keeps the other files."""
    run, store = analysed
    folder = tmp_path / "meshes"
    folder.mkdir()
    shutil.copy(run / "floor.stl", folder / "floor.stl")
    assert main(["export", str(store), fmt, str(folder), "-q"]) == 2
    err = capsys.readouterr().err
    assert "holds files that are not a demsplit export, such as 'floor.stl'" in err and err.count("\n") == 1
    assert sorted(p.name for p in folder.iterdir()) == ["floor.stl"]
    assert main(["export", str(store), fmt, str(folder), "-q", "--overwrite"]) == 0
    assert (folder / "floor.stl").read_bytes() == (run / "floor.stl").read_bytes()
    assert len(list(folder.iterdir())) > 2


def test_an_export_replaces_an_earlier_export_of_its_kind_whole(analysed, tmp_path, capsys):
    """export --vtk into the folder of another run's VTK export: the new series alone is left (the other
    run's frames were left beside it, one series of two simulations); into a CSV export, refused."""
    _, store = analysed
    other = tmp_path / "yade.h5"
    assert main(["run", str(SAMPLES / "yade" / "mindlin_box.h5"), "-o", str(other), "-q"]) == 0
    vtk = tmp_path / "vtk"
    assert main(["export", str(other), "--vtk", str(vtk), "-q"]) == 0
    assert main(["export", str(store), "--vtk", str(vtk), "-q"]) == 0
    fresh = tmp_path / "fresh"
    assert main(["export", str(store), "--vtk", str(fresh), "-q"]) == 0
    assert tree(vtk) == tree(fresh)
    csv = tmp_path / "csv"
    assert main(["export", str(other), "--csv", str(csv), "-q"]) == 0
    assert main(["export", str(store), "--vtk", str(csv), "-q"]) == 2
    assert "holds a demsplit csv export, not a vtk one" in capsys.readouterr().err
    assert main(["export", str(store), "--csv", str(csv), "-q"]) == 0
    assert (csv / "particles.csv").read_bytes() == _csv_of(store, tmp_path / "csv2")


def _csv_of(store: Path, folder: Path) -> bytes:
    assert main(["export", str(store), "--csv", str(folder), "-q"]) == 0
    return (folder / "particles.csv").read_bytes()


@pytest.mark.parametrize("fmt, failing", [("--csv", 3), ("--vtk", 2)])
def test_an_export_on_a_full_disk_leaves_the_folder_as_it_was_and_names_the_file(
    analysed, tmp_path, capsys, monkeypatch, fmt, failing
):
    """ENOSPC while the export writes its files: exit 2 naming the file it was writing; nothing of the new
    export is left (half the tables were, and the message named no file), an earlier export is kept whole."""
    import errno

    import meshio
    import pandas as pd

    _, store = analysed
    folder = tmp_path / "export"
    assert main(["export", str(store), fmt, str(folder), "-q"]) == 0
    before = tree(folder)
    calls = []
    real = pd.DataFrame.to_csv if fmt == "--csv" else meshio.write

    def full(*args, **kwargs):
        calls.append(1)
        if len(calls) == failing:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(*args, **kwargs)

    monkeypatch.setattr(*((pd.DataFrame, "to_csv") if fmt == "--csv" else (meshio, "write")), full)
    for target in (folder, tmp_path / "new"):
        calls.clear()
        assert main(["export", str(store), fmt, str(target), "-q"]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"demsplit: error: {target}/") and "No space left on device" in err
        assert err.count("\n") == 1
    assert tree(folder) == before and not (tmp_path / "new").exists()


def test_a_refused_run_leaves_nothing_and_the_rerun_it_suggests_works(packing, tmp_path, capsys):
    """A run refused at a later frame (%g dumps whose positions cannot give the overlaps) kept its earlier
    frames in a hidden work directory, and the rerun with the option the message suggests was refused as the
    resumption of an 'interrupted run', naming resume=True."""
    out = tmp_path / "out.h5"
    argv = [
        "run",
        str(packing / "in.packing"),
        "--atoms",
        str(packing / "atoms.txt"),
        "--contacts",
        str(packing / "pairs.txt"),
        "--walls",
        str(packing / "wall.txt"),
        "-o",
        str(out),
        "-q",
    ]
    assert main(argv) == 2
    assert "--force-positions" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["packing"]
    assert main([*argv, "--force-positions"]) == 0


def test_an_interrupted_run_is_told_to_resume_with_the_cli_option(tmp_path, capsys):
    """Only an interruption keeps frames; its message names the command-line option, not Python's resume=True."""
    from demsplit.results.writer import ResultWriter
    from result_frames import PROVENANCE, WALLS_META, synthetic_frame

    out = tmp_path / "out.h5"
    writer = ResultWriter(out, PROVENANCE, walls_meta=WALLS_META)
    writer.append(synthetic_frame(0))
    writer.abandon()  # what Ctrl-C leaves
    assert main(["run", str(SAMPLES / "yade" / "mindlin_box.h5"), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert "an interrupted run left its finished frames" in err and "--resume" in err and "resume=True" not in err


def test_warnings_obey_quiet(tmp_path):
    """A library's warning (matplotlib's on a frame without energy) reached stderr under -q."""
    import subprocess
    import sys

    from demsplit.results.writer import ResultWriter
    from result_frames import PROVENANCE, WALLS_META, synthetic_frame

    store = tmp_path / "empty.h5"
    with ResultWriter(store, PROVENANCE, walls_meta=WALLS_META) as w:
        w.append(synthetic_frame(0, n_pairs=0, n_wall_contacts=0))
    argv = [sys.executable, "-m", "demsplit.cli", "report", str(store), "-o", str(tmp_path / "r.html")]
    quiet = subprocess.run([*argv, "-q"], capture_output=True, text=True, timeout=300)
    assert quiet.returncode == 0 and quiet.stdout == "" and quiet.stderr == ""
    loud = subprocess.run(argv, capture_output=True, text=True, timeout=300)
    assert loud.returncode == 0 and "Warning" in loud.stderr  # shown without -q
