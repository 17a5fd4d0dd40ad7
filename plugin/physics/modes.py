"""The energy modes of a contact and the rule that splits each between the two bodies.

A contact law returns its elastic energy mode by mode; the split rule belongs
to the mode, not to the law (DESIGN.md, "Energy modes and how each is split"):
whatever law produced the traction, a half-space's surface displacement under
it scales with one compliance, so the share of body 1 is that compliance over
the sum of both.

| mode | column | share column | share of body 1 under the material split |
|---|---|---|---|
| normal | ``u_n`` | ``share_n1`` | c1/(c1 + c2), c = (1 - nu^2)/E (eqs. 14-15) |
| tangential | ``u_t`` | ``share_t1`` | t1/(t1 + t2), t = (2 - nu)/G (Mindlin); ``paper``: (1 - 2 nu)/G |

Results carry one energy column and one share column per mode, in the order
of :data:`MODES`; a law that lacks a mode contributes 0 to it and says why
(``skipped``). Adding a mode (rolling ``u_r``, twisting ``u_tw``, cohesion
``u_adh``) is one entry here with its rule, plus its columns in the results
schema.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .shares import normal_share, tangential_share

ShareRule = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def _normal_rule(tangential_rule: str) -> ShareRule:
    return normal_share


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
TANGENTIAL = Mode("tangential", "u_t", "share_t1", "tangential spring energy (J), split by (2 - nu)/G",
                  _tangential_rule)

MODES: tuple[Mode, ...] = (NORMAL, TANGENTIAL)
"""Every mode, in the order of the result columns."""

MODE_COLUMNS: tuple[str, ...] = tuple(m.column for m in MODES)
"""Energy column of every mode: ``("u_n", "u_t")``."""
