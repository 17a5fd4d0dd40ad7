"""The generic LAMMPS-style input interpreter: logical lines, comments, words, variables, expressions.

What LAMMPS' and LIGGGHTS' ``Input`` class does to a line before a command
sees it (``input.cpp``), independent of what the commands mean: a trailing
``&`` joins the next physical line (:func:`logical_lines`), ``#`` outside
quotes starts a comment (:func:`strip_comment`), ``$x``, ``${name}`` and
``$(expr)`` are substituted outside quotes (:func:`substitute`), and the line
is split into words, quoted text being one word (:func:`split_words`).
:class:`Variables` keeps the variables the way ``variable.cpp`` does and
evaluates equal-style formulas with numbers, ``+ - * / ^``, parentheses,
``v_name``, ``PI`` and the functions of ``FUNCTIONS``. Anything that depends
on the simulation (thermo keywords, atom values) is :class:`Unevaluable`.

Every evaluation gives a finite number or one :class:`~demsplit.errors.ScriptError`
naming the file and the line: a domain error (``sqrt(-1)``, ``ln(0)``), an
overflow (``10^400``), a division by zero (``1/0``, ``0^(-1)``) and a formula
nested too deeply are input errors, never a Python exception or an ``inf``.
The LIGGGHTS semantics of the commands are in :mod:`demsplit.readers.liggghts_script`.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from ..errors import ScriptError


@dataclass(frozen=True)
class Where:
    """Where a command is: its file and the number of its first physical line."""

    file: Path
    line: int


class Unevaluable(Exception):
    """A variable whose value demsplit cannot know (thermo keywords, atom styles...)."""


def logical_lines(path: Path) -> Iterator[tuple[int, str]]:
    """(first physical line number, text) of each command: a line whose last
    non-blank character is ``&`` continues on the next one (``input.cpp``
    ``file()``: the ``&`` is dropped, the next line appended as is)."""
    try:
        text = path.read_text()
    except OSError as exc:
        raise ScriptError(f"cannot read the input script ({exc.strerror}).", file=path,
                          fix="check the path.") from None
    except UnicodeDecodeError as exc:
        line = exc.object[: exc.start].count(b"\n") + 1
        raise ScriptError(f"byte 0x{exc.object[exc.start]:02x} at offset {exc.start} is not UTF-8 text; "
                          "expected a LIGGGHTS input script.", file=path, line=line,
                          fix="pass the input script (a text file), or remove the damaged bytes.") from None
    start, pending = 0, ""
    for number, raw in enumerate(text.splitlines(), start=1):
        body = raw.rstrip()
        if not pending:
            start = number
        if body.endswith("&"):
            pending += body[:-1]
            continue
        yield start, pending + body
        pending = ""
    if pending:
        yield start, pending


def strip_comment(text: str) -> str:
    """``text`` up to a ``#`` outside quotes."""
    quote = ""
    for i, ch in enumerate(text):
        if ch == "#" and not quote:
            return text[:i]
        if ch == quote:
            quote = ""
        elif not quote and ch in "\"'":
            quote = ch
    return text


def split_words(text: str, where: Where) -> list[str]:
    """Words of a line; quoted text is one word, quotes stripped (``nextword``)."""
    words, i, n = [], 0, len(text)
    while True:
        while i < n and text[i].isspace():
            i += 1
        if i >= n:
            return words
        if text[i] in "\"'":
            stop = text.find(text[i], i + 1)
            if stop < 0:
                raise ScriptError(f"unbalanced quotes in: {text.strip()!r}.", file=where.file,
                                  line=where.line, fix="close the quote.")
            if stop + 1 < n and not text[stop + 1].isspace():
                raise ScriptError(f"a closing quote must be followed by a blank: {text.strip()!r}.",
                                  file=where.file, line=where.line, fix="add a space after the quote.")
            words.append(text[i + 1:stop])
            i = stop + 1
        else:
            j = i
            while j < n and not text[j].isspace():
                j += 1
            words.append(text[i:j])
            i = j


# --------------------------------------------------------------------------
# Variables and a small arithmetic evaluator for equal-style formulas
# --------------------------------------------------------------------------

TOKEN = re.compile(r"\s*(?:(?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)|(?P<name>[A-Za-z_]\w*)|(?P<op>[-+*/^(),]))")
FUNCTIONS = {"sqrt": math.sqrt, "exp": math.exp, "ln": math.log, "log": math.log10, "abs": abs,
              "sin": math.sin, "cos": math.cos, "tan": math.tan, "asin": math.asin,
              "acos": math.acos, "atan": math.atan, "floor": math.floor, "ceil": math.ceil,
              "round": round}
