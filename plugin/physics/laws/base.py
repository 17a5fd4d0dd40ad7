"""What every contact law is: the :class:`ContactLaw` base class and what a law sees of its contacts.

A law is one small class in one file of this package, registered under the
name the simulator uses (``liggghts:hertz``, ``yade:Law2_ScGeom_MindlinPhys_Mindlin``).
It declares the contact columns, particle columns and parameters it needs,
computes the elastic energy of every mode it has (:mod:`demsplit.physics.modes`)
from arrays, and describes itself in one line. It never splits energy between
the bodies (the mode's rule does) and never looks at a model name.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar, Protocol

import numpy as np

from ...errors import UnsupportedModelError

PairRule = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]


class ContactRows(Protocol):
    """The contacts one law acts on, as the law sees them (:class:`demsplit.physics.bodies.LawRows`).

    ``delta`` (m), ``r1``, ``r2`` (m) are float64 arrays of these rows;
    :meth:`column` gives any other contact column of these rows, as float64,
    and raises an error naming the law and the fix when it is missing.
    """

    delta: np.ndarray
    r1: np.ndarray
    r2: np.ndarray

    def has(self, *names: str) -> bool:
        """True when the contacts have every column in ``names``."""

    def column(self, name: str) -> np.ndarray:
        """Contact column ``name`` of these rows (float64)."""

    def per_pair(self, rule: PairRule) -> np.ndarray | float:
        """``rule(E1, nu1, E2, nu2)`` of every row (a scalar in a single-material scene)."""

    def pair_values(self, rule: PairRule) -> tuple[np.ndarray, np.ndarray]:
        """``rule`` for the compiled loops as ``(values, code)`` (see :mod:`demsplit.kernels`)."""

    def reduced_mass(self) -> np.ndarray:
        """m* = m1 m2/(m1 + m2) of every row (kg); a wall has infinite mass."""

    def particle_column(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """Particle column ``name`` of body 1 and of body 2 of every row (float64; body 2 of a wall row: NaN)."""

    def type_pair(self, table: Any) -> np.ndarray | float:
        """A per-type-pair property ``table[t1 - 1][t2 - 1]`` of every row (a scalar if it holds one value)."""


@dataclass
class LawEnergy:
    """Energy of every mode a law has, per contact row (J), and the modes it could not compute, with why.

    ``skipped``: per mode the law has but cannot compute from the columns given (not dumped), why; the
    partition calls these *missing* and refuses the run for them unless ``--allow-missing MODE``.
    ``unknown``: per mode, the rows whose value the law could not know from the data (a boolean array);
    for a mode named there the law has itself decided which rows without a written history
    (``history_unknown``) are unknown, instead of all of them. ``unknown_why``: per mode of ``unknown``, why
    its rows are unknown, when the run must be refused for them unless the user lets it go on
    (``--allow-missing MODE``), as for a mode whose columns were not dumped."""

    modes: dict[str, np.ndarray]
    skipped: dict[str, str] = field(default_factory=dict)
    unknown: dict[str, np.ndarray] = field(default_factory=dict)
    unknown_why: dict[str, str] = field(default_factory=dict)


class ContactLaw(ABC):
    """A contact law of a simulator (see the module docstring).

    Class attributes a law sets:

    ``key``
        registry name, ``simulator:name`` as the simulator spells it;
    ``summary``
        one line: what the law is and which energies it gives, with the equation;
    ``modes``
        energy columns it computes (``u_n``, ``u_t``; :mod:`demsplit.physics.modes`);
    ``contact_columns``
        contact columns it needs beyond the canonical ones (``demsplit.frame``);
    ``mode_columns``
        per mode, the contact columns without which that mode is not computed
        (and said so) rather than refused;
    ``particle_columns``
        particle columns it needs (``mass`` for LIGGGHTS hooke);
    ``parameters``
        name -> (default or ``REQUIRED``, meaning with unit);
    ``comparison_splits``
        the naive splits reported beside the distribution law for it;
    ``compiled``
        it has a compiled path whose results must equal its numpy path;
    ``simulator_energies``
        the simulator's own energy functions of the law, for validation:
        name in the snapshot's ``law_energies`` -> method of the law functor
        (YADE's ``normElastEnergy``), and the modes whose sum it equals;
    ``example_params``
        parameters of a typical run, for the registry-wide tests and the docs;
    ``simulator_parameters``
        the simulator's name of a value its run defines (an attribute of YADE's Law2 functor, a LIGGGHTS
        ``fix property/global``) -> the parameter of this law it gives, where the law declares that
        parameter: the readers take the law's parameters from the run through this map;
    ``simulator_settings``
        a switch of the simulator's model line (LIGGGHTS ``ktToKnUser on``) -> ``(parameter, value when
        on, value when off)``;
    ``normal_from_stored_force``
        the normal energy comes from a force the simulator stored (a cohesive bond
        holds energy in tension, at delta < 0), not from delta: the properties "no
        energy without overlap" and "dU_n/d(delta) is the normal force" do not apply.

    A law whose contacts act across a gap (a liquid bridge, a bond) says how far with
    :meth:`separation_limit`; one whose contacts may overlap beyond the smaller radius (a JCFpm smooth joint)
    says how deep with :meth:`overlap_limit`.
    """

    REQUIRED: ClassVar[object] = object()

    key: ClassVar[str]
    summary: ClassVar[str]
    modes: ClassVar[tuple[str, ...]]
    contact_columns: ClassVar[tuple[str, ...]] = ()
    mode_columns: ClassVar[Mapping[str, tuple[str, ...]]] = {}
    particle_columns: ClassVar[tuple[str, ...]] = ()
    parameters: ClassVar[Mapping[str, tuple[Any, str]]] = {}
    comparison_splits: ClassVar[tuple[str, ...]] = ("equal", "radius")
    compiled: ClassVar[bool] = False
    simulator_energies: ClassVar[Mapping[str, tuple[str, tuple[str, ...]]]] = {}
    example_params: ClassVar[Mapping[str, Any]] = {}
    normal_from_stored_force: ClassVar[bool] = False
    simulator_parameters: ClassVar[Mapping[str, str]] = {}
    simulator_settings: ClassVar[Mapping[str, tuple[str, Any, Any]]] = {}

    def __init__(self, params: Mapping[str, Any] | None = None) -> None:
        params = dict(params or {})
        unknown = sorted(set(params) - set(self.parameters))
        if unknown:
            raise UnsupportedModelError(
                f"contact law {self.key}: unknown parameter(s) {unknown}; it takes {sorted(self.parameters)}."
            )
        for name, (default, meaning) in self.parameters.items():
            if name not in params:
                if default is ContactLaw.REQUIRED:
                    raise UnsupportedModelError(
                        f"contact law {self.key} needs the parameter {name!r} ({meaning}).",
                        fix=f"give {name} in the scene's model parameters.",
                    )
                params[name] = default
        self.params: dict[str, Any] = params
        self.check()

    def check(self) -> None:
        """Validate ``self.params`` (raise a :class:`~demsplit.errors.DemsplitError`); default: nothing to check."""

    @abstractmethod
    def energies(self, rows: ContactRows, *, compiled: bool = True) -> LawEnergy:
        """Elastic energy of every mode of the contacts ``rows`` (J). ``compiled``:
        use the compiled path where the law has one (:attr:`compiled`)."""

    @abstractmethod
    def normal_force(self, rows: ContactRows) -> np.ndarray:
        """Elastic normal force of the contacts ``rows`` (N): the derivative dU_n/d(delta)."""

    def separation_limit(self, r1: np.ndarray | float, r2: np.ndarray | float) -> np.ndarray | float:
        """The largest gap -delta (m) at which the simulator writes a contact of this law between bodies of radii
        ``r1`` and ``r2`` (r2 = inf: a wall): a contact further apart is not its output. 0 for a law whose
        contacts end when the bodies part (delta <= 0 is then no contact)."""
        return 0.0

    def overlap_limit(self, contacts: Mapping[str, np.ndarray]) -> np.ndarray | None:
        """The largest overlap delta (m) the simulator gives each contact of this law (``contacts``: the contact
        columns of its rows), beyond which a contact is not a plausible output of the law; None: the smaller of
        r1 and r2 (a sphere overlapped deeper than its radius is a broken dump, not a DEM contact)."""
        return None

    def describe(self) -> str:
        """One line for ``info``/``check``: the key, its parameters (but those unset or ``off``) and the summary."""
        shown = ", ".join(f"{k}={v!r}" for k, v in sorted(self.params.items()) if v is not None and v != "off")
        return f"{self.key}" + (f" ({shown})" if shown else "") + f": {self.summary}"

    @classmethod
    def run_parameters(cls) -> dict[str, str]:
        """The entries of :attr:`simulator_parameters` whose parameter this law has: what a reader reads
        from the run for it (simulator name -> parameter)."""
        return {name: param for name, param in cls.simulator_parameters.items() if param in cls.parameters}

    def needs(self) -> tuple[str, ...]:
        """Every contact column this law reads when it can (required and per-mode)."""
        return tuple(dict.fromkeys([*self.contact_columns, *(c for cols in self.mode_columns.values() for c in cols)]))

    def missing_mode(self, rows: ContactRows, mode: str) -> str | None:
        """Why ``mode`` cannot be computed from these contacts (its columns are absent), or None."""
        cols = self.mode_columns.get(mode, ())
        if rows.has(*cols):
            return None
        return (
            f"the contact data has no {' '.join(cols)} columns, so the {mode} energy of {self.key} cannot be computed"
        )
