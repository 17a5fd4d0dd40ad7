"""An optional feature whose extra is not installed is one error naming the extra (exit 2), not a
traceback: Parquet (pyarrow), VTK (meshio), Dask (distributed)."""

from __future__ import annotations

import builtins

import pytest
from conftest import SAMPLES
from demsplit import cli


@pytest.fixture
def store(tmp_path):
    out = tmp_path / "p.h5"
    assert cli.main(["run", str(SAMPLES / "yade" / "mindlin_box.h5"), "-o", str(out), "-q"]) == 0
    return out


def block(monkeypatch, module: str) -> None:
    real_import = builtins.__import__

    def blocked(name, *args, **kwargs):
        if name.split(".")[0] == module:
            raise ImportError(f"No module named {module!r}")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", blocked)


@pytest.mark.parametrize(
    "module, argv, extra",
    [
        ("pyarrow", ["export", "{store}", "--parquet", "{tmp}/pq"], "parquet"),
        ("meshio", ["export", "{store}", "--vtk", "{tmp}/vtk"], "vtk"),
        (
            "distributed",
            ["run", str(SAMPLES / "yade" / "mindlin_box.h5"), "-o", "{tmp}/d.h5", "--dask", "local:1"],
            "dask",
        ),
    ],
)
@pytest.mark.slow
def test_a_missing_extra_is_named(store, tmp_path, monkeypatch, capsys, module, argv, extra):
    capsys.readouterr()
    block(monkeypatch, module)
    code = cli.main([a.format(store=store, tmp=tmp_path) for a in argv])
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.count("\n") == 1 and f"pip install 'demsplit[{extra}]'" in err and "internal error" not in err
