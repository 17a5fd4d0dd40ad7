"""The generic LAMMPS-style input interpreter: logical lines, comments, words, variables, expressions.

What LAMMPS' and LIGGGHTS' ``Input`` class does to a line before a command
sees it (``input.cpp``), independent of what the commands mean:

* :func:`logical_lines`: a line whose last non-blank character is ``&``
  continues on the next one (the ``&`` is dropped, the next line appended as
  is). The file is text without control characters (tab, form feed and CR
  are blanks); anything else is refused as "not an input script" with its
  line, never quoted. It is read as UTF-8, and a byte that is not UTF-8 (a
  Latin-1 "é" in a comment, which LIGGGHTS reads as it reads any byte) is kept
  as itself (:func:`read_text`).
* :func:`strip_comment`: ``#`` outside quotes starts a comment.
* :func:`substitute`: ``$x``, ``${name}`` and ``$(expr)`` are replaced outside
  quotes (``Input::substitute``); ``${name}`` of an equal-style variable
  becomes its value in ``%.15g``, ``$(expr)`` its value in ``%.20g``.
* :func:`split_words`: the line is split at blanks, quoted text being one word
  with its quotes stripped (``nextword``).

:class:`Variables` keeps the variables the way ``variable.cpp`` does
(``define``, ``retrieve``) and evaluates equal-style formulas (``evaluate``).
Supported: numbers, ``+ - * / ^``, parentheses, ``v_name``, ``PI`` and the
one-argument functions of :data:`FUNCTIONS`, with LIGGGHTS 3.8's rules
(measured on Debian's 3.8.0): unary minus binds tighter than ``^``
(``-2^2`` is 4), ``^`` is evaluated left to right (``2^3^2`` is 64),
``round`` rounds halves up (``round(-2.5)`` is -2), ``v_name`` reads the
variable's text the way ``retrieve`` writes it (an equal-style value passes
through ``%.15g``), and a power by 0 is an error, as in LIGGGHTS ("Power by 0
in variable formula"). Anything that depends on the simulation (thermo
keywords, ``c_``/``f_`` references, atom values, ``random()``, the comparison
and logical operators, ``%``, two-argument functions) is :class:`Unevaluable`:
the caller decides whether the command needed it.

Every evaluation gives a finite number or one :class:`~demsplit.errors.ScriptError`
naming the file and the line, with a fix: a domain error (``sqrt(-1)``,
``ln(0)``, ``(-8)^(1/3)``), an overflow anywhere in the formula (``10^400``,
``1/(10^300*10^300)``: LIGGGHTS would carry an ``inf`` on), a division by zero
(``1/0``, ``0^(-1)``), a variable that is not a number, and a formula nested
too deeply to evaluate (Python's ``RecursionError``). Every value of a formula
is made by one function, :meth:`_Evaluator.apply`, which is where these faults
are caught. Messages quote input text only as an :func:`excerpt`: bounded and
printable, whatever file it comes from.

The interpreter's work is bounded, whatever the script: a logical line is at most :data:`MAX_LINE`
characters before and after substitution, a script (with its includes) hands at most :data:`MAX_CHARACTERS`
characters of lines and substituted values to the commands, and its formulas take at most
:data:`MAX_OPERATIONS` operations (an equal-style variable is evaluated once per definition of the
variables, however often a formula refers to it). Past a bound the script is refused with one
:class:`~demsplit.errors.ScriptError` naming the file and the line. The text of ``getenv`` variables
comes from the environment, not the script: it is never quoted in a message.

The LIGGGHTS semantics of the commands are in :mod:`demsplit.readers.liggghts_script`.
"""

from __future__ import annotations

import math
import operator
import os
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from ..errors import ScriptError

__all__ = [
    "Where",
    "Unevaluable",
    "excerpt",
    "read_text",
    "logical_lines",
    "strip_comment",
    "split_words",
    "Variables",
    "substitute",
    "TOKEN",
    "FUNCTIONS",
    "CONSTANTS",
    "MAX_LINE",
    "MAX_CHARACTERS",
    "MAX_OPERATIONS",
]

