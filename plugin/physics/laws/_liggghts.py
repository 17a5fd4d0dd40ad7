"""What LIGGGHTS' sphere models share: the ``tangential`` choice and the history spring.

LIGGGHTS composes a contact from a normal model, which also sets the
tangential stiffness kt, and a tangential model; ``tangential history`` keeps
a spring displacement ``shear`` (m) per contact with F_t = -kt shear, so its
energy is kt |shear|^2 / 2 (``tangential_model_history.h``);
``no_history`` keeps none. Not a law itself: the normal-model laws derive
from :class:`LiggghtsNormalModel`.
"""

from __future__ import annotations

import numpy as np

from ...errors import UnsupportedModelError
from .base import ContactLaw, ContactRows

SHEAR = ("shearx", "sheary", "shearz")
"""Contact columns of the tangential spring history (m)."""

TANGENTIAL_MODELS = ("history", "no_history")


class LiggghtsNormalModel(ContactLaw):
    """A LIGGGHTS normal model with its ``tangential`` model as a parameter."""

    modes = ("u_n", "u_t")
    mode_columns = {"u_t": SHEAR}
    parameters = {"tangential": ("history", "LIGGGHTS tangential model: history or no_history")}

    def check(self) -> None:
        tangential = self.params["tangential"]
        if tangential not in TANGENTIAL_MODELS:
            raise UnsupportedModelError(f"{self.key}: tangential model {tangential!r} is not supported; "
                                        f"it takes {', '.join(TANGENTIAL_MODELS)}.")
        if tangential == "no_history":
            self.modes = ("u_n",)
            self.mode_columns = {}

    def shear_state(self, rows: ContactRows) -> tuple[bool, dict[str, str]]:
        """Whether the tangential spring energy can be computed, and the ``skipped`` entry if not."""
        if "u_t" not in self.modes:
            return False, {}
        why = self.missing_mode(rows, "u_t")
        return (False, {"u_t": why}) if why else (True, {})

    @staticmethod
    def shear(rows: ContactRows) -> np.ndarray:
        """The spring displacement of every row, shape (n, 3) (m)."""
        return np.stack([rows.column(c) for c in SHEAR], axis=-1)
