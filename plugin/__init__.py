"""demsplit: per-particle elastic contact energy for YADE, LIGGGHTS and LAMMPS GRANULAR runs.

Each contact's elastic energy (normal and tangential, with the contact law the
run used) is split between the two bodies by the Feng & Gao distribution law,
and the contact point is placed by the same ratio.

The physics core (:mod:`demsplit.physics`) needs only numpy and is imported
eagerly, so ``demsplit.yade`` works inside YADE's own Python. Everything that
needs pandas, h5py or matplotlib is imported on first use.
"""

from __future__ import annotations

from importlib import import_module

# isort: off
from .runtime import command  # noqa: F401 (first: sets the demsplit command's process up before numpy loads)

# isort: on
from .errors import (
    ContactError,
    DemsplitError,
    InputFormatError,
    MaterialError,
    PrecisionError,
    ScriptError,
    StoreError,
    TruncatedFileError,
    UnsupportedModelError,
)
from .frame import Box, Frame
from .physics.elastic import (
    hertz_energy,
    hertz_force,
    hooke_energy,
    power_law_energy,
    shear_spring_energy,
    tangential_spring_energy,
)
from .physics.laws.yade_mindlin import hertz_energy_from_kno
from .physics.moduli import (
    effective_modulus,
    effective_radius,
    effective_shear_modulus,
    mindlin_compliance,
    plane_strain_compliance,
)
from .physics.partition import ContactEnergy, contact_energies, partition, per_particle
from .physics.shares import contact_point, normal_share, overlap_depths, radius_share, springs_share, tangential_share
from .scene import ContactModel, Material, Scene, Wall

__version__ = "0.1.0"

# name -> module that defines it; imported on first access (PEP 562)
_LAZY = {
    "analyze": "demsplit.pipeline",
    "Results": "demsplit.results",
    "load_results": "demsplit.results",
    "open_run": "demsplit.readers",
}


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'demsplit' has no attribute {name!r}")


__all__ = [
    "Box",
    "ContactEnergy",
    "ContactError",
    "ContactModel",
    "DemsplitError",
    "Frame",
    "InputFormatError",
    "Material",
    "MaterialError",
    "PrecisionError",
    "Scene",
    "ScriptError",
    "StoreError",
    "TruncatedFileError",
    "UnsupportedModelError",
    "Wall",
    "contact_energies",
    "contact_point",
    "effective_modulus",
    "effective_radius",
    "effective_shear_modulus",
    "hertz_energy",
    "hertz_energy_from_kno",
    "hertz_force",
    "hooke_energy",
    "mindlin_compliance",
    "normal_share",
    "overlap_depths",
    "partition",
    "per_particle",
    "plane_strain_compliance",
    "power_law_energy",
    "radius_share",
    "shear_spring_energy",
    "springs_share",
    "tangential_share",
    "tangential_spring_energy",
    *_LAZY,
]