MAX_LINE = 1 << 20
"""Characters of one logical line, before and after its variables are substituted."""
MAX_CHARACTERS = 64 << 20
"""Characters of lines and substituted values one script (with its includes) hands to its commands."""
MAX_OPERATIONS = 1_000_000
"""Operations (numbers, variables, arithmetic) the formulas of one script may take to evaluate."""
_FIX_BOUND = (
    "a LIGGGHTS input script is far smaller: check that this is the run's script, and that its "
    "variables do not grow by referring to each other."
)


@dataclass(frozen=True)
class Where:
    """Where a command is: its file and the number of its first physical line."""

    file: Path
    line: int


class Unevaluable(Exception):
    """A value demsplit cannot know before the run (thermo keywords, atom-style
    variables, operators and functions it does not evaluate...)."""


def excerpt(text: str, limit: int = 60) -> str:
    """A bounded, printable quote of input text for a message: the text without
    its surrounding blanks, cut after ``limit`` characters, in Python's
    ``repr`` (quotes around it, control and other unprintable characters escaped)."""
    shown = text.strip()
    return repr(shown if len(shown) <= limit else shown[:limit] + "...")


_CONTROL = re.compile(r"[\x00-\x08\x0e-\x1f\x7f-\x9f]")
"""Characters no input script holds (tab, LF, VT, FF and CR are blanks to LAMMPS)."""


def read_text(path: Path) -> str:
    """The text of the input script ``path``: UTF-8, each byte that is not UTF-8 kept as its surrogate escape
    (Python's ``surrogateescape``), as LIGGGHTS, which reads bytes, keeps it. The text encodes back to the same
    bytes (``text.encode("utf-8", "surrogateescape")``), a file name in it opens the file of those bytes, and
    :func:`excerpt` shows such a byte escaped. Raises :class:`OSError` when the file cannot be read."""
    return path.read_bytes().decode("utf-8", errors="surrogateescape")


def logical_lines(path: Path) -> Iterator[tuple[int, str]]:
    """(first physical line number, text) of each command: a line whose last
    non-blank character is ``&`` continues on the next one (``input.cpp``
    ``file()``: the ``&`` is dropped, the next line appended as is). Lines end
    at LF only, as for ``fgets``; a CR before it is a blank.

    A file that cannot be read or holds a control character is refused with a
    :class:`ScriptError` naming the file and the line, before any of its
    commands is read and without quoting it (:func:`read_text`: bytes that are
    not UTF-8 are kept)."""
    try:
        if path.stat().st_size > MAX_CHARACTERS:
            raise ScriptError(
                f"the file is {path.stat().st_size} bytes, more than the {MAX_CHARACTERS} an input script may be.",
                file=path,
                fix="give the run's input script, and check its include lines.",
            )
        text = read_text(path)
    except OSError as exc:
        raise ScriptError(f"cannot read the input script ({exc.strerror}).", file=path, fix="check the path.") from None
    bad = _CONTROL.search(text)
    if bad:
        line = text.count("\n", 0, bad.start()) + 1
        column = bad.start() - (text.rfind("\n", 0, bad.start()) + 1) + 1
        raise ScriptError(
            f"character 0x{ord(bad.group()):02x} (a control character) at column {column} is "
            "not text; expected a LIGGGHTS input script.",
            file=path,
            line=line,
            fix="pass the input script (a text file), or remove the control characters.",
        )
    physical = text.split("\n")
    if physical[-1] == "":
        physical.pop()
    start, pending = 0, []
    for number, raw in enumerate(physical, start=1):
        body = raw.rstrip()
        if not pending:
            start = number
        if len(body) > MAX_LINE or sum(map(len, pending)) + len(body) > MAX_LINE:
            raise ScriptError(
                f"the command that starts here is longer than {MAX_LINE} characters.",
                file=path,
                line=start,
                fix=_FIX_BOUND,
            )
        if body.endswith("&"):
            pending.append(body[:-1])
            continue
        yield start, "".join(pending) + body
        pending = []
    if pending:
        yield start, "".join(pending)


_COMMENT_OR_QUOTE = re.compile(r"[#\"']")
_WORD = re.compile(r"\S+")


