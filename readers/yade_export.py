"""YADE's own ``yade.export.VTKExporter`` files (legacy ASCII VTK: spheres, interactions) as a run.

:class:`YadeVtkRun` reads a series of ``NAME-spheres-N.vtk`` files, each with
its ``NAME-intrs-N.vtk``; the materials, the law and the walls' material are
not in the files and come as options. ``yade.export.text``/``textExt`` sphere
files are not read: they hold no wall, facet or box contact at all, so a run
read from them could not be whole.

All of them print ``%g`` (6 significant digits). An overlap recomputed from
such positions, delta = r1 + r2 - |x2 - x1|, has an absolute error up to
sqrt(3) h, with h = 10^(floor(log10 max|x|) - 5) the last printed digit of the
coordinates; its relative bound sqrt(3) h / delta is computed per contact and
the frame is refused with :class:`~demsplit.errors.PrecisionError` when the
largest bound exceeds ``tolerance``. A dumped ``penetrationDepth`` (a VTK
``what`` field) is used instead when present: rounding delta itself to 6
digits costs at most 5e-6 relative. For full precision use
:func:`demsplit.yade.snapshot`.

What the files hold (yade 2023.02a, py/export.py):

- ``exportSpheres``: sphere centres (wrapped into the periodic cell), ``radius``,
  and the ``what`` point fields; demsplit needs ``what=dict(id='b.id',
  matId='b.material.id')``.
- ``exportInteractions``: for each real interaction two points, the centre of
  body 1 and the centre of body 2 + hSize.cellDist (unwrapped, so consistent
  with each other), and the ``what`` cell fields. demsplit needs ``id1``,
  ``id2`` and reads, when present, ``penetrationDepth``, ``normal``,
  ``refR1``, ``refR2``, ``contactPoint`` and the physics' attributes the law
  reads, each in the field named as YADE's attribute (``kno``, ``kso``, ``kn``,
  ``ks``, ``normalForce``, ``shearForce``; Hertz-Mindlin's ``shearElastic``; the
  law's ``phys``). Without ``what`` the file has no data.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
from demsplit.errors import InputFormatError, MaterialError, PrecisionError
from demsplit.frame import Box, Frame, Table, describe_steps
from demsplit.physics.laws import simulator_words
from demsplit.physics.laws._yade import SCALAR, SPRINGS, Phys
from demsplit.scene import ContactModel, Material, Scene, Wall

from .base import MATERIALS, OVERLAP_TOLERANCE, Option, Run
from .precision import position_error, printed_step
from .yade_snapshot import particle_first

SNAPSHOT_FIX = (
    "write full-precision snapshots with demsplit.yade.snapshot() from a PyRunner "
    "(see docs/yade.md), or raise the tolerance"
)
VTK_ID_FIX = (
    "export with VTKExporter.exportSpheres(what=dict(id='b.id', matId='b.material.id')) and "
    "exportInteractions(what=dict(id1='i.id1', id2='i.id2', "
    "penetrationDepth='i.geom.penetrationDepth', ...))"
)
VTK_MAGIC = b"# vtk DataFile"
"""The first bytes of a legacy VTK file."""
PERCENT_G_DIGITS = 6
PERCENT_G_MAX_INT = 999_999
"""Integers above this are printed by ``%g`` as ``1.23457e+06``: ids destroyed."""


# --------------------------------------------------------------------------
# Legacy ASCII VTK
# --------------------------------------------------------------------------


class VtkPolyData:
    """The parts of a legacy ASCII POLYDATA file that VTKExporter writes:
    ``points`` (n, 3), ``lines`` (m, 2) point indices or None, and
    ``point_data`` / ``cell_data`` name -> array ((n,), (n, 3) or (n, 3, 3))."""

    def __init__(
        self,
        path: Path,
        comment: str,
        points: np.ndarray,
        lines: np.ndarray | None,
        point_data: dict[str, np.ndarray],
        cell_data: dict[str, np.ndarray],
    ) -> None:
        self.path, self.comment = path, comment
        self.points, self.lines = points, lines
        self.point_data, self.cell_data = point_data, cell_data


_COMPONENTS = {"SCALARS": 1, "VECTORS": 3, "NORMALS": 3, "TENSORS": 9}


def read_vtk(path: str | Path) -> VtkPolyData:
    """Parse a legacy ASCII VTK POLYDATA file (as written by VTKExporter).

    The header (3 lines) is read as text; the body is split into tokens once
    and each numeric block converted by numpy.
    """
    path = Path(path)
    text = path.read_text()
    head = text.split("\n", 3)
    if len(head) < 4 or not head[0].startswith(VTK_MAGIC.decode()):
        raise InputFormatError(
            f"not a legacy VTK file: first line {head[0][:40]!r}, expected '# vtk DataFile ...'.",
            file=path,
            line=1,
            fix="give a file written by yade.export.VTKExporter.",
        )
    if head[2].strip() != "ASCII":
        raise InputFormatError(
            f"expected an ASCII VTK file, found {head[2].strip()!r}.",
            file=path,
            line=3,
            fix="give a file written by yade.export.VTKExporter (ASCII).",
        )
    tokens = head[3].split()
    pos = 0

    def numbers(count: int, what: str) -> np.ndarray:
        nonlocal pos
        block = tokens[pos : pos + count]
        if len(block) < count:
            raise InputFormatError(
                f"{what}: expected {count} numbers, the file ends after {len(block)}.",
                file=path,
                fix="the export was cut short; export again.",
            )
        try:
            values = np.array(block, dtype=np.float64)
        except ValueError:
            bad = next(t for t in block if not _is_number(t))
            raise InputFormatError(
                f"{what}: expected {count} numbers, found {bad!r} among them.",
                file=path,
                fix="the file is damaged or not VTKExporter's; export again.",
            ) from None
        pos += count
        return values

    points = lines = None
    point_data: dict[str, np.ndarray] = {}
    cell_data: dict[str, np.ndarray] = {}
    target, n_target = None, 0
    while pos < len(tokens):
        key = tokens[pos]
        if key == "DATASET":
            if tokens[pos + 1] != "POLYDATA":
                raise InputFormatError(
                    f"expected DATASET POLYDATA, found DATASET {tokens[pos + 1]}.",
                    file=path,
                    fix="give a sphere or interaction file of yade.export.VTKExporter.",
                )
            pos += 2
        elif key == "POINTS":
            n = int(tokens[pos + 1])
            pos += 3
            points = numbers(3 * n, "POINTS").reshape(n, 3)
        elif key == "LINES":
            n, size = int(tokens[pos + 1]), int(tokens[pos + 2])
            pos += 3
            conn = numbers(size, "LINES").astype(np.int64).reshape(n, size // n)
            if (conn[:, 0] != 2).any():
                raise InputFormatError(
                    "LINES with other than 2 points per line.",
                    file=path,
                    fix="give an interaction file of yade.export.VTKExporter.",
                )
            lines = conn[:, 1:]
        elif key in ("POINT_DATA", "CELL_DATA"):
            n_target = int(tokens[pos + 1])
            target = point_data if key == "POINT_DATA" else cell_data
            pos += 2
        elif key in _COMPONENTS:
            if target is None:
                raise InputFormatError(
                    f"{key} before POINT_DATA/CELL_DATA.",
                    file=path,
                    fix="give a file written by yade.export.VTKExporter.",
                )
            name = tokens[pos + 1]
            ncomp = _COMPONENTS[key]
            pos += 3
            if key == "SCALARS":
                if tokens[pos] != "LOOKUP_TABLE":  # optional component count
                    ncomp = int(tokens[pos])
                    pos += 1
                pos += 2  # LOOKUP_TABLE default
            values = numbers(ncomp * n_target, f"{key} {name}")
            shape = {1: (n_target,), 3: (n_target, 3), 9: (n_target, 3, 3)}.get(ncomp, (n_target, ncomp))
            target[name] = values.reshape(shape)
        else:
            raise InputFormatError(
                f"unexpected keyword {key!r} in the VTK body.",
                file=path,
                fix="give a sphere or interaction file of yade.export.VTKExporter.",
            )
    if points is None:
        raise InputFormatError("no POINTS section.", file=path, fix="give a file written by yade.export.VTKExporter.")
    return VtkPolyData(path, head[1], points, lines, point_data, cell_data)


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


# --------------------------------------------------------------------------
# Precision of %g numbers
# --------------------------------------------------------------------------


def overlap_error_bound(x1: np.ndarray, x2: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """Relative error bound sqrt(3) h / delta of overlaps recomputed from ``%g``
    centres ``x1``, ``x2`` (shape (n, 3), m), with h the last printed digit of
    the largest coordinate of the pair (inf where delta <= 0)."""
    h = printed_step(np.maximum(np.abs(x1).max(axis=1), np.abs(x2).max(axis=1)), PERCENT_G_DIGITS)
    return position_error(h, delta)


def check_overlap_precision(bound: np.ndarray, tolerance: float, *, path: Path, step: int | None, what: str) -> None:
    """Raise :class:`PrecisionError` when the worst relative bound exceeds ``tolerance``."""
    if len(bound) and bound.max() > tolerance:
        worst = int(np.argmax(bound))
        raise PrecisionError(
            f"overlaps recomputed from {what} ({PERCENT_G_DIGITS} significant digits) carry a relative error "
            f"up to {bound[worst]:.3g} (contact row {worst}; {int((bound > tolerance).sum())} of {len(bound)} "
            f"contacts above the tolerance {tolerance:g}).",
            file=path,
            step=step,
            fix=SNAPSHOT_FIX + ".",
        )


def check_percent_g_ids(ids: np.ndarray, *, path: Path, what: str) -> np.ndarray:
    """Ids printed with ``%g`` as int64; refuse ids that %g has destroyed."""
    ids = np.asarray(ids, dtype=np.float64)
    if (ids > PERCENT_G_MAX_INT).any() or (ids != np.rint(ids)).any():
        raise PrecisionError(
            f"{what} are printed with %g, which keeps 6 digits: ids above {PERCENT_G_MAX_INT} are destroyed "
            f"(largest here {ids.max():g}).",
            file=path,
            fix=SNAPSHOT_FIX.split(", or")[0] + ".",
        )
    return ids.astype(np.int64)


# --------------------------------------------------------------------------
# Frames from VTKExporter files
# --------------------------------------------------------------------------


def _missing(have: dict, need: tuple[str, ...], *, path: Path, what: str, fix: str) -> None:
    missing = [n for n in need if n not in have]
    if missing:
        raise InputFormatError(
            f"the {what} lacks the field(s) {missing} (it has {sorted(have)}).", file=path, fix=fix + "."
        )


def vtk_particles(spheres: VtkPolyData, *, default_type: int | None = None) -> Table:
    """Particles table from an ``exportSpheres`` file with ``id`` and
    ``matId`` (or ``materialId``) point fields; ``default_type`` stands in for
    a missing material field."""
    pdata = spheres.point_data
    _missing(pdata, ("radius", "id"), path=spheres.path, what="sphere file", fix=VTK_ID_FIX)
    ids = check_percent_g_ids(pdata["id"], path=spheres.path, what="sphere ids")
    mat_field = next((k for k in ("matId", "materialId", "material") if k in pdata), None)
    if mat_field is None and default_type is None:
        raise MaterialError(
            f"the sphere file has no material id field (fields: {sorted(pdata)}), so the material of each "
            "sphere is unknown.",
            file=spheres.path,
            fix=VTK_ID_FIX + ", or pass default_type=",
        )
    n = len(spheres.points)
    types = (
        check_percent_g_ids(pdata[mat_field], path=spheres.path, what="material ids")
        if mat_field
        else np.full(n, default_type)
    )
    return {
        "id": ids,
        "type": types.astype(np.int32),
        "x": spheres.points[:, 0],
        "y": spheres.points[:, 1],
        "z": spheres.points[:, 2],
        "radius": pdata["radius"],
    }


def vtk_frame(
    spheres_path: str | Path,
    interactions_path: str | Path | None = None,
    *,
    tolerance: float = 1e-3,
    step: int | None = None,
    default_type: int | None = None,
    wall_ids: list[int] | None = None,
    box: Box | None = None,
    attributes: tuple[Phys, ...] = SPRINGS,
) -> tuple[Frame, np.ndarray]:
    """One Frame from VTKExporter's sphere file and (optionally) interaction file.

    ``delta`` is the dumped ``penetrationDepth`` field when present (``%g`` of
    delta: error <= 5e-6 relative), otherwise recomputed from the two printed
    centres and the sphere radii (refused above ``tolerance``, see the module
    docstring). Contacts whose partner is not in the sphere file are wall,
    facet or box contacts: they need ``penetrationDepth``, ``normal``,
    ``refR1`` and ``refR2`` fields; their wall index is the position of the
    body id in ``wall_ids`` (default: the sorted non-sphere ids found).
    ``step`` defaults to the number in the file name (VTKExporter's numLabel).
    ``attributes``: the interaction physics the run's law reads (its ``phys``), each taken from the field
    named as YADE's attribute (``normalForce``, ``shearElastic``, ``kno``, ...) when the file has it.
    Returns the frame and the wall body ids (wall index k is body ``wall_ids[k]``).
    """
    spheres = read_vtk(spheres_path)
    if step is None:
        digits = "".join(c for c in Path(spheres_path).stem.rsplit("-", 1)[-1] if c.isdigit())
        step = int(digits) if digits else 0
    particles = vtk_particles(spheres, default_type=default_type)
    notes = ["YADE VTKExporter export (%g)"]
    if interactions_path is None:
        return Frame(
            step=step,
            particles=particles,
            contacts={},
            box=box,
            source=(str(spheres_path),),
            notes=notes + ["no interaction file: no contacts"],
        ), np.zeros(0, np.int64)
    inter = read_vtk(interactions_path)
    path = inter.path
    cdata = inter.cell_data
    _missing(cdata, ("id1", "id2"), path=path, what="interaction file", fix=VTK_ID_FIX)
    id1 = check_percent_g_ids(cdata["id1"], path=path, what="interaction id1 values")
    id2 = check_percent_g_ids(cdata["id2"], path=path, what="interaction id2 values")
    p = inter.points[inter.lines] if inter.lines is not None else inter.points.reshape(-1, 2, 3)
    xa, xb = p[:, 0], p[:, 1]

    sorted_ids = np.sort(particles["id"])
    order = np.argsort(particles["id"])

    def sphere_row(ids: np.ndarray) -> np.ndarray:
        k = np.clip(np.searchsorted(sorted_ids, ids), 0, max(len(sorted_ids) - 1, 0))
        found = sorted_ids[k] == ids if len(sorted_ids) else np.zeros(len(ids), bool)
        return np.where(found, order[k], -1)

    ra, rb = sphere_row(id1), sphere_row(id2)
    sa, sb = ra >= 0, rb >= 0
    pair = sa & sb
    if not (sa | sb).all():
        i = int(np.flatnonzero(~(sa | sb))[0])
        raise InputFormatError(
            f"interaction {id1[i]}-{id2[i]}: neither body is in the sphere file.",
            file=path,
            step=step,
            fix="export all spheres (ids='all') at the same iteration.",
        )
    if not pair.all():
        _missing(
            cdata,
            ("penetrationDepth", "normal", "refR1", "refR2"),
            path=path,
            what="interaction file (needed for wall/facet/box contacts, whose geometry is not exported)",
            fix=VTK_ID_FIX,
        )
    others = np.concatenate([id1[~sa], id2[~sb]])
    wall_ids = np.unique(others) if wall_ids is None else np.asarray(wall_ids, dtype=np.int64)
    unknown = np.setdiff1d(others, wall_ids)
    if len(unknown):
        raise InputFormatError(
            f"bodies {unknown.tolist()} are neither spheres of the sphere file nor in wall_ids.",
            file=path,
            step=step,
            fix="list every wall, facet and box body id in wall_ids.",
        )
    wall_order = np.argsort(wall_ids)

    def wall_index(ids: np.ndarray, is_sphere: np.ndarray) -> np.ndarray:
        k = np.searchsorted(wall_ids[wall_order], ids) if len(wall_ids) else np.zeros(len(ids), np.int64)
        return np.where(is_sphere, -1, wall_order[np.clip(k, 0, max(len(wall_ids) - 1, 0))] if len(wall_ids) else -1)

    wall1, wall2 = wall_index(id1, sa), wall_index(id2, sb)

    radius = particles["radius"]
    refR1 = cdata["refR1"] if "refR1" in cdata else radius[np.maximum(ra, 0)]
    refR2 = cdata["refR2"] if "refR2" in cdata else radius[np.maximum(rb, 0)]
    if "penetrationDepth" in cdata:
        delta = cdata["penetrationDepth"]
        overlap_source = "VTK penetrationDepth field (%g: <= 5e-6 relative)"
        bound = np.full(len(delta), 5e-6)
    else:
        delta = refR1 + refR2 - np.linalg.norm(xb - xa, axis=1)
        bound = overlap_error_bound(xa, xb, delta)
        check_overlap_precision(bound, tolerance, path=path, step=step, what="VTKExporter's %g centres")
        overlap_source = "recomputed from VTK %g centres"
    if "normal" in cdata:
        normal = cdata["normal"]
    else:
        d = xb - xa
        normal = d / np.linalg.norm(d, axis=1)[:, None]
    t = {
        "id1": id1,
        "id2": id2,
        "delta": delta,
        "nx": normal[:, 0],
        "ny": normal[:, 1],
        "nz": normal[:, 2],
        "refR1": refR1,
        "refR2": refR2,
        "xa": xa[:, 0],
        "ya": xa[:, 1],
        "za": xa[:, 2],
        "xb": xb[:, 0],
        "yb": xb[:, 1],
        "zb": xb[:, 2],
    }
    if "contactPoint" in cdata:
        t.update({"cp" + a: cdata["contactPoint"][:, k] for k, a in enumerate("xyz")})
    for a in attributes:
        if a.yade in cdata:
            t.update(
                {a.column: cdata[a.yade]}
                if a.shape == SCALAR
                else {c: cdata[a.yade][:, k] for k, c in enumerate(a.columns)}
            )
    contacts = particle_first(t, sa, wall1, wall2, attributes)
    types = particles["type"]
    contacts["type1"] = types[np.where(sa, ra, rb)]
    # wall types are not in the export: they come from the scene's wall list
    keep = ~(contacts["delta"] < 0)  # a NaN depth is kept, for the validation to name it
    if not keep.all():
        notes.append(f"{int((~keep).sum())} interaction(s) with negative overlap left out (no elastic energy)")
        contacts = {c: v[keep] for c, v in contacts.items()}
        bound = bound[keep]
    if len(wall_ids):
        notes.append(f"wall index k is YADE body wall_ids[k], wall_ids = {wall_ids.tolist()}")
    return Frame(
        step=step,
        particles=particles,
        contacts=contacts,
        box=box,
        source=(str(spheres_path), str(interactions_path)),
        overlap_source=overlap_source,
        overlap_error=bound,
        notes=notes,
    ), wall_ids


# --------------------------------------------------------------------------
# The run: a series of VTKExporter files
# --------------------------------------------------------------------------

_SPHERES = re.compile(r"^(?P<base>.*)-spheres-(?P<step>\d+)\.vtk$")


def vtk_series(path: Path) -> tuple[np.ndarray, list[Path]]:
    """The steps (int64) and sphere files of the series the sphere file ``path`` belongs to: every
    ``NAME-spheres-N.vtk`` of its directory, ordered by N."""
    match = _SPHERES.match(path.name)
    if match is None:
        raise InputFormatError(
            "not a VTKExporter sphere file name (NAME-spheres-N.vtk).",
            file=path,
            fix="give the spheres file of exportSpheres(numLabel=O.iter).",
        )
    found = sorted(
        (int(m.group("step")), p)
        for p in path.parent.iterdir()
        if (m := _SPHERES.match(p.name)) and m.group("base") == match.group("base")
    )
    return np.array([step for step, _ in found], dtype=np.int64), [p for _, p in found]


def interactions_file(spheres: Path) -> Path:
    """The ``NAME-intrs-N.vtk`` beside the sphere file ``NAME-spheres-N.vtk`` (it may not exist)."""
    return spheres.with_name(_SPHERES.sub(r"\g<base>-intrs-\g<step>.vtk", spheres.name))


def is_vtk_part(path: Path, head: bytes) -> bool:
    """Whether ``path`` (first bytes ``head``) is a legacy VTK file that is not a run's sphere file
    (VTKExporter's interactions file, say): part of a run, for ``demsplit info``."""
    return head.startswith(VTK_MAGIC) and not YadeVtkRun.detect(path, head)


def describe_vtk(path: Path) -> str:
    """What ``demsplit info`` prints about a VTK file that is part of a run (:func:`is_vtk_part`)."""
    return "\n".join(
        _vtk_lines(path)
        + ["  not a run of its own: demsplit reads NAME-spheres-N.vtk, with NAME-intrs-N.vtk beside it"]
    )


def _vtk_lines(path: Path) -> list[str]:
    """One legacy VTK file in words: its points, lines and data fields."""
    data = read_vtk(path)
    return [
        f"{path}: legacy VTK file ({data.comment.strip()})",
        f"  points:   {len(data.points)}" + ("" if data.lines is None else f", lines: {len(data.lines)}"),
        "  point fields: " + (", ".join(sorted(data.point_data)) or "none"),
        "  cell fields:  " + (", ".join(sorted(data.cell_data)) or "none"),
    ]


class YadeVtkRun(Run):
    """VTKExporter files of a YADE run (module docstring).

    ``path``: one ``NAME-spheres-N.vtk`` file; every ``NAME-spheres-*.vtk`` of
    its directory is a frame (ordered by N), read with its ``NAME-intrs-N.vtk``.
    ``materials`` (YADE material id -> Material), ``law`` (a ``yade:`` key of the
    law registry) and, when there are wall, facet or box contacts, ``wall_type``
    (their material id) are required: the files do not hold them.
    """

    format_name = "yade-vtk"
    formats = (
        "YADE VTKExporter files (NAME-spheres-N.vtk beside NAME-intrs-N.vtk) with --material for every "
        "material id, --law and --wall-type",
    )
    cli_group = "YADE inputs"
    cli_options = (
        MATERIALS,
        Option(
            "law",
            ("--law",),
            "the run's contact law, for YADE VTKExporter files (which do not hold it): "
            + ", ".join(simulator_words("yade").values()),
            {"choices": tuple(simulator_words("yade").values()), "metavar": "LAW"},
        ),
        Option(
            "wall_type",
            ("--wall-type",),
            "material type of the mesh walls (LIGGGHTS) or of the wall, facet and box bodies (YADE VTK)",
            {"type": int, "metavar": "T"},
        ),
        OVERLAP_TOLERANCE,
    )

    @classmethod
    def detect(cls, path: Path | None, head: bytes) -> bool:
        return path is not None and head.startswith(VTK_MAGIC) and _SPHERES.match(path.name) is not None

    @classmethod
    def describe_file(cls, path: Path) -> str:
        """The series' frames, the first frame's counts and fields, and the options a run needs (the files
        hold no materials, law or wall material)."""
        steps, spheres = vtk_series(path)
        intrs = interactions_file(spheres[0])
        frame, wall_ids = vtk_frame(
            spheres[0], intrs if intrs.is_file() else None, tolerance=np.inf, step=int(steps[0])
        )
        needs = [
            f"--material ID:E:NU for the material ids {np.unique(frame.particles['type']).tolist()}",
            "--law yade:Law2_...",
        ]
        if len(wall_ids):
            needs.append(f"--wall-type ID (the material of YADE bodies {wall_ids.tolist()})")
        lines = [
            f"{path}: YADE VTKExporter files",
            f"  frames:   {len(steps)}, steps {describe_steps(steps)}",
            f"  first frame: {frame.n_particles} spheres, {frame.n_contacts} contacts; overlaps: "
            f"{frame.overlap_source or 'no interactions file'}",
            "  run needs: " + ", ".join(needs),
        ]
        lines += ["  " + line for f in (spheres[0], intrs) if f.is_file() for line in _vtk_lines(f)]
        return "\n".join(lines)

    def __init__(
        self,
        path: Path,
        *,
        materials: dict[int, Material] | None = None,
        law: str | None = None,
        wall_type: int | None = None,
        overlap_tolerance: float | None = None,
    ) -> None:
        path = Path(path)
        self.steps, self._spheres = vtk_series(path)
        missing = [
            what
            for what, given in (
                ("the materials (--material ID:E:NU for every YADE material id)", materials),
                ("the contact law (--law yade:Law2_...)", law),
            )
            if not given
        ]
        if missing:
            raise InputFormatError(
                f"VTKExporter files do not hold {' and '.join(missing)}.",
                file=path,
                fix="give them as options, or write full-precision snapshots with "
                "demsplit.yade.snapshot(), which hold everything.",
            )
        self._tolerance = 1e-3 if overlap_tolerance is None else overlap_tolerance
        # the files that exist (a frame whose interactions file is missing is refused when it is read)
        self.sources = [p for sp in self._spheres for p in (sp, interactions_file(sp)) if p.is_file()]
        self.notes = []
        # the walls are the non-sphere bodies in contact in the first frame
        _, self._wall_ids = vtk_frame(
            self._spheres[0], self._interactions(0), tolerance=np.inf, step=int(self.steps[0])
        )
        if len(self._wall_ids) and wall_type is None:
            raise InputFormatError(
                "the interactions include wall, facet or box contacts, whose material the files do not hold.",
                file=self._interactions(0),
                fix="give it with --wall-type ID (a YADE material id).",
            )
        self.scene = Scene(
            materials=dict(materials),
            model=ContactModel(law),
            walls=[Wall(name=f"YADE body {int(b)}", kind="yade_wall", type=int(wall_type)) for b in self._wall_ids],
            source=str(path),
        )

    def _interactions(self, k: int) -> Path:
        """The interactions file of frame ``k``; a missing one is an error (the frame's contacts are unknown)."""
        interactions = interactions_file(self._spheres[k])
        if not interactions.is_file():
            raise InputFormatError(
                "the interactions file of this sphere file is missing: the frame's contacts are unknown.",
                file=interactions,
                step=int(self.steps[k]),
                fix="export with VTKExporter.exportInteractions at the same iteration.",
            )
        return interactions

    def __len__(self) -> int:
        return len(self._spheres)

    def frame(self, k: int) -> Frame:
        return vtk_frame(
            self._spheres[k],
            self._interactions(k),
            tolerance=self._tolerance,
            step=int(self.steps[k]),
            wall_ids=self._wall_ids,
            attributes=self.scene.model.contact_law.phys,
        )[0]

    def describe(self) -> dict[str, Any]:
        return {
            "kind": self.format_name,
            "spheres": [str(p) for p in self._spheres],
            "overlap_tolerance": self._tolerance,
        }
