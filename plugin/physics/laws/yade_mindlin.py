"""YADE ``Law2_ScGeom_MindlinPhys_Mindlin`` (``HertzMindlin.cpp``): Hertz normal force, Mindlin shear.

YADE stores kno = (4/3) E* sqrt(R*) (N/m^1.5) per interaction, with F_n =
kno delta^(3/2); so u_n = (2/5) kno delta^(5/2) (eq. 13), with YADE's own
refR conventions for walls and facets. With ``normal_stiffness="materials"``
(the reader's ``plane_as_plane``) E* and R* are rebuilt from the materials and
the radii the reader gives instead: u_n = (8/15) E* sqrt(R* delta) delta^2.
The shear spring is the stored incremental one: u_t = |F_t|^2 / (2 ks), with F_t the elastic shear force
``shearElastic`` (``shearForce`` is it minus the viscous force when the contact is damped).
With ``includeAdhesion`` the DMT adhesion force F_adh = 4 pi R* gamma that YADE
stores per interaction pulls the bodies together: its work u_adh = -F_adh delta
(J, apart from the elastic total); YADE's ``normElastEnergy()`` is then u_n + u_adh.
A saved state's overlap follows from the stored tangent stiffness kn = (3/2) kno delta^(1/2), whatever
the damping and the adhesion (both change the stored force, not kn).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ...errors import UnsupportedModelError
from ..elastic import hertz_energy_from_moduli, hertz_force_from_moduli, overlap
from ..moduli import effective_modulus, effective_radius, f64
from . import register
from ._yade import KN, KNO, KS, KSO, NORMAL_FORCE, VECTOR, Phys, Table, YadeScGeomLaw, where_known
from .base import ContactRows, LawEnergy

STIFFNESS_SOURCES = ("stored", "materials")


def hertz_energy_from_kno(delta: ArrayLike, kno: ArrayLike) -> np.ndarray:
    """Hertz energy from YADE's stored stiffness: S = (2/5) kno delta^(5/2) (J),
    with F = kno delta^(3/2) and kno = (4/3) E* sqrt(R*) (N/m^1.5)."""
    d = overlap(delta)
    return 0.4 * f64(kno) * np.sqrt(d) * d * d


@register
class YadeMindlin(YadeScGeomLaw):
    key = "yade:Law2_ScGeom_MindlinPhys_Mindlin"
    summary = (
        "Hertz u_n = (2/5) kno delta^(5/2) with YADE's stored kno; Mindlin shear u_t = |F_t|^2/(2 ks) "
        "from the stored shear force and stiffness"
    )
    contact_columns = ("kno",)
    phys = (
        NORMAL_FORCE,
        Phys("shearElastic", "fse", "ft", VECTOR),
        KN,
        KS,
        KNO,
        KSO,
        Phys("adhesionForce", "adhesion", "adhesion_force"),
    )
    parameters = {
        "normal_stiffness": (
            "stored",
            "kno as YADE stored it ('stored'), or rebuilt from the "
            "materials and the radii the reader gives ('materials')",
        ),
        "include_adhesion": (
            False,
            "includeAdhesion: the DMT adhesion force F_adh = 4 pi R* gamma "
            "(stored per interaction) pulls the bodies together",
        ),
    }
    simulator_parameters = {"includeAdhesion": "include_adhesion"}
    simulator_energies = {"mindlin_normElastEnergy": ("normElastEnergy", ("u_n",))}

    def check(self) -> None:
        self.params["include_adhesion"] = bool(self.params["include_adhesion"])
        if self.params["include_adhesion"]:  # YADE's normElastEnergy() then includes -F_adh delta
            self.modes = ("u_n", "u_t", "u_adh")
            self.contact_columns = (*self.contact_columns, "adhesion_force")
            self.simulator_energies = {"mindlin_normElastEnergy": ("normElastEnergy", ("u_n", "u_adh"))}
        if self.params["normal_stiffness"] not in STIFFNESS_SOURCES:
            raise UnsupportedModelError(
                f"{self.key}: normal_stiffness must be one of {STIFFNESS_SOURCES}, "
                f"got {self.params['normal_stiffness']!r}."
            )
        if self.params["normal_stiffness"] == "materials":
            self.contact_columns = tuple(c for c in self.contact_columns if c != "kno")

    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        modes, skipped = self.shear_energy(rows)
        if "kno" in self.contact_columns:
            u_n = hertz_energy_from_kno(rows.delta, rows.column("kno"))
        else:
            u_n = hertz_energy_from_moduli(
                rows.delta, effective_radius(rows.r1, rows.r2), rows.per_pair(effective_modulus)
            )
        if self.params["include_adhesion"]:  # the work of the constant DMT force since first touch
            modes["u_adh"] = -rows.column("adhesion_force") * overlap(rows.delta)
        return LawEnergy({"u_n": u_n, **modes}, skipped)

    def depth_from_phys(self, t: Table) -> np.ndarray:
        """delta = (kn / (1.5 kno))^2, from the tangent stiffness YADE stored; unknown where kn = 0 (a contact
        kept apart by ``neverErase``, whose forces and stiffnesses YADE zeroes)."""
        return where_known(t["kn"] > 0, (t["kn"] / (1.5 * t["kno"])) ** 2)

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        if "kno" not in self.contact_columns:
            return hertz_force_from_moduli(
                rows.delta, effective_radius(rows.r1, rows.r2), rows.per_pair(effective_modulus)
            )
        d = overlap(rows.delta)
        return rows.column("kno") * np.sqrt(d) * d
