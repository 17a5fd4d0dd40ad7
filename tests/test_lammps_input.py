"""The generic input interpreter (readers/lammps_input.py): lines, words, variables and formulas.

Every fault of a formula or of an input file is one ScriptError that names the file and the line, and
quotes at most a bounded, printable excerpt of the input; every value a formula gives is finite.
"""

from __future__ import annotations

import math
import re
import subprocess
from pathlib import Path

import pytest
from demsplit.errors import ScriptError
from demsplit.readers.lammps_input import (
    FUNCTIONS,
    Unevaluable,
    Variables,
    Where,
    excerpt,
    logical_lines,
    split_words,
    substitute,
)
from demsplit.readers.liggghts_script import read_script
from hypothesis import given, settings
from hypothesis import strategies as st
from test_liggghts_script import HEADER, script

WHERE = Where(Path("in.test"), 7)


def evaluate(formula: str, **defined: str) -> float:
    """``formula`` evaluated with string variables ``defined`` (equal-style where the value starts with '=')."""
    variables = Variables({})
    for name, value in defined.items():
        style, value = ("equal", value[1:]) if value.startswith("=") else ("string", value)
        variables.define([name, style, value], WHERE)
    return variables.evaluate(formula, WHERE)


def fault(formula: str, **defined: str) -> ScriptError:
    with pytest.raises(ScriptError) as err:
        evaluate(formula, **defined)
    message = str(err.value)
    assert "in.test:7" in message and err.value.fix and message.isprintable() and len(message) < 600, message
    return err.value


# ---------------------------------------------------------------- faults of formulas, one test per class


@pytest.mark.parametrize(
    "formula",
    ["sqrt(-1)", "ln(0)", "ln(-2)", "log(0)", "asin(1.5)", "acos(-2)", "(-8)^(1/3)", "(-1)^0.5", "sqrt(1-2*v_x)"],
)
def test_a_domain_error_is_a_script_error(formula):
    assert "outside the" in fault(formula, x="1").message  # the function's domain, or the domain of ^


@pytest.mark.parametrize(
    "formula",
    [
        "10^400",
        "exp(1000)",
        "1e999",
        "10^300*10^300",
        "-(10^300)*10^300",
        "1/(10^300*10^300)",
        "atan(10^300*10^300)",
        "exp(-(10^300*10^300))",
        "floor(10^300*10^300)",
        "1e308+1e308",
        "-1e308-1e308",
        "1/1e-310",
        "v_big*10",
        "2^2^2^2^2^2^2^2^2^2^2",
    ],
)
def test_an_overflow_anywhere_in_the_formula_is_a_script_error(formula):
    # LIGGGHTS carries an inf on (1/inf is 0); demsplit refuses the formula where the value overflows
    assert "overflows" in fault(formula, big="1e308").message


@pytest.mark.parametrize("formula", ["1/0", "0^(-1)", "0^-2", "1/(2-2)", "v_x/(v_x-1)", "5/0.0"])
def test_a_division_by_zero_is_a_script_error(formula):
    assert "division by zero" in fault(formula, x="1").message


@pytest.mark.parametrize("formula", ["2^0", "0^0", "3^(1-1)", "v_x^(v_x-1)"])
def test_a_power_by_zero_is_refused_as_liggghts_refuses_it(formula):
    err = fault(formula, x="1")
    assert "power by 0" in err.message and "Power by 0 in variable formula" in err.fix


@pytest.mark.parametrize("value", ["abc", "1.5.2", "inf", "nan", "-infinity", "1e999", "x" * 5000])
def test_a_variable_that_is_not_a_finite_number_is_a_script_error(value):
    err = fault("v_s+1", s=value)
    assert "not a finite number" in err.message or "not a number" in err.message


@pytest.mark.parametrize(
    "formula",
    [
        "(" * 5000 + "1" + ")" * 5000,
        "-" * 20000 + "1",
        "+" * 20000 + "1",
        "sqrt(" * 3000 + "4" + ")" * 3000,
        "1+(" * 3000 + "1" + ")" * 3000,
    ],
)
def test_a_formula_nested_too_deeply_is_a_script_error(formula):
    assert "nested too deeply" in fault(formula).message


