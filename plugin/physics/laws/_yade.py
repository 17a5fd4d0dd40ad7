"""What YADE's laws share: the interaction attributes a law reads, the overlap a saved state does not
hold, the moduli of the split, the stored incremental shear spring.

A YADE law declares the attributes of YADE's interaction physics it reads (:class:`Phys`: ``i.phys.kn``,
``i.phys.shearForce``, ...), with their columns in demsplit's snapshot (:mod:`demsplit.yade`) and the
contact columns they become (:mod:`demsplit.readers.yade_snapshot`): the exporter and the reader take
them from the law, so adding a YADE law is adding one file. YADE saves every attribute but the
overlap ``penetrationDepth`` (``Attr::noSave``); :meth:`YadeLaw.depth_from_phys` recovers it from what the
law stored where the stored force or stiffness is an invertible function of it. Not a law itself: the
YADE laws derive from :class:`YadeLaw` (or :class:`YadeScGeomLaw`, with the shear spring).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..elastic import stored_shear_energy
from .base import ContactLaw, ContactRows

Table = Mapping[str, np.ndarray]

SCALAR, VECTOR, NORM = "scalar", "vector", "norm"
"""How an attribute is stored and read: a number; a vector whose components a law reads (a force on
YADE's body 2, whose sign flips when demsplit puts the particle first); a vector whose magnitude a law reads."""


@dataclass(frozen=True)
class Phys:
    """An attribute of YADE's interaction physics (``i.phys.<yade>``) that a law reads.

    ``column``: its name in the snapshot's interactions table (a vector: three columns ``column`` + x, y, z);
    ``contact``: the contact column it gives the law (a ``vector``: ``contact`` + x, y, z; a ``norm``: the
    magnitude), or None for an attribute only :meth:`YadeLaw.depth_from_phys` reads."""

    yade: str
    column: str
    contact: str | None = None
    shape: str = SCALAR

    @property
    def columns(self) -> tuple[str, ...]:
        """Its columns in the snapshot's interactions table."""
        return (self.column,) if self.shape == SCALAR else tuple(self.column + a for a in "xyz")

    @property
    def contact_columns(self) -> tuple[str, ...]:
        """The contact columns it gives (none for a ``contact`` of None)."""
        if self.contact is None:
            return ()
        return tuple(self.contact + a for a in "xyz") if self.shape == VECTOR else (self.contact,)


NORMAL_FORCE = Phys("normalForce", "fn", "fn", NORM)
"""The normal force vector (N; ``fn``: its magnitude)."""
SHEAR_FORCE = Phys("shearForce", "fs", "ft", VECTOR)
"""The stored shear force (N) on YADE's body 2."""
KN, KS = Phys("kn", "kn", "kn"), Phys("ks", "ks", "ks")
"""Normal and shear stiffness (N/m) as the law keeps them."""
KNO, KSO = Phys("kno", "kno", "kno"), Phys("kso", "kso", "kso")
"""MindlinPhys' Hertz constants: F_n = kno delta^(3/2) (N/m^1.5), ks = kso delta^(1/2) (N/m^1.5)."""
SPRINGS = (NORMAL_FORCE, SHEAR_FORCE, KN, KS)
"""What every YADE law with normal and shear springs stores (NormShearPhys)."""

ENGINE_PHYS = {"Law2_ScGeom_CapillaryPhys_Capillarity": (Phys("fCap", "fcap", None, VECTOR),)}
"""Attributes an engine beside the InteractionLoop adds to the physics: the capillary force (N), which
the snapshot reader checks is 0 (its work needs YADE's meniscus tables)."""

SHEAR_COLUMNS = ("ftx", "fty", "ftz", "ks")
"""Contact columns of the incremental shear spring: force (N) and stiffness (N/m)."""


def finite_positive(x: object) -> bool:
    """A finite number > 0 (a JSON value of a material attribute)."""
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and x > 0


def along_normal(t: Table, vector: str) -> np.ndarray:
    """The component of the vector columns ``vector`` + x, y, z along YADE's normal n (``nx ny nz``), per row."""
    return t[vector + "x"] * t["nx"] + t[vector + "y"] * t["ny"] + t[vector + "z"] * t["nz"]


def magnitude(t: Table, vector: str) -> np.ndarray:
    """|v| of the vector columns ``vector`` + x, y, z, per row."""
    return np.sqrt(t[vector + "x"] ** 2 + t[vector + "y"] ** 2 + t[vector + "z"] ** 2)


def where_known(known: np.ndarray, value: np.ndarray) -> np.ndarray:
    """``value`` where ``known``, NaN elsewhere (the rows whose overlap the stored physics does not give)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(known, value, np.nan)


class YadeLaw(ContactLaw):
    """A YADE law: the attributes it reads (``phys``), how a saved state's overlap follows from them, and
    which moduli of a YADE material the split takes.

    ``moduli``: ``"elastic"`` when the law's stiffness comes from ``young`` and ``poisson`` as elastic
    moduli (Hertz-Mindlin), so the split takes (E, nu) = (young, poisson); ``"springs"`` when it comes from
    springs k_i = 2 E_i r_i in series with ``poisson`` the ratio ks/kn (FrictPhys and the laws that build
    on it): the law has no Poisson ratio, so the split takes (young, 0), compliance 1/E, which shares a
    contact of equal radii as the law's own springs do (``--material`` gives other moduli).
    ``tracked_energies``: entries of ``O.energy`` the law fills, each the sum of the given modes."""

    phys: ClassVar[tuple[Phys, ...]] = SPRINGS
    moduli: ClassVar[str] = "elastic"
    tracked_energies: ClassVar[Mapping[str, tuple[str, ...]]] = {}

    SPRINGS_NOTE: ClassVar[str] = (
        "YADE's 'poisson' of {law} is the ratio ks/kn of the material's springs, not a "
        "Poisson ratio: the split takes each material's young as E and nu = 0 "
        "(compliance 1/E); --material ID:E:NU gives other moduli"
    )

    def depth_from_phys(self, t: Table) -> np.ndarray:
        """The overlap delta (m) of each interaction of a saved state, from the attributes the law stored
        (``t``: the snapshot's interaction columns, YADE's order); NaN where they do not give it (the
        reader then takes it from the geometry). Default: nowhere."""
        return np.full(len(t["nx"]), np.nan)

    def split_moduli(self, material: Mapping, physics: Sequence[Mapping] = ()) -> tuple[float, float] | str:
        """(E, nu) of a YADE material (its attributes, ``O.materials[i].dict()``) for the split, or why the
        law gives none (see ``moduli``); ``physics``: the Ip2 functors (class and attributes), which may
        build the stiffness without the materials' moduli."""
        E, nu = material.get("young"), material.get("poisson")
        if not finite_positive(E):
            return f"its young = {E!r} is not a modulus > 0"
        if self.moduli == "springs":
            return float(E), 0.0
        if not (isinstance(nu, (int, float)) and -1 < nu <= 0.5):
            return f"its poisson = {nu!r} is not a Poisson ratio in (-1, 0.5]"
        return float(E), float(nu)

    def moduli_note(self) -> str | None:
        """What the split's moduli are, when they are not the material's own (E, nu)."""
        return self.SPRINGS_NOTE.format(law=self.key) if self.moduli == "springs" else None


class YadeScGeomLaw(YadeLaw):
    """A YADE law with a normal energy (subclasses) and the stored incremental shear spring."""

    modes = ("u_n", "u_t")
    mode_columns = {"u_t": SHEAR_COLUMNS}

    def shear_energy(self, rows: ContactRows) -> tuple[dict[str, np.ndarray], dict[str, str]]:
        """``({"u_t": energy}, {})``, or ``({}, {"u_t": why not})`` when the columns are absent:
        u_t = |F_t|^2/(2 ks) with the stored shear force and stiffness (:data:`SHEAR_COLUMNS`)."""
        why = self.missing_mode(rows, "u_t")
        if why:
            return {}, {"u_t": why}
        ft = np.stack([rows.column(c) for c in SHEAR_COLUMNS[:3]], axis=-1)
        return {"u_t": stored_shear_energy(rows.delta, ft, rows.column("ks"))}, {}


def stored_spring_energy(force: np.ndarray, k: np.ndarray) -> np.ndarray:
    """|F|^2/(2 k) (J) of a spring whose force (or moment) magnitude and stiffness the simulator stored;
    0 where k = 0 (a spring YADE has not set)."""
    return np.divide(force * force, 2.0 * k, out=np.zeros_like(force), where=k > 0)


class YadeStoredSprings(YadeScGeomLaw):
    """A YADE law whose normal and shear springs' forces and stiffnesses are stored and may hold energy
    without overlap (bonds in tension): u_n = |F_n|^2/(2 kn), u_t = |F_s|^2/(2 ks), kept where delta < 0.
    Its stiffnesses are FrictPhys' springs (``moduli = "springs"``)."""

    contact_columns = ("fn", "kn")
    normal_from_stored_force = True
    moduli = "springs"

    def spring_energies(self, rows: ContactRows) -> tuple[dict[str, np.ndarray], dict[str, str]]:
        """``u_n`` and, when its columns are there, ``u_t`` (else the ``skipped`` entry)."""
        modes, skipped = {"u_n": stored_spring_energy(rows.column("fn"), rows.column("kn"))}, {}
        why = self.missing_mode(rows, "u_t")
        if why:
            skipped["u_t"] = why
        else:
            ft = np.sqrt(sum(rows.column(c) ** 2 for c in SHEAR_COLUMNS[:3]))
            modes["u_t"] = stored_spring_energy(ft, rows.column("ks"))
        return modes, skipped

    def normal_force(self, rows: ContactRows) -> np.ndarray:
        return rows.column("fn")

    def separation_limit(self, r1: np.ndarray | float, r2: np.ndarray | float) -> np.ndarray | float:
        """A bond holds at any gap YADE keeps it real (it breaks by the law's strength, not by a distance)."""
        return np.inf
