"""Conventions of the ``demsplit`` command: every argument of every command is described, in plain text
(no reStructuredText markup), and ``-q`` silences every command."""

from __future__ import annotations

import argparse
import re
import shutil

import pytest
from conftest import SAMPLES
from demsplit import cli

MARKUP = re.compile(r"``|:(func|class|mod|meth|attr|ref):`")


def subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = cli.build_parser()
    (action,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return {"": parser, **action.choices}


def test_every_argument_is_described_in_plain_text():
    for name, parser in subparsers().items():
        texts = [parser.description, parser.epilog]
        assert parser.description, f"demsplit {name} has no description"
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                texts += [c.help for c in action._choices_actions]
                continue
            assert action.help and action.help != argparse.SUPPRESS, f"demsplit {name}: {action.dest} has no help"
            texts.append(action.help)
        texts += [g.description for g in parser._action_groups]
        for text in filter(None, texts):
            assert not MARKUP.search(text), f"demsplit {name}: markup in {text!r}"
        help_text = parser.format_help()
        assert not MARKUP.search(help_text), help_text


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    out = tmp_path_factory.mktemp("store") / "packing.h5"
    assert cli.main(["run", str(SAMPLES / "liggghts" / "packing" / "in.packing"), "-o", str(out), "-q"]) == 0
    return out


def commands(store, tmp_path) -> dict[str, list[str]]:
    """One invocation of each command on the samples."""
    script = tmp_path / "in.packing"
    shutil.copy(SAMPLES / "liggghts" / "packing" / "in.packing", script)
    return {
        "run": ["run", str(SAMPLES / "yade" / "mindlin_box.h5"), "-o", str(tmp_path / "y.h5")],
        "info": ["info", str(store)],
        "check": ["check", str(SAMPLES / "yade" / "mindlin_box.h5")],
        "report": ["report", str(store)],
        "report -o": ["report", str(store), "-o", str(tmp_path / "r.html")],
        "export": ["export", str(store), "--csv", str(tmp_path / "csv"), "--dump", str(tmp_path / "p.dump")],
        "yade-path": ["yade-path"],
        "prepare": ["prepare", str(script), "-o", str(tmp_path / "in.prepared")],
        "convert": ["convert", str(SAMPLES / "yade" / "mindlin_box.h5"), "-o", str(tmp_path / "cache.h5")],
    }


@pytest.mark.slow
def test_quiet_silences_every_command(store, tmp_path, capsys):
    loud, quiet = tmp_path / "loud", tmp_path / "quiet"
    loud.mkdir()
    quiet.mkdir()
    runs = commands(store, loud)
    assert {argv[0] for argv in runs.values()} == set(subparsers()) - {""}  # every command is covered
    for name, argv in runs.items():
        assert cli.main(argv) == 0, name
        assert capsys.readouterr().out.strip(), f"{name} prints nothing without -q: the test would not see -q work"
    for name, argv in commands(store, quiet).items():
        assert cli.main([*argv, "-q"]) == 0, name
        out, err = capsys.readouterr()
        assert (out, err) == ("", ""), f"demsplit {name} -q printed {out + err!r}"
