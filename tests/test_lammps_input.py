"""The generic input interpreter (readers/lammps_input.py): every fault of a formula or of an input file is
one ScriptError that names the file and the line, and quotes at most a bounded, printable excerpt."""

from __future__ import annotations

from pathlib import Path

import pytest
from demsplit.errors import ScriptError
from demsplit.readers.lammps_input import Variables, Where, logical_lines, split_words, substitute
from demsplit.readers.liggghts_script import read_script

WHERE = Where(Path("in.test"), 7)


@pytest.mark.parametrize("formula, reason", [
    ("sqrt(-1)", "domain"), ("ln(0)", "domain"), ("(-8)^(1/3)", "domain"), ("acos(2)", "domain"),
    ("10^400", "overflows"), ("exp(1000)", "overflows"), ("floor(10^300*10^300)", "overflows"),
    ("0^(-1)", "division by zero"),
])
def test_arithmetic_faults_are_script_errors(formula, reason):
    with pytest.raises(ScriptError, match=reason) as err:
        Variables({}).evaluate(formula, WHERE)
    assert "in.test:7" in str(err.value)


@pytest.mark.parametrize("formula", ["10^300*10^300", "-(10^300)*10^300"])
def test_a_value_that_is_not_finite_is_refused(formula):
    with pytest.raises(ScriptError, match="evaluates to"):
        Variables({}).evaluate(formula, WHERE)


@pytest.mark.parametrize("depth", [2000, 20000])
def test_deep_nesting_is_a_script_error_with_a_bounded_excerpt(depth):
    with pytest.raises(ScriptError, match="nested too deeply") as err:
        Variables({}).evaluate("(" * depth + "1" + ")" * depth, WHERE)
    assert len(str(err.value)) < 300


def test_immediate_expressions_and_variables_substitute():
    v = Variables({"n": "4"})
    v.define(["r", "equal", "2*v_n"], WHERE)
    assert split_words(substitute("x ${r} $(v_r/2) 'a b'", v, WHERE), WHERE) == ["x", "8", "4", "a b"]


@pytest.mark.parametrize("content", [b"\x00\x01\x02\xff\xfe binary", b"root:x:0:0:\xe9\xff\n" * 50])
def test_a_file_that_is_not_a_text_script_is_named_not_quoted(tmp_path, content):
    foreign = tmp_path / "foreign"
    foreign.write_bytes(content)
    script = tmp_path / "in.x"
    script.write_text(f"include {foreign}\n")
    with pytest.raises(ScriptError) as err:
        read_script(script)
    message = str(err.value)
    assert str(foreign) in message and "root:x" not in message and message.isprintable()


def test_continued_lines_keep_the_first_line_number(tmp_path):
    script = tmp_path / "in.x"
    script.write_text("a &\n  b\nc\n")
    assert list(logical_lines(script)) == [(1, "a   b"), (3, "c")]