def strip_comment(text: str) -> str:
    """``text`` up to a ``#`` outside quotes."""
    i = 0
    while True:
        found = _COMMENT_OR_QUOTE.search(text, i)
        if found is None:
            return text
        if found.group() == "#":
            return text[: found.start()]
        end = text.find(found.group(), found.end())
        if end < 0:
            return text
        i = end + 1


def split_words(text: str, where: Where) -> list[str]:
    """Words of a line; quoted text is one word, quotes stripped (``nextword``).
    A quote must be closed, and followed by a blank or the end of the line."""
    words, i, n = [], 0, len(text)
    while True:
        found = _WORD.search(text, i)
        if found is None:
            return words
        i = found.start()
        if text[i] in "\"'":
            stop = text.find(text[i], i + 1)
            if stop < 0:
                raise ScriptError(
                    f"unbalanced quotes in: {excerpt(text)}.", file=where.file, line=where.line, fix="close the quote."
                )
            if stop + 1 < n and not text[stop + 1].isspace():
                raise ScriptError(
                    f"a closing quote must be followed by a blank: {excerpt(text)}.",
                    file=where.file,
                    line=where.line,
                    fix="add a space after the quote.",
                )
            words.append(text[i + 1 : stop])
            i = stop + 1
        else:
            words.append(found.group())
            i = found.end()


# --------------------------------------------------------------------------
# Variables and a small arithmetic evaluator for equal-style formulas
# --------------------------------------------------------------------------

TOKEN = re.compile(r"\s*(?:(?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)|(?P<name>[A-Za-z_]\w*)|(?P<op>[-+*/^(),]))")
"""One token of a formula: a number, a name, or an operator or parenthesis."""


def _round(x: float) -> float:
    """``round()`` as LIGGGHTS' ``MYROUND``: a half goes up (``round(2.5)`` is 3, ``round(-2.5)`` is -2)."""
    return math.ceil(x) if x - math.floor(x) >= 0.5 else math.floor(x)


FUNCTIONS: dict[str, Callable[[float], float]] = {
    "sqrt": math.sqrt,
    "exp": math.exp,
    "ln": math.log,
    "log": math.log10,
    "abs": abs,
    "sin": math.sin,
    "cos": math.cos,
    "tan": math.tan,
    "asin": math.asin,
    "acos": math.acos,
    "atan": math.atan,
    "floor": math.floor,
    "ceil": math.ceil,
    "round": _round,
}
"""The one-argument math functions of an equal-style formula (``log`` is base 10, ``ln`` natural)."""

CONSTANTS = {"PI": math.pi}
"""The named constants of an equal-style formula."""

_NAME = re.compile(r"\w+", re.ASCII)
_COPIED = ("index", "loop", "world", "universe", "uloop", "string", "getenv")
"""Styles whose value is text ``retrieve`` hands back as is."""

_FIX_DOMAIN = (
    "keep each function's argument in its domain (sqrt: x >= 0; ln and log: x > 0; asin and acos: "
    "-1 <= x <= 1), and raise a negative number to whole powers only."
)
_FIX_OVERFLOW = "keep every value of the formula within +-1.8e308: rescale it (e.g. other units, smaller factors)."
_FIX_ZERO = "make sure no divisor, and no base raised to a negative power, is 0."
_FIX_POWER_0 = "write 1 for x^0: LIGGGHTS 3.8 stops on it ('Power by 0 in variable formula')."


