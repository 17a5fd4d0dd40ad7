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
    return {"itself": target, "symlink": tmp_path / "link.h5", "hard link": tmp_path / "hard.h5",
            "dot-dot": target.parent / ".." / target.parent.name / target.name}


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
@pytest.mark.parametrize("out, message", [("", "empty"), ("/dev/null", "not a regular file"),
                                          ("{dir}", "a directory"), ("{dir}/no/such/dir/x.h5", "does not exist")])
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

H5_NO_SPACE = ("Can't synchronously write data (file write failed: time = Thu Nov 26 04:21:00 2026, filename = "
               "'store.h5', file descriptor = 7, errno = 28, error message = 'No space left on device', buf = "
               "0x55d0, total write size = 8192, bytes this sub-write = 8192, bytes actually written = "
               "18446744073709551615, offset = 0)")
"""What h5py raises when the disk fills under HDF5: an OSError without errno, the cause inside its text."""


@pytest.mark.parametrize("failing_commit", [1, 2])
def test_a_full_disk_is_one_message_with_the_path_and_a_rerun_works(packing, tmp_path, capsys, monkeypatch,
                                                                   failing_commit):
    """ENOSPC inside HDF5 at the first frame's commit: exit 2 naming the output and the cause, nothing left
    behind, and a plain rerun works (it was refused as 'interrupted'). At a later commit: the committed frames
    are kept for --resume, said so, and --resume completes."""
    from demsplit.results import store, writer

    real, calls = writer.ResultWriter._commit, []

    def full(self):
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
    return subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(where)],
                          capture_output=True).returncode == 0


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0 or not shutil.which("mount"),
                    reason="mounts a small tmpfs (root only)")
@pytest.mark.parametrize("size, kept", [("200k", 0), ("400k", 1)])
def test_a_real_full_file_system(packing, tmp_path, capsys, size, kept):
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
        if kept:
            assert left == [".out.h5.partial"] and "for --resume" in err
        else:
            assert left == []
        assert _mount_tmpfs(full, "50m", remount=True)
        assert main(run + (["--resume"] if kept else [])) == 0
        assert sorted(p.name for p in full.iterdir()) == ["out.h5"]
    finally:
        subprocess.run(["umount", str(full)], capture_output=True)


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0 or not shutil.which("mount"),
                    reason="mounts a read-only tmpfs and makes a device node (root only)")
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
