"""The ``demsplit`` command.

    demsplit run IN [--atoms F] [--contacts F] [--walls F] -o OUT.h5
    demsplit info FILE
    demsplit check IN
    demsplit prepare SCRIPT [-o OUT]
    demsplit report OUT.h5 [-o report.html]
    demsplit export OUT.h5 --parquet DIR | --csv DIR | --vtk DIR | --dump FILE
    demsplit convert IN -o CACHE.h5
    demsplit yade-path

``IN`` is a LIGGGHTS or LAMMPS input script (its dumps are found from its ``dump``
lines unless given), YADE saved states or a ``demsplit.yade`` snapshot file (readers/). Errors print one
message naming the file, timestep and line and how to fix it, and exit 2;
``--debug`` shows the traceback.
"""

from __future__ import annotations

import argparse
import signal
import sys
import traceback
import warnings
from pathlib import Path

import numpy as np

from .errors import DemsplitError, InputFormatError, system_error
from .outputs import check_output_path

EXIT_ERROR = 2
EXIT_BUG = 3
EXIT_INTERRUPTED = 130  # 128 + SIGINT
EXIT_TERMINATED = 143  # 128 + SIGTERM


class Terminated(BaseException):
    """SIGTERM arrived: unwinds like Ctrl-C (an open result store keeps its committed frames for --resume)."""


def _raise_terminated(signum, frame) -> None:
    raise Terminated()


def _reader_options(args: argparse.Namespace) -> dict:
    """Options of :func:`demsplit.readers.open_run` given on the command line, as the reader of the input
    takes them (:attr:`demsplit.readers.base.Run.cli_options`); an option its reader does not take is an
    error naming the option."""
    from .readers import reader_for, readers

    given = {}
    for cls in readers():
        for opt in cls.cli_options:
            value = getattr(args, _dest(opt), None)
            if value is not None and value is not False and value != []:  # (0 is a value: `in` would equate it)
                given[opt.flags] = value
    simulator = getattr(args, "simulator", None)
    if not given:
        return {} if simulator is None else {"simulator": simulator}
    inputs = args.input if isinstance(args.input, list) else [args.input]
    cls = reader_for(inputs[0], simulator)
    options: dict = {} if simulator is None else {"simulator": simulator}
    for flags, value in given.items():
        opt = next((o for o in cls.cli_options if o.flags == flags), None)
        if opt is None:
            taken = sorted({o.flags[0] for o in cls.cli_options})
            raise InputFormatError(
                f"{flags[0]} does not apply to {cls.formats[0]}.",
                fix=f"leave it out; this input takes {', '.join(taken) or 'no input option'}.",
            )
        if opt.into:
            options.setdefault(opt.into, {})[opt.name] = opt.value(value)
        else:
            options[opt.name] = opt.value(value)
    return options


def _dest(opt) -> str:
    """The argparse destination of a reader option: its first flag, as argparse names it."""
    return opt.flags[0].lstrip("-").replace("-", "_")