def test_variables_that_refer_to_each_other_in_a_loop_are_a_script_error():
    assert "loop" in fault("v_a", a="=v_b+1", b="=v_a+1").message


_LEAVES = st.sampled_from(["0", "1", "2", "0.5", "7", "1e-300", "1e300", "1.7e308", "PI", "v_x", "v_e"])


def _compose(inner):
    return st.one_of(
        st.tuples(inner, st.sampled_from("+-*/^"), inner).map(lambda t: f"({t[0]}){t[1]}({t[2]})"),
        st.tuples(st.sampled_from(sorted(FUNCTIONS)), inner).map(lambda t: f"{t[0]}({t[1]})"),
        inner.map(lambda t: f"-({t})"),
    )


@pytest.mark.slow
@settings(max_examples=400, deadline=None)
@given(st.recursive(_LEAVES, _compose, max_leaves=16))
def test_every_formula_gives_a_finite_number_or_a_script_error(formula):
    try:
        value = evaluate(formula, x="-3", e="=10^300*v_x/3")
    except ScriptError as err:
        assert "in.test:7" in str(err) and err.fix
    else:
        assert isinstance(value, float) and math.isfinite(value)


# ---------------------------------------------------------------- what LIGGGHTS 3.8 computes


@pytest.mark.parametrize(
    "formula, value",
    [
        ("-2^2", 4),
        ("2^-1", 0.5),
        ("2^3^2", 64),
        ("4^0.5^2", 4),
        ("2^-1^2", 0.25),
        ("-2^-2^-1", 4),
        ("2*-3^2", 18),
        ("round(2.5)", 3),
        ("round(-2.5)", -2),
        ("round(-2.6)", -3),
        ("floor(-0.5)", -1),
        ("log(1000)", 3),
        ("v_third*3-1", float("0.333333333333333") * 3 - 1),
    ],
)
def test_formulas_evaluate_as_liggghts_does(formula, value):
    # measured on Debian's LIGGGHTS 3.8.0 (test_formulas_match_the_real_program): ^ left to right, unary minus
    # before ^, round() rounds halves up, v_name of an equal-style variable passes through %.15g
    assert evaluate(formula, third="=1/3") == pytest.approx(value, rel=1e-15, abs=1e-300)


def test_what_only_the_run_knows_is_unevaluable():
    for formula in ["step", "c_ke", "2 > 1", "7 % 2", "atan2(1,2)", "v_a", "(1"]:
        with pytest.raises(Unevaluable):
            variables = Variables({})
            variables.define(["a", "atom", "x"], WHERE)
            variables.evaluate(formula, WHERE)


_SIM_FORMULAS = [
    "-2^2",
    "2^3^2",
    "4^0.5^2",
    "2^-1^2",
    "-2^-2^-1",
    "2*-3^2",
    "round(2.5)",
    "round(-2.5)",
    "7-PI",
    "v_third*3-1",
    "sqrt(2)*exp(1)/ln(10)",
    "atan(1)*4-PI",
    "floor(-0.5)+ceil(-0.5)",
    "1e-300*1e-300",
    "abs(-3)/4^2/2",
    "asin(0.5)+acos(0.5)",
]