class Variables:
    """LAMMPS variables as LIGGGHTS' ``Variable`` class keeps them: ``index``,
    ``loop``, ``world``, ``universe``, ``uloop`` (first value), ``string``,
    ``equal`` (a formula, evaluated when used), ``getenv``; other styles
    (``atom``, ``file``, ``python``...) are kept but :class:`Unevaluable`.
    Command-line values are index variables defined first, so the script
    cannot redefine them."""

    def __init__(self, cli: dict[str, str]) -> None:
        self.values: dict[str, tuple[str, str]] = {k: ("index", str(v)) for k, v in cli.items()}
        self.cli = set(cli)
        self.characters = 0  # handed to the commands so far (MAX_CHARACTERS)
        self.operations = 0  # of formulas so far (MAX_OPERATIONS)
        self._evaluated: dict[str, str] = {}  # equal-style values since the last definition

    def charge(self, characters: int, where: Where) -> None:
        """Count ``characters`` more handed to the commands; past :data:`MAX_CHARACTERS` the script is refused."""
        self.characters += characters
        if self.characters > MAX_CHARACTERS:
            raise ScriptError(
                f"the script and its includes, with their variables substituted, pass "
                f"{MAX_CHARACTERS} characters here.",
                file=where.file,
                line=where.line,
                fix=_FIX_BOUND,
            )

    def operation(self, where: Where) -> None:
        """Count one operation of a formula; past :data:`MAX_OPERATIONS` the script is refused."""
        self.operations += 1
        if self.operations > MAX_OPERATIONS:
            raise ScriptError(
                f"the script's formulas take more than {MAX_OPERATIONS} operations to evaluate "
                "(equal-style variables that refer to each other many times).",
                file=where.file,
                line=where.line,
                fix=_FIX_BOUND,
            )

    def environment(self) -> list[str]:
        """The values of the ``getenv`` variables (text from the environment, never quoted in a message)."""
        return [v for style, v in self.values.values() if style == "getenv" and v]

    def define(self, words: list[str], where: Where) -> None:
        """The ``variable NAME STYLE ARGS`` command (``words`` without ``variable``).
        Index-like styles keep their first definition, ``string`` and ``equal``
        are redefined, ``delete`` removes the variable."""
        if len(words) < 2:
            raise ScriptError(
                f"variable command needs NAME STYLE ARGS, got {excerpt(' '.join(words))}.",
                file=where.file,
                line=where.line,
                fix="complete the variable command.",
            )
        name, style, args = words[0], words[1], words[2:]
        self._evaluated.clear()  # a definition may change any equal-style value
        if name in self.cli:
            return
        if style == "delete":
            self.values.pop(name, None)
            return
        if not _NAME.fullmatch(name):
            raise ScriptError(
                f"variable name {excerpt(name)} is not letters, digits and underscores "
                "(LIGGGHTS: 'Variable name must be alphanumeric or underscore characters').",
                file=where.file,
                line=where.line,
                fix="rename the variable.",
            )
        if style in ("index", "loop", "world", "universe", "uloop") and name in self.values:
            return  # the first definition wins (variable.cpp: "if (find(arg[0]) >= 0) return")
        if style in _COPIED + ("equal",) and not args:
            raise ScriptError(
                f"variable {name} {excerpt(style)} needs a value.",
                file=where.file,
                line=where.line,
                fix=f"give variable {name} a value.",
            )
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
        """Text a ``${name}`` reference becomes (equal-style: ``%.15g`` of its value)."""
        if name not in self.values:
            shown = name if _NAME.fullmatch(name) and len(name) <= 60 else "NAME"
            raise ScriptError(
                f"variable {excerpt(name)} is used but not defined.",
                file=where.file,
                line=where.line,
                fix=f"define it in the script ('variable {shown} index VALUE') or pass it with --var {shown} VALUE "
                "(LIGGGHTS: -var).",
            )
        style, value = self.values[name]
        if style == "equal":
            if name not in self._evaluated:
                self._evaluated[name] = f"{self.evaluate(value, where, depth + 1):.15g}"
            return self._evaluated[name]
        if style not in _COPIED:
            raise Unevaluable(f"variable {name} is {style}-style")
        return value

    def evaluate(self, expr: str, where: Where, depth: int = 0) -> float:
        """Value of an equal-style formula (see the module docstring): a finite
        number, :class:`Unevaluable` when it needs what only the run knows, or
        a :class:`ScriptError` naming ``where`` when it cannot be evaluated."""
        if depth > 50:
            raise ScriptError(
                f"variables refer to each other in a loop ({excerpt(expr)}).",
                file=where.file,
                line=where.line,
                fix="break the circular variable definitions.",
            )
        tokens, pos = [], 0
        expr = expr.strip()
        while pos < len(expr):
            m = TOKEN.match(expr, pos)
            if not m or m.end() == pos:
                raise Unevaluable(f"cannot evaluate {excerpt(expr)}")
            tokens.append((m.lastgroup, m.group(m.lastgroup)))
            pos = m.end()
            while pos < len(expr) and expr[pos].isspace():
                pos += 1
        try:
            return _Evaluator(tokens, self, where, depth).run(expr)
        except _Fault as fault:
            raise ScriptError(
                f"the formula {excerpt(expr)} cannot be evaluated: {fault.reason}.",
                file=where.file,
                line=where.line,
                fix=fault.fix,
            ) from None
        except RecursionError:
            raise ScriptError(
                f"the formula {excerpt(expr)} is nested too deeply to evaluate.",
                file=where.file,
                line=where.line,
                fix="split it into several equal-style variables.",
            ) from None