def _argparse_type(convert):
    """A reader option's ``type`` for argparse: its ValueError becomes argparse's usage error with the text."""

    def parse(text: str):
        try:
            return convert(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = getattr(convert, "__name__", "value")
    return parse


def _add_input(p: argparse.ArgumentParser) -> None:
    """The input argument and every registered reader's options, in its help section."""
    from .readers import readers

    p.add_argument(
        "input",
        nargs="*",
        default=None,
        help="the run: "
        + "; ".join(f for cls in readers() for f in cls.formats)
        + " (several files are one run only where the reader says so); omit it to describe a LIGGGHTS "
        "scene with --atoms, --contacts, --material and --columns",
    )
    p.add_argument(
        "--simulator",
        choices=sorted({cls.simulator for cls in readers() if cls.simulator}),
        help="the simulator whose run the input is, where its words cannot tell (a LAMMPS and a LIGGGHTS "
        "script are text in the same language; demsplit recognises pair_style granular and gran/* as "
        "LAMMPS, pair_style gran model ... as LIGGGHTS)",
    )
    groups: dict[str, argparse._ArgumentGroup] = {}
    added: set[tuple[str, ...]] = set()
    for cls in readers():
        for opt in cls.cli_options:
            if opt.flags in added:
                continue
            added.add(opt.flags)
            title = opt.group or cls.cli_group
            group = groups.get(title) or groups.setdefault(title, p.add_argument_group(title))
            kwargs = dict(opt.argparse)
            if "type" in kwargs:
                kwargs["type"] = _argparse_type(kwargs["type"])
            group.add_argument(*opt.flags, dest=_dest(opt), help=opt.help, **kwargs)


def _options(args: argparse.Namespace):
    from .pipeline import Options

    return Options(
        tangential_rule=args.tangential_rule,
        compare=not args.no_compare,
        contacts=not args.no_contacts,
        allow_missing=tuple(args.allow_missing or ()),
        accuracy=not args.no_accuracy,
        split=args.split,
    )


def cmd_run(args: argparse.Namespace) -> int:
    from .pipeline import run_to_store

    options = _reader_options(args)
    if args.input:  # what the run's reader keeps next to the output (converted YADE states)
        from .readers import reader_for

        first = args.input[0] if isinstance(args.input, list) else args.input
        options = {**reader_for(first, getattr(args, "simulator", None)).output_options(Path(args.output)), **options}
    report, _ = run_to_store(
        args.input,
        args.output,
        options=_options(args),
        jobs=args.jobs,
        dask=args.dask,
        resume=args.resume,
        on_bad_frame=args.on_bad_frame,
        compression=None if args.compression == "none" else args.compression,
        progress=False if args.quiet else None,
        overwrite=args.overwrite,
        type_names=dict(args.type_name or ()),
        **options,
    )
    if not args.quiet:
        from .results.report import text_summary
        from .results.store import read_last_frame

        print(text_summary(read_last_frame(args.output)))
        for note in report.notes:
            print(f"note: {note}")
        if report.bad_frames:
            print(f"{len(report.bad_frames)} bad frame(s) skipped (listed in the output's provenance):")
            for bad in report.bad_frames:
                print(f"  frame {bad['frame']} (step {bad['step']}): {bad['error']}")
        print(
            f"wrote {args.output} ({report.frames_done} frame(s)"
            + (f", {report.frames_resumed} resumed" if report.frames_resumed else "")
            + ")"
        )
    return 0


def cmd_info(args: argparse.Namespace) -> int:
    from .inspection import describe_file

    text = describe_file(args.file)
    if not args.quiet:
        print(text)
    return 0


def cmd_check(args: argparse.Namespace) -> int:
    from .inspection import check_run

    text, ok = check_run(args.input, **_reader_options(args))
    if not args.quiet:  # the exit status says whether a problem was found
        print(text)
    return 0 if ok else 1


def cmd_report(args: argparse.Namespace) -> int:
    from .results import load_results
    from .results.report import text_summary, write_html
    from .results.store import protected_files

    results = load_results(args.results)
    names = dict(args.type_name or ())
    if args.output:
        write_html(
            results,
            args.output,
            step=args.step,
            names=names,
            inputs=protected_files(args.results, results.provenance),
            overwrite=args.overwrite,
        )
        if not args.quiet:
            print(f"wrote {args.output}")
    else:
        text = text_summary(results, step=args.step, names=names)
        if not args.quiet:
            print(text)
    return 0


def _positive(text: str) -> int:
    try:
        n = int(text)
        if n <= 0:
            raise ValueError
        return n
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number of timesteps, got {text!r}") from None


def _type_name(text: str) -> tuple[int, str]:
    t, sep, name = text.partition("=")
    try:
        if not sep or not name.strip():
            raise ValueError
        return int(t), name.strip()
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected TYPE=NAME (e.g. 1=glass), got {text!r}") from None


def cmd_export(args: argparse.Namespace) -> int:
    from .results import load_results
    from .results.exports.dump import export_dump
    from .results.exports.tables import export_tables
    from .results.exports.vtk import export_vtk
    from .results.store import protected_files

    folders = [(fmt, d) for fmt, d in (("parquet", args.parquet), ("csv", args.csv), ("vtk", args.vtk)) if d]
    if not folders and not args.dump:
        raise DemsplitError("nothing to export to.", fix="give --parquet DIR, --csv DIR, --vtk DIR or --dump FILE.")
    same = [fmt for fmt, d in folders if sum(Path(d).absolute() == Path(o).absolute() for _, o in folders) > 1]
    if same:
        raise DemsplitError(
            f"--{same[0]} and --{same[1]} name the same folder: an export folder holds one export.",
            file=dict(folders)[same[0]],
            fix="give each format its own folder.",
        )
    results = load_results(args.results)
    inputs = protected_files(args.results, results.provenance)
    written = []
    for fmt, directory in folders:
        if fmt != "vtk":
            written += export_tables(results, directory, fmt=fmt, inputs=inputs, overwrite=args.overwrite)
    if args.dump:
        written.append(export_dump(results, args.dump, inputs=inputs, overwrite=args.overwrite))
    if not args.quiet:
        for path in written:
            print(f"wrote {path}")
    if args.vtk:  # one line for the whole series, not one per file
        not_drawn: list[str] = []
        vtk = export_vtk(
            results,
            args.vtk,
            inputs=inputs,
            overwrite=args.overwrite,
            progress=False if args.quiet else None,
            not_drawn=not_drawn,
        )
        if not args.quiet:
            series = [p.name for p in vtk if p.suffix == ".pvd"]
            print(
                f"wrote {len(vtk) - len(series)} VTK files of {len(results.steps)} frame(s) in {args.vtk}: open "
                f"{', '.join(series)} in ParaView"
                + (f" (walls not drawn: {'; '.join(not_drawn)})" if not_drawn else "")
            )
    return 0


def cmd_prepare(args: argparse.Namespace) -> int:
    from .outputs import PREPARED_SCRIPT, output_errors, output_files, stamp_script
    from .prepare import prepare_script
    from .prepare_lammps import prepare_lammps_script
    from .readers.lammps_input import read_text
    from .readers.lammps_script import is_lammps_script, read_lammps_script
    from .readers.liggghts_script import read_script

    script = Path(args.input)
    out = Path(args.output or script.with_name(script.name + ".demsplit"))
    lammps = script.is_file() and is_lammps_script(script.read_bytes())  # LAMMPS' own output: docs/lammps-output.md
    prepared = (prepare_lammps_script if lammps else prepare_script)(script, every=args.every)
    parts = [prepared]
    while parts[-1].part2 is not None:
        parts.append(parts[-1].part2)
    paths = [out] + [out.with_name(f"{out.name}.part{k}") for k in range(2, len(parts) + 1)]
    protected = [script, *(read_lammps_script if lammps else read_script)(script).named_files()]
    for path in paths:  # every path checked before anything is written
        check_output_path(path, protected, kind=PREPARED_SCRIPT, overwrite=args.overwrite)
    if not args.quiet:
        print("\n".join(note for part in parts for note in part.notes))
    if not prepared.added:
        return 0
    with output_files(paths) as tmps:  # all parts or none
        for part, path in zip(parts, paths):
            with output_errors(path):
                tmps[path].write_bytes(stamp_script(part.data))
    if not args.quiet:
        print(prepared.diff(read_text(script), str(script)))
        where = f"in {out.parent}" if len(paths) == 1 else f"one after the other in {out.parent}"
        print(
            f"wrote {', '.join(map(str, paths))}: run {'it' if len(paths) == 1 else 'them'} with "
            f"{'; '.join(f'{prepared.program} -in {p.name}' for p in paths)} {where}, then "
            + "; ".join(f"'demsplit run {p} -o results{'' if k == 0 else k + 1}.h5'" for k, p in enumerate(paths))
        )
    return 0


def cmd_convert(args: argparse.Namespace) -> int:
    from .readers.cache import convert_run

    path = convert_run(args.input, args.output, overwrite=args.overwrite, **_reader_options(args))
    if not args.quiet:
        print(f"wrote {path}")
    return 0


def cmd_yade_path(args: argparse.Namespace) -> int:
    import sysconfig

    # site-packages of the Python demsplit is installed in (a regular or an editable
    # install): site.addsitedir() it inside YADE (docs/yade.md)
    if not args.quiet:
        print(sysconfig.get_paths()["purelib"])
    return 0


def _add_overwrite(p: argparse.ArgumentParser, what: str) -> None:
    p.add_argument(
        "--overwrite",
        action="store_true",
        help=f"replace {what} (by default only a file of the kind the command writes is replaced; a "
        "file of the run is never replaced)",
    )


def build_parser() -> argparse.ArgumentParser:
    from . import __version__

    parser = argparse.ArgumentParser(
        prog="demsplit",
        description="Per-particle elastic contact energy of LIGGGHTS, LAMMPS GRANULAR and YADE "
        "runs, split between the two bodies by the Feng & Gao material law.",
        epilog="Errors print one message naming the file, timestep and line and how to fix it, and exit 2; --debug "
        "shows the traceback. 'demsplit COMMAND -h' describes a command.",
    )
    parser.add_argument("--version", action="version", version=f"demsplit {__version__}")
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--debug", action="store_true", help="show the traceback of an error")
    common.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors; no progress bar")
    sub = parser.add_subparsers(dest="command", required=True)

    def add(name: str, help: str) -> argparse.ArgumentParser:  # every subcommand takes --debug/--quiet
        return sub.add_parser(name, help=help, description=help[0].upper() + help[1:] + ".", parents=[common])

    p = add("run", "per-particle energies of every frame, written to an HDF5 store")
    _add_input(p)
    p.add_argument("-o", "--output", required=True, help="output HDF5 file")
    _add_overwrite(p, "an existing file that is not a result store")
    p.add_argument("--jobs", "-j", type=int, default=1, help="worker processes (frames in parallel)")
    p.add_argument(
        "--dask", metavar="ADDRESS", help="run on a Dask cluster: tcp://HOST:PORT, a scheduler file, or local:N"
    )
    p.add_argument("--resume", action="store_true", help="continue an interrupted run from its last complete frame")
    p.add_argument(
        "--on-bad-frame",
        choices=("stop", "skip"),
        default="stop",
        help="stop at a bad frame (default), or skip it and list it in the output",
    )
    p.add_argument(
        "--tangential-rule",
        choices=("mindlin", "paper"),
        default="mindlin",
        help="tangential split factor: Mindlin (2-nu)/G (default) or the paper's eq. 22 (1-2nu)/G",
    )
    p.add_argument("--no-compare", action="store_true", help="skip the 50/50 and radius-weighted splits")
    p.add_argument("--no-contacts", action="store_true", help="do not store the per-contact table")
    p.add_argument(
        "--no-accuracy",
        action="store_true",
        help="skip the expected error of the split (a/R per contact, share_n1_error, u_n_error)",
    )
    p.add_argument(
        "--split",
        choices=("material", "corrected"),
        default="material",
        help="material: the distribution law (default); corrected: its normal split corrected for "
        "finite bodies by the fitted finite-element model (docs/accuracy.md)",
    )
    p.add_argument(
        "--allow-missing",
        action="append",
        metavar="NAME",
        help="go on without a wall (by name) or an energy mode (u_t, u_r, ...) that the run has but "
        "its files do not hold; its values are then marked not computed, never 0 (repeatable; "
        "'all' for everything). Without it such a run is refused",
    )
    p.add_argument(
        "--compression",
        choices=("auto", "gzip", "lzf", "none"),
        default="auto",
        help="HDF5 compression of the output: auto (default; gzip for the columns whose first chunk "
        "compresses well, such as integers, shares and points, no filter for the others: docs/store.md), "
        "gzip (every column; smallest, slowest), lzf (h5py only), none (fastest, largest); "
        "any HDF5 tool reads auto, gzip and none",
    )
    p.add_argument(
        "--type-name",
        action="append",
        type=_type_name,
        metavar="T=NAME",
        help="name material type T NAME, stored with the results and used by report and export "
        "(repeatable; YADE material labels are stored already)",
    )
    p.set_defaults(func=cmd_run)

    p = add("info", "describe a dump or snapshot file: kind, frames, columns, precision")
    p.add_argument(
        "file",
        help="a LIGGGHTS or LAMMPS dump or input script, YADE snapshot or saved state, ingest cache or result store",
    )
    p.set_defaults(func=cmd_info)

    p = add("check", "validate a run without computing energies")
    _add_input(p)
    p.set_defaults(func=cmd_check)

    p = add("report", "summary of a result file: text, or a self-contained HTML page with -o")
    p.add_argument("results", help="a store written by demsplit run")
    p.add_argument("-o", "--output", help="HTML file to write (default: the text summary on the terminal)")
    _add_overwrite(p, "an existing file that is not a demsplit report")
    p.add_argument("--step", type=int, metavar="N", help="the timestep of the detailed frame (default: the last)")
    p.add_argument(
        "--type-name",
        action="append",
        type=_type_name,
        metavar="T=NAME",
        help="name material type T NAME in the tables and figures (repeatable; overrides the names "
        "stored by run --type-name and YADE's material labels)",
    )
    p.set_defaults(func=cmd_report)

    p = add("export", "export a result file's tables to Parquet or CSV, or as a VTK series for ParaView")
    p.add_argument("results", help="a store written by demsplit run")
    p.add_argument("--parquet", metavar="DIR", help="one Parquet file per table (units in the field metadata)")
    p.add_argument("--csv", metavar="DIR", help="one CSV file per table")
    p.add_argument(
        "--vtk",
        metavar="DIR",
        help="one VTK file per frame for particles (points), contacts (lines between the bodies) and "
        "walls (surfaces), and a .pvd series of each (needs the vtk extra: pip install "
        "'demsplit[vtk]')",
    )
    p.add_argument(
        "--dump",
        metavar="FILE",
        help="the per-particle table as a LAMMPS-style dump (positions, radius, energies), which OVITO opens directly",
    )
    _add_overwrite(
        p,
        "files that are not a demsplit export of the format (in a folder: its other files are "
        "kept; an earlier export in it is replaced)",
    )
    p.set_defaults(func=cmd_export)

    p = add("yade-path", "print the directory to site.addsitedir() inside YADE so that 'import demsplit.yade' works")
    p.set_defaults(func=cmd_yade_path)

    p = add(
        "prepare", "write a copy of a LIGGGHTS or LAMMPS input script with the dumps demsplit needs, and show the diff"
    )
    p.add_argument("input", help="the LIGGGHTS or LAMMPS input script")
    p.add_argument(
        "-o",
        "--output",
        help="prepared script (default: INPUT.demsplit next to the input; a script "
        "split at a mesh wall fix after a run also gets OUTPUT.part2, ...)",
    )
    p.add_argument(
        "--every",
        type=_positive,
        metavar="N",
        help="timesteps between the frames of the dumps prepare adds (default: the interval of the "
        "script's own dumps, else of its thermo output, else 100 frames over its runs)",
    )
    _add_overwrite(p, "an existing file that is not a script prepare wrote, or one edited since")
    p.set_defaults(func=cmd_prepare)

    p = add("convert", "write a run's dumps once to an HDF5 ingest cache read much faster later")
    _add_input(p)
    p.add_argument("-o", "--output", required=True, help="cache file (.h5)")
    _add_overwrite(p, "an existing file that is not an ingest cache")
    p.set_defaults(func=cmd_convert)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if isinstance(getattr(args, "input", None), list):  # none, one path, or several files of one run
        args.input = None if not args.input else args.input[0] if len(args.input) == 1 else args.input
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        with np.errstate(all="ignore"), warnings.catch_warnings():  # every number is checked explicitly
            if args.quiet:  # (demsplit.validate); a library's warning (matplotlib's, say) is shown unless -q
                warnings.simplefilter("ignore")
            return args.func(args)
    except DemsplitError as exc:
        if args.debug:
            traceback.print_exc()
        print(f"demsplit: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except BrokenPipeError:  # the reader of our output went away (demsplit info F | head): not an error
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:  # the system's fault (disk full, read-only, permissions), not a bug: name the path
        if args.debug:
            traceback.print_exc()
        print(f"demsplit: error: {system_error(exc)}", file=sys.stderr)
        return EXIT_ERROR
    except (KeyboardInterrupt, Terminated) as exc:
        what = "terminated (SIGTERM)" if isinstance(exc, Terminated) else "interrupted"
        resume = "; run again with --resume to continue from the last complete frame" if args.command == "run" else ""
        print(f"demsplit: {what}{resume}.", file=sys.stderr)
        return EXIT_TERMINATED if isinstance(exc, Terminated) else EXIT_INTERRUPTED
    except Exception as exc:  # a bug: say so, keep the CLI's promise of one message
        if args.debug:
            traceback.print_exc()
        print(
            f"demsplit: internal error ({type(exc).__name__}: {exc}). This is a bug in demsplit; "
            "rerun with --debug and report the traceback.",
            file=sys.stderr,
        )
        return EXIT_BUG
    finally:
        signal.signal(signal.SIGTERM, previous)


def command() -> None:
    """The ``demsplit`` console script (and ``python -m demsplit.cli``): :func:`main` on the command
    line, then the process ends with its exit status at once (:func:`demsplit.runtime.command.exit_now`)."""
    from .runtime.command import exit_now

    exit_now(main())


if __name__ == "__main__":
    command()