@pytest.mark.simulator
def test_formulas_match_the_real_program(liggghts, tmp_path):
    lines = ["variable third equal 1/3"]
    for k, formula in enumerate(_SIM_FORMULAS):
        lines += [f"variable f{k} equal {formula.replace(' ', '')}", f'print "F{k} ${{f{k}}}"']
    path = tmp_path / "in.formulas"
    path.write_text("\n".join(lines) + "\n")
    proc = subprocess.run(
        ["stdbuf", "-o0", "-e0", liggghts, "-in", path.name, "-log", "none"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0 and "ERROR" not in proc.stdout, proc.stdout[-2000:]
    printed = dict(re.findall(r"^F(\d+) (\S+)$", proc.stdout, re.M))
    variables = Variables({})
    for line in lines:
        if line.startswith("variable"):
            variables.define(line.split()[1:], WHERE)
    assert {int(k): v for k, v in printed.items()} == {
        k: variables.retrieve(f"f{k}", WHERE) for k in range(len(_SIM_FORMULAS))
    }


# ---------------------------------------------------------------- lines, words, substitution


def test_immediate_expressions_and_variables_substitute():
    v = Variables({"n": "4"})
    v.define(["r", "equal", "2*v_n"], WHERE)
    assert split_words(substitute("x ${r} $(v_r/2) 'a b'", v, WHERE), WHERE) == ["x", "8", "4", "a b"]


def test_continued_lines_keep_the_first_line_number(tmp_path):
    script_path = tmp_path / "in.x"
    script_path.write_bytes(b"a &\n  b\r\nc\x0cd\n\ne &")
    assert list(logical_lines(script_path)) == [(1, "a   b"), (3, "c\x0cd"), (4, ""), (5, "e ")]


@pytest.mark.parametrize(
    "line",
    [
        "x 'abc" + "y" * 5000,
        "x ${" + "z" * 5000,
        "x ${" + "z" * 5000 + "}",
        "x $(" + "1+" * 5000,
        "x 'a'b",
        "variable " + "n" * 5000 + "- equal 1",
    ],
)
def test_a_faulty_line_is_quoted_as_a_bounded_excerpt(line):
    variables = Variables({})
    with pytest.raises(ScriptError) as err:
        words = split_words(substitute(line, variables, WHERE), WHERE)
        variables.define(words[1:], WHERE)
    assert len(str(err.value)) < 400 and "in.test:7" in str(err.value)


def test_an_excerpt_is_bounded_and_printable():
    assert excerpt("  ab  ") == "'ab'"
    shown = excerpt("\x1b[2J" + "\x00" * 500 + "é" * 500)
    assert shown.isprintable() and len(shown) < 4 * 60 + 10 and "\x1b" not in shown


# ---------------------------------------------------------------- include of a file that is not a script


_SECRET = "SECRET-0123456789"


@pytest.mark.parametrize(
    "content",
    [
        b"\x00\x01\x02\xff\xfe binary " + _SECRET.encode(),  # not UTF-8
        b"\x7fELF\x02\x01\x01\x00" + b"\x00" * 8 + _SECRET.encode(),  # an executable
        ("root:x:0:0:" + _SECRET + "\n").encode() + b"\x00\n",  # UTF-8 with a NUL byte
        b"\x1b[2J\x1b[31m" + _SECRET.encode() + b"\n",  # terminal escapes
        ("root:$6$" + _SECRET + "$hash:19000:0:99999:7:::\n").encode(),  # /etc/shadow
        ("print '" + "A" * 100 + _SECRET + "\n").encode(),  # a long line, unbalanced
        ("fix " + "A" * 100 + _SECRET + "\n").encode(),  # a command too short
    ],
)
def test_a_file_that_is_not_a_text_script_is_named_not_quoted(tmp_path, content):
    foreign = tmp_path / "foreign"
    foreign.write_bytes(content)
    main = tmp_path / "in.x"
    main.write_text(f"include {foreign}\n")
    with pytest.raises(ScriptError) as err:
        read_script(main)
    message = str(err.value)
    assert str(foreign) in message and _SECRET not in message and message.isprintable() and len(message) < 500


# ---------------------------------------------------------------- through read_script (moved from
# test_liggghts_script.py: they test the interpreter only)


def test_unary_minus_binds_tighter_than_power(tmp_path):
    s = script(tmp_path, "variable a equal -2^2\nvariable b equal 2^-1\nvariable c equal 7-PI\n")
    assert s.variables["a"] == "4" and s.variables["b"] == "0.5"
    assert float(s.variables["c"]) == pytest.approx(7 - math.pi, rel=1e-14)


def test_undefined_variable(tmp_path):
    with pytest.raises(ScriptError, match="'radius' is used but not defined") as err:
        script(tmp_path, "\n\nfix ins all particletemplate/sphere 1 atom_type 1 radius constant ${radius}\n")
    assert err.value.line == HEADER.count("\n") + 3
    assert "-var radius" in err.value.fix


def test_continuation_line_number_and_unbalanced_quote(tmp_path):
    with pytest.raises(ScriptError, match="unbalanced quotes") as err:
        script(tmp_path, 'dump d all custom 10 a.txt id &\n   x y\ndump_modify d format "%d %g %g\n')
    assert err.value.line == HEADER.count("\n") + 3


# --- the interpreter's work is bounded: one refusal naming the file and the line ----------------------------


def _refusal(tmp_path: Path, lines: list[str], seconds: float = 10.0) -> ScriptError:
    import time

    path = tmp_path / "in.bounded"
    path.write_text("\n".join(lines) + "\n")
    t0 = time.monotonic()
    with pytest.raises(ScriptError) as err:
        read_script(path)
    assert time.monotonic() - t0 < seconds
    return err.value


def test_string_variables_that_double_are_refused_at_the_line_that_passes_the_bound(tmp_path):
    """817 bytes of doubling string variables took 34 s and 1.8 GB; 1.4 KB was killed by the kernel."""
    lines = ["variable a0 string xxxxxxxxxxxxxxxx"]
    lines += [f"variable a{i} string ${{a{i - 1}}}${{a{i - 1}}}" for i in range(1, 40)]
    err = _refusal(tmp_path, lines)
    assert err.file.endswith("in.bounded") and err.line == 17 and "longer than 1048576 characters" in err.message


def test_formulas_that_refer_to_each_other_are_evaluated_once_each_and_bounded(tmp_path):
    """v_v21 referring to v_v20 twice, and so on, took 2^21 evaluations (a hang); each variable is now
    evaluated once per definition (40 levels: 2^40 evaluations before). A formula that still takes more than
    MAX_OPERATIONS is refused."""
    from demsplit.readers.lammps_input import MAX_OPERATIONS

    path = tmp_path / "in.chain"
    path.write_text(
        HEADER
        + "variable v0 equal 1\n"
        + "".join(f"variable v{i} equal v_v{i - 1}+v_v{i - 1}\n" for i in range(1, 41))
        + "timestep $(v_v40*1e-20)\n"
    )
    assert read_script(path).timestep == pytest.approx(2.0**40 * 1e-20)
    long = "variable big equal " + "+".join(["1"] * (MAX_OPERATIONS // 6))
    err = _refusal(tmp_path, [long] + [f"variable t{k} equal $(v_big)" for k in range(4)])
    assert err.line == 5 and f"more than {MAX_OPERATIONS} operations" in err.message  # the 4th evaluation


def test_includes_nested_too_deeply_are_one_refusal(tmp_path):
    """600 nested includes were exit 3 (RecursionError)."""
    from demsplit.readers.liggghts_script import MAX_INCLUDE_DEPTH

    for k in range(600):
        (tmp_path / f"f{k}.in").write_text(f"include f{k + 1}.in\n" if k < 599 else "variable z equal 1\n")
    err = _refusal(tmp_path, ["include f0.in"])
    assert err.file == str(tmp_path / f"f{MAX_INCLUDE_DEPTH - 2}.in") and err.line == 1
    assert f"more than {MAX_INCLUDE_DEPTH} deep" in err.message


def test_a_script_too_large_and_a_line_too_long_are_refused(tmp_path):
    from demsplit.readers.lammps_input import MAX_LINE

    err = _refusal(tmp_path, ["units si", "variable a string " + "x" * MAX_LINE])
    assert err.line == 2 and "longer than" in err.message
    err = _refusal(tmp_path, ["units si", "variable a string &", "x" * (MAX_LINE // 2) + " &", "y" * (MAX_LINE // 2)])
    assert err.line == 2


def test_the_value_of_an_environment_variable_is_never_quoted(tmp_path, monkeypatch):
    """variable s getenv NAME: its value comes from the environment, not the script; a message or a warning
    names the variable instead."""
    monkeypatch.setenv("DEMSPLIT_TEST_SECRET", "hunter2-secret")
    err = _refusal(tmp_path, ["variable s getenv DEMSPLIT_TEST_SECRET", "units ${s}"])
    assert "hunter2" not in str(err) and "${s}" in str(err) and err.line == 2
    path = tmp_path / "in.warn"
    path.write_text(
        HEADER + "variable s getenv DEMSPLIT_TEST_SECRET\n"
        "dump d all custom 100 atoms.txt id type x y z radius\ndump_modify d ${s} yes\n"
    )
    warnings = "\n".join(read_script(path).warnings)
    assert "hunter2" not in warnings