class _Fault(Exception):
    """Why a value of a formula cannot be made; :meth:`Variables.evaluate`
    turns it into the formula's one :class:`ScriptError`."""

    def __init__(self, reason: str, fix: str) -> None:
        super().__init__(reason)
        self.reason, self.fix = reason, fix


def _operation(show: str, args: tuple) -> str:
    """An operation of a formula for a message: ``show`` with its arguments,
    numbers in ``%.6g``, text as a bounded excerpt."""
    return show.format(*(f"{a:.6g}" if isinstance(a, float) else excerpt(a, 30)[1:-1] for a in args))


class _Evaluator:
    """Recursive descent, with LIGGGHTS' precedence (``variable.cpp``):
    sum := product (('+'|'-') product)*; product := power (('*'|'/') power)*;
    power := unary ('^' unary)* (left to right); unary := '-' unary | '+' unary | atom;
    atom := number | '(' sum ')' | v_name | constant | function '(' sum ')'.
    Every value is made by :meth:`apply`."""

    def __init__(self, tokens: list[tuple[str, str]], variables: Variables, where: Where, depth: int):
        self.tokens, self.i, self.vars, self.where, self.depth = tokens, 0, variables, where, depth

    @staticmethod
    def apply(fn: Callable[..., float | complex], args: tuple, show: str) -> float:
        """``fn(*args)`` as a finite float, or the :class:`_Fault` that says why
        not; ``show`` writes the operation for the message (``"{0}/{1}"``,
        ``"sqrt({0})"``). The one place where a domain error, an overflow or a
        division by zero is caught: the arguments are finite (they come from
        here), so a result that is not finite is an overflow."""
        try:
            value = fn(*args)
        except ZeroDivisionError:
            raise _Fault(f"{_operation(show, args)} is a division by zero", _FIX_ZERO) from None
        except OverflowError:
            raise _Fault(f"{_operation(show, args)} overflows", _FIX_OVERFLOW) from None
        except ValueError:
            raise _Fault(f"{_operation(show, args)} is outside the function's domain", _FIX_DOMAIN) from None
        if isinstance(value, complex):
            raise _Fault(
                f"{_operation(show, args)} is outside the domain of ^ (a negative number to a fractional power)",
                _FIX_DOMAIN,
            )
        value = float(value)
        if not math.isfinite(value):
            raise _Fault(f"{_operation(show, args)} overflows", _FIX_OVERFLOW)
        return value

    def run(self, expr: str) -> float:
        value = self.sum()
        if self.i != len(self.tokens):
            raise Unevaluable(f"cannot evaluate {excerpt(expr)}")
        return value

    def peek(self) -> str | None:
        return self.tokens[self.i][1] if self.i < len(self.tokens) else None

    def take(self) -> tuple[str, str]:
        if self.i >= len(self.tokens):
            raise Unevaluable("formula ends too early")
        self.vars.operation(self.where)
        self.i += 1
        return self.tokens[self.i - 1]

    def sum(self) -> float:
        value = self.product()
        while self.peek() in ("+", "-"):
            op = self.take()[1]
            value = self.apply(operator.add if op == "+" else operator.sub, (value, self.product()), "{0}" + op + "{1}")
        return value

    def product(self) -> float:
        value = self.power()
        while self.peek() in ("*", "/"):
            op = self.take()[1]
            value = self.apply(
                operator.mul if op == "*" else operator.truediv, (value, self.power()), "{0}" + op + "{1}"
            )
        return value

    def power(self) -> float:
        value = self.unary()
        while self.peek() == "^":
            self.take()
            exponent = self.unary()
            if exponent == 0:
                raise _Fault(f"{_operation('{0}^{1}', (value, exponent))} is a power by 0", _FIX_POWER_0)
            value = self.apply(operator.pow, (value, exponent), "{0}^{1}")
        return value

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
            return self.apply(float, (text,), "the number {0}")
        if text == "(":
            value = self.sum()
            if self.take()[1] != ")":
                raise Unevaluable("missing ')'")
            return value
        if kind == "name":
            if text.startswith("v_"):
                return self.variable(text[2:])
            if text in CONSTANTS:
                return CONSTANTS[text]
            if text in FUNCTIONS and self.peek() == "(":
                self.take()
                value = self.sum()
                if self.take()[1] != ")":
                    raise Unevaluable(f"{text}() takes one argument here")
                return self.apply(FUNCTIONS[text], (value,), text + "({0})")
        raise Unevaluable(f"{excerpt(text, 30)} is not known before the run")

    def variable(self, name: str) -> float:
        """``v_name``: the variable's text read as a number, as LIGGGHTS'
        ``atof(retrieve(name))`` does (an equal-style value passes through
        ``%.15g``); a text that is not a number is refused, where LIGGGHTS reads 0."""
        text = self.vars.retrieve(name, self.where, self.depth)
        try:
            value = float(text)
        except ValueError:
            raise _Fault(
                f"{excerpt('v_' + name, 30)} is {excerpt(text, 30)}, not a number",
                "give the variable a number (LIGGGHTS would compute with 0 where demsplit refuses).",
            ) from None
        if not math.isfinite(value):
            raise _Fault(
                f"{excerpt('v_' + name, 30)} is {excerpt(text, 30)}, not a finite number",
                "give the variable a finite number.",
            )
        return value