CONSTANTS = {"PI": math.pi}


class Variables:
    """LAMMPS variables as LIGGGHTS' ``Variable`` class keeps them: ``index``,
    ``loop``, ``world``, ``universe``, ``uloop`` (first value), ``string``,
    ``equal`` (a formula, evaluated when used), ``getenv``. Command-line values
    are index variables defined first, so the script cannot redefine them."""

    def __init__(self, cli: dict[str, str]) -> None:
        self.values: dict[str, tuple[str, str]] = {k: ("index", str(v)) for k, v in cli.items()}
        self.cli = set(cli)

    def define(self, words: list[str], where: Where) -> None:
        if len(words) < 2:
            raise ScriptError(f"variable command needs NAME STYLE ARGS, got {words}.",
                              file=where.file, line=where.line, fix="complete the variable command.")
        name, style, args = words[0], words[1], words[2:]
        if name in self.cli:
            return
        if style == "delete":
            self.values.pop(name, None)
            return
        if style in ("index", "loop", "world", "universe", "uloop") and name in self.values:
            return  # the first definition wins (variable.cpp: "if (find(arg[0]) >= 0) return")
        if style in ("index", "loop", "world", "universe", "uloop", "string", "equal", "getenv") and not args:
            raise ScriptError(f"variable {name} {style} needs a value.", file=where.file,
                              line=where.line, fix=f"give variable {name} a value.")
        if style == "loop":  # loop N [pad] counts from 1, loop N1 N2 [pad] from N1
            value = "1" if len(args) == 1 or args[1] == "pad" else args[0]
        elif style in ("index", "world", "universe", "uloop", "string"):
            value = args[0]
        elif style == "equal":
            value = " ".join(args)
        elif style == "getenv":
            value = os.environ.get(args[0], "")
        else:  # atom, atomfile, file, python...: values demsplit cannot know
            value = ""
        self.values[name] = (style, value)

    def retrieve(self, name: str, where: Where, depth: int = 0) -> str:
        """Text a ``${name}`` reference becomes (equal-style: ``%.15g``)."""
        if name not in self.values:
            raise ScriptError(
                f"variable {name!r} is used but not defined.", file=where.file, line=where.line,
                fix=f"define it in the script ('variable {name} index VALUE') or pass "
                f"variables={{'{name}': VALUE}} (LIGGGHTS: -var {name} VALUE).")
        style, value = self.values[name]
        if style == "equal":
            return f"{self.evaluate(value, where, depth + 1):.15g}"
        if style not in ("index", "loop", "world", "universe", "uloop", "string", "getenv"):
            raise Unevaluable(f"variable {name} is {style}-style")
        return value

    def evaluate(self, expr: str, where: Where, depth: int = 0) -> float:
        """Value of an equal-style formula: numbers, ``+ - * / ^``, parentheses,
        ``v_name``, ``PI`` and the functions in ``FUNCTIONS``. Unary minus
        binds tighter than ``^`` in LIGGGHTS 3.8 (measured: ``-2^2`` is 4)."""
        if depth > 50:
            raise ScriptError(f"variables refer to each other in a loop ({expr!r}).", file=where.file,
                              line=where.line, fix="break the circular variable definitions.")
        tokens, pos = [], 0
        expr = expr.strip()
        while pos < len(expr):
            m = TOKEN.match(expr, pos)
            if not m or m.end() == pos:
                raise Unevaluable(f"cannot evaluate {expr!r}")
            tokens.append((m.lastgroup, m.group(m.lastgroup)))
            pos = m.end()
            while pos < len(expr) and expr[pos].isspace():
                pos += 1
        try:
            value = _Evaluator(tokens, self, where, depth).run(expr)
        except (ArithmeticError, ValueError) as exc:  # sqrt(-1), ln(0), 10^400, 0^(-1)
            raise ScriptError(f"the formula {_excerpt(expr)} cannot be evaluated ({_reason(exc)}).",
                              file=where.file, line=where.line, fix="correct the formula.") from None
        except RecursionError:
            raise ScriptError(f"the formula {_excerpt(expr)} is nested too deeply to evaluate.", file=where.file,
                              line=where.line, fix="simplify the formula.") from None
        if not math.isfinite(value):
            raise ScriptError(f"the formula {_excerpt(expr)} evaluates to {value}.", file=where.file,
                              line=where.line, fix="correct the formula: every value must be finite.")
        return value


