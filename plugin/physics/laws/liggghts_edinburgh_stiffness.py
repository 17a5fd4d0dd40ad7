"""LIGGGHTS ``pair_style gran model edinburgh/stiffness`` (``normal_model_edinburgh_stiffness.h``), without
surface energy.

The Edinburgh elasto-plastic model of :mod:`.liggghts_edinburgh` with the loading
stiffness given per pair of types instead of built from the materials: k1 =
LoadingStiffness (N/m^n, n = overlapExponent), k2 = k1 UnloadingStiffness, and
LIGGGHTS sets kt = kn = k1 for the sub-models (the source divides both by
``force->nktv2p``, 1 in units si). Loading F = k1 delta^n, unloading and
reloading F = k2 (delta^n - dp^n), dp the stored plastic overlap (at most delta);
the elastic energy is what the contact gives back along its unloading curve,

    u_n = k2 [(delta^(n+1) - dp^(n+1))/(n + 1) - dp^n (delta - dp)],

the pull-off force f0 does the work f0 delta (u_adh, apart), and the tangential
spring u_t = k1 |shear|^2/2. The history is that of ``edinburgh`` (dp, the
previous overlap, kc, f0). surfaceEnergy > 0 is refused as for ``edinburgh``.
"""

from __future__ import annotations

import numpy as np

from . import register
from .base import ContactLaw, ContactRows
from .liggghts_edinburgh import LiggghtsEdinburgh


@register
class LiggghtsEdinburghStiffness(LiggghtsEdinburgh):
    key = "liggghts:edinburgh/stiffness"
    summary = (
        "Edinburgh elasto-plastic with given stiffness (loading k1 delta^n, unloading k2 (delta^n - dp^n)), "
        "u_n = the energy given back along the unloading curve; tangential history u_t = k1 |shear|^2/2"
    )
    parameters = {
        **LiggghtsEdinburgh.parameters,
        "loading_stiffness": (ContactLaw.REQUIRED, "LoadingStiffness k1 per type pair (N/m^n)"),
    }
    example_params = {"overlap_exponent": 1.0, "unloading_stiffness": 5.0, "loading_stiffness": 2e5}

    def check(self) -> None:
        super().check()
        self.params["loading_stiffness"] = self.table("loading_stiffness")

    def k1(self, rows: ContactRows) -> np.ndarray:
        """Loading stiffness LoadingStiffness (N/m^n), per row."""
        return np.broadcast_to(rows.type_pair(self.params["loading_stiffness"]), rows.delta.shape)

    def kt(self, rows: ContactRows) -> np.ndarray:
        """kt = k1 (N/m): LIGGGHTS gives the sub-models the loading stiffness as kt."""
        return self.k1(rows)