_DOLLAR_OR_QUOTE = re.compile(r"[$\"']")
_PAREN = re.compile(r"[()]")


def substitute(text: str, variables: Variables, where: Where) -> str:
    """Replace ``${name}``, ``$x`` and ``$(expr)`` outside quotes (``Input::substitute``):
    ``${name}`` and ``$x`` by :meth:`Variables.retrieve`, ``$(expr)`` by
    :meth:`Variables.evaluate` in ``%.20g``. The result is at most :data:`MAX_LINE` characters, and counts
    towards the script's :data:`MAX_CHARACTERS`."""
    out, i, n, size = [], 0, len(text), 0
    while True:
        found = _DOLLAR_OR_QUOTE.search(text, i)
        if found is None:
            out.append(text[i:])
            break
        j = found.start()
        if found.group() != "$":  # a quoted part is copied as it is
            end = text.find(found.group(), j + 1)
            stop = n if end < 0 else end + 1
            out.append(text[i:stop])
            i = stop
            continue
        out.append(text[i:j])
        if text.startswith("{", j + 1):
            end = text.find("}", j + 2)
            if end < 0:
                raise ScriptError(
                    f"'${{' without '}}' in: {excerpt(text)}.",
                    file=where.file,
                    line=where.line,
                    fix="close the variable name with '}'.",
                )
            value = variables.retrieve(text[j + 2 : end], where)
            i = end + 1
        elif text.startswith("(", j + 1):
            level, k = 0, j + 2
            for paren in _PAREN.finditer(text, j + 2):
                if paren.group() == ")" and level == 0:
                    k = paren.start()
                    break
                level += 1 if paren.group() == "(" else -1
            else:
                raise ScriptError(
                    f"'$(' without ')' in: {excerpt(text)}.",
                    file=where.file,
                    line=where.line,
                    fix="close the immediate variable with ')'.",
                )
            value = f"{variables.evaluate(text[j + 2 : k], where):.20g}"
            i = k + 1
        elif j + 1 < n:
            value = variables.retrieve(text[j + 1], where)
            i = j + 2
        else:
            raise ScriptError(
                "'$' at the end of a line.",
                file=where.file,
                line=where.line,
                fix="remove the '$' or name a variable after it.",
            )
        out.append(value)
        size += len(value)
        if size + len(text) > MAX_LINE:
            raise ScriptError(
                f"with its variables substituted, the command is longer than {MAX_LINE} characters.",
                file=where.file,
                line=where.line,
                fix=_FIX_BOUND,
            )
    result = "".join(out)
    variables.charge(len(result), where)
    return result
