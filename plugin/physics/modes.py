"""The energy modes of a contact and the rule that splits each between the two bodies.

A contact law returns its elastic energy mode by mode; the split rule belongs
to the mode, not to the law (docs/design.md, "Energy modes, split rules and completeness"):
whatever law produced the traction, a half-space's surface displacement under
it scales with one compliance, so the share of body 1 is that compliance over
the sum of both.

| mode | column | share column | share of body 1 under the material split |
|---|---|---|---|
| normal | ``u_n`` | ``share_n1`` | c1/(c1 + c2), c = (1 - nu^2)/E (eqs. 14-15) |
| tangential | ``u_t`` | ``share_t1`` | t1/(t1 + t2), t = (2 - nu)/G (Mindlin); ``paper``: (1 - 2 nu)/G |
| rolling (bending) | ``u_r`` | ``share_r1`` | c1/(c1 + c2): an antisymmetric normal traction |
| twisting | ``u_tw`` | ``share_tw1`` | (1/G1)/(1/G1 + 1/G2): a torsional traction |
| cohesion work | ``u_adh`` | none | 1/2: it belongs to the interface, not a body |

The elastic modes sum to the elastic total ``u``; the cohesion work
``u_adh`` (signed: negative where the bond holds the bodies together) is
reported beside it, never added to it. Results always carry ``u_n`` and
``u_t`` (and their shares); ``u_r``, ``u_tw`` and ``u_adh`` only when a law of
the scene has them (:func:`scene_modes`). A law that lacks a mode the scene
has contributes 0 to it and says why (``skipped``). Adding a mode is one
entry here with its rule, plus its columns' units in the results schema.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np

from .shares import normal_share, tangential_share, twisting_share

ShareRule = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def _normal_rule(tangential_rule: str) -> ShareRule:
    return normal_share


def _twisting_rule(tangential_rule: str) -> ShareRule:
    return twisting_share


def _tangential_rule(tangential_rule: str) -> ShareRule:
    return lambda E1, nu1, E2, nu2: tangential_share(E1, nu1, E2, nu2, rule=tangential_rule)


@dataclass(frozen=True)
class Mode:
    """One mode of contact energy: its result columns and its material split rule.

    ``rule(tangential_rule)`` gives the share of body 1 as ``f(E1, nu1, E2, nu2)``
    (``tangential_rule``: ``"mindlin"`` or ``"paper"``, see
    :func:`~demsplit.physics.shares.tangential_share`).
    """

    name: str
    column: str
    share_column: str
    description: str
    rule: Callable[[str], ShareRule]


NORMAL = Mode("normal", "u_n", "share_n1", "normal elastic energy (J), split by (1 - nu^2)/E", _normal_rule)
TANGENTIAL = Mode(
    "tangential", "u_t", "share_t1", "tangential spring energy (J), split by (2 - nu)/G", _tangential_rule
)
ROLLING = Mode("rolling", "u_r", "share_r1", "rolling (bending) spring energy (J), split by (1 - nu^2)/E", _normal_rule)
TWISTING = Mode("twisting", "u_tw", "share_tw1", "twisting spring energy (J), split by 1/G", _twisting_rule)

MODES: tuple[Mode, ...] = (NORMAL, TANGENTIAL, ROLLING, TWISTING)
"""Every elastic mode, in the order of the result columns."""

MODE_COLUMNS: tuple[str, ...] = tuple(m.column for m in MODES)
"""Energy column of every elastic mode: ``("u_n", "u_t", "u_r", "u_tw")``."""

ALWAYS: tuple[Mode, ...] = (NORMAL, TANGENTIAL)
"""The modes every result carries, whatever the laws (0 where a law has none, and said so)."""

ADHESION_COLUMN = "u_adh"
"""Cohesion (adhesion, capillary) work of a contact (J, signed), split 1/2 to each body and
reported apart from the elastic total."""

ADHESION_SHARE = 0.5
"""Share of the cohesion work given to body 1: the work belongs to the interface."""


def scene_modes(columns: Iterable[str]) -> tuple[Mode, ...]:
    """The elastic modes results carry for laws whose modes are ``columns``: :data:`ALWAYS`, then
    every other mode of :data:`MODES` some law has, in the order of :data:`MODES`."""
    columns = set(columns)
    return tuple(m for m in MODES if m in ALWAYS or m.column in columns)


NOT_COMPUTED_BITS: dict[str, int] = {"u_n": 1, "u_t": 2, "u_r": 4, "u_tw": 8, ADHESION_COLUMN: 16}
"""Bit of every mode in a ``not_computed`` column: the bits set name the modes whose value in that
row is unknown (their columns hold 0 there, which is not a measurement). A contact's bits say which
of its modes could not be computed; a particle's or a wall's, which modes of at least one of its
contacts."""


HISTORY_LOST = sum(NOT_COMPUTED_BITS.values())
"""The ``history_unknown`` value of a contact whose history the simulator never wrote: every mode that reads a
history is unknown (a reader that rebuilt part of it sets only the bits of the modes still unknown)."""


def not_computed_modes(bits: int) -> list[str]:
    """The mode columns named by a ``not_computed`` value (``6`` -> ``["u_t", "u_r"]``)."""
    return [mode for mode, bit in NOT_COMPUTED_BITS.items() if int(bits) & bit]