class _Evaluator:
    """Recursive descent: sum := product (('+'|'-') product)*;
    product := power (('*'|'/') power)*; power := unary ('^' power)?;
    unary := '-' unary | '+' unary | atom."""

    def __init__(self, tokens: list[tuple[str, str]], variables: Variables, where: Where, depth: int):
        self.tokens, self.i, self.vars, self.where, self.depth = tokens, 0, variables, where, depth

    def run(self, expr: str) -> float:
        value = self.sum()
        if self.i != len(self.tokens):
            raise Unevaluable(f"cannot evaluate {expr!r}")
        return value

    def peek(self) -> str | None:
        return self.tokens[self.i][1] if self.i < len(self.tokens) else None

    def take(self) -> tuple[str, str]:
        if self.i >= len(self.tokens):
            raise Unevaluable("formula ends too early")
        self.i += 1
        return self.tokens[self.i - 1]

    def sum(self) -> float:
        value = self.product()
        while self.peek() in ("+", "-"):
            op = self.take()[1]
            value = value + self.product() if op == "+" else value - self.product()
        return value

    def product(self) -> float:
        value = self.power()
        while self.peek() in ("*", "/"):
            op = self.take()[1]
            right = self.power()
            if op == "/" and right == 0:
                raise ScriptError("division by zero in a variable formula.", file=self.where.file,
                                  line=self.where.line, fix="correct the formula.")
            value = value * right if op == "*" else value / right
        return value

    def power(self) -> float:
        base = self.unary()
        if self.peek() == "^":
            self.take()
            value = base ** self.power()
            if isinstance(value, complex):  # a negative base to a fractional power
                raise ValueError("a negative number to a fractional power")
            return value
        return base

    def unary(self) -> float:
        if self.peek() == "-":
            self.take()
            return -self.unary()
        if self.peek() == "+":
            self.take()
            return self.unary()
        return self.atom()

    def atom(self) -> float:
        kind, text = self.take()
        if kind == "num":
            return float(text)
        if text == "(":
            value = self.sum()
            if self.take()[1] != ")":
                raise Unevaluable("missing ')'")
            return value
        if kind == "name":
            if text.startswith("v_"):
                return float(self.vars.retrieve(text[2:], self.where, self.depth))
            if text in CONSTANTS:
                return CONSTANTS[text]
            if text in FUNCTIONS and self.peek() == "(":
                self.take()
                value = self.sum()
                if self.take()[1] != ")":
                    raise Unevaluable(f"{text}() takes one argument here")
                return float(FUNCTIONS[text](value))
        raise Unevaluable(f"{text!r} is not known before the run")


def substitute(text: str, variables: Variables, where: Where) -> str:
    """Replace ``${name}``, ``$x`` and ``$(expr)`` outside quotes (``Input::substitute``)."""
    out, i, quote, n = [], 0, "", len(text)
    while i < n:
        ch = text[i]
        if ch == "$" and not quote:
            if text.startswith("{", i + 1):
                end = text.find("}", i + 2)
                if end < 0:
                    raise ScriptError(f"'${{' without '}}' in: {text.strip()!r}.", file=where.file,
                                      line=where.line, fix="close the variable name with '}'.")
                out.append(variables.retrieve(text[i + 2:end], where))
                i = end + 1
            elif text.startswith("(", i + 1):
                level, j = 0, i + 2
                while j < n and not (text[j] == ")" and level == 0):
                    level += {"(": 1, ")": -1}.get(text[j], 0)
                    j += 1
                if j >= n:
                    raise ScriptError(f"'$(' without ')' in: {text.strip()!r}.", file=where.file,
                                      line=where.line, fix="close the immediate variable with ')'.")
                out.append(f"{variables.evaluate(text[i + 2:j], where):.20g}")
                i = j + 1
            elif i + 1 < n:
                out.append(variables.retrieve(text[i + 1], where))
                i += 2
            else:
                raise ScriptError("'$' at the end of a line.", file=where.file, line=where.line,
                                  fix="remove the '$' or name a variable after it.")
            continue
        if ch == quote:
            quote = ""
        elif not quote and ch in "\"'":
            quote = ch
        out.append(ch)
        i += 1
    return "".join(out)




def _excerpt(text: str, limit: int = 60) -> str:
    """A bounded, printable quote of input text for a message."""
    shown = text.strip()
    return repr(shown if len(shown) <= limit else shown[:limit] + "...")


def _reason(exc: BaseException) -> str:
    if isinstance(exc, ZeroDivisionError):
        return "division by zero"
    if isinstance(exc, OverflowError):
        return "the result overflows"
    return "outside the function's domain"
