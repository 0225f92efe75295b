"""``contactcal`` command line. Subcommands import their heavy dependencies lazily.

Each concept adds its own subcommands (``add_parsers`` in ``pipeline/commands.py``,
``calibration/command.py``, ``bench/command.py``, ``evaluate/command.py``); the optional roles
(``synth``, ``train``) add theirs through the :data:`COMMAND_GROUP` entry points.

Exit codes: 0 success, 1 a run that found nothing usable (e.g. no contact in any frame),
2 bad input or usage (one-line message on stderr, nothing written); 130 interrupted (Ctrl-C),
143 or 129 stopped by SIGTERM or SIGHUP (one line; outputs all or nothing, as on Ctrl-C).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from contextlib import nullcontext
from typing import Any

from contactcal.infer.bench import command as bench_command
from contactcal.infer.calibration import command as calibrate_command
from contactcal.infer.errors import RunError
from contactcal.infer.evaluate import command as evaluate_command
from contactcal.infer.files.interrupt import Terminated, stop_signals_interrupt
from contactcal.infer.files.stdout import named_stdout
from contactcal.infer.image.cv_threads import opencv_threads
from contactcal.infer.parser import Parser
from contactcal.infer.pipeline import commands as pipeline_commands
from contactcal.infer.pipeline.args import check_cpu_count

#: Entry-point group through which other roles add subcommands (see pyproject.toml).
COMMAND_GROUP = "contactcal.commands"


class _Version(argparse.Action):
    """``--version``: print the installed version and exit (looked up only when asked)."""

    def __init__(self, option_strings: Sequence[str], dest: str, **kwargs: Any) -> None:
        kwargs.setdefault("help", "show the version and exit")
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: object,
        option_string: str | None = None,
    ) -> None:
        from contactcal.infer import __version__

        print(f"contactcal {__version__}")
        parser.exit()


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The argument parser (exposed for tests and docs).

    Args:
        command: the subcommand about to run. When it is one of the core's, the optional roles'
            subcommands are not added (finding and importing them took ~10-20 ms of every
            command's start-up here); None or any other word: all of them (``--help`` lists all).
    """
    parser = Parser(
        prog="contactcal",
        description="Contact-area calibration of pneumatic fingertip displays from rig images.",
    )
    parser.add_argument("--version", action=_Version)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    pipeline_commands.add_parsers(sub)  # measure, demo
    calibrate_command.add_parsers(sub)
    bench_command.add_parsers(sub)
    evaluate_command.add_parsers(sub)
    if command not in sub.choices:
        add_plugin_commands(sub)
    return parser


#: What an interrupted command leaves, where it is not "nothing" (commands that write as they go).
INTERRUPTED = {
    "synth": "the frames written so far stay; run it again with the same arguments to resume",
    "train": (
        "the last finished epoch's checkpoint (last.pt) and config.json stay; continue with "
        "--resume (stopped before the first epoch ended there are none: start it again)"
    ),
}


def add_plugin_commands(sub: argparse._SubParsersAction) -> None:
    """Subcommands registered by other roles (``synth``, ``train``) as entry points.

    Each entry point of the group :data:`COMMAND_GROUP` is a function taking the subparsers
    object; the core names no role, so it imports none.
    """
    from importlib.metadata import entry_points

    for ep in sorted(entry_points(group=COMMAND_GROUP), key=lambda e: e.name):
        ep.load()(sub)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``contactcal`` console script."""
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(argv[0] if argv else None)
    args = parser.parse_args(argv)
    args.argv = argv  # recorded in calibration.json
    try:  # one line, as every other bad input, before any thread is started
        check_cpu_count("--threads", getattr(args, "threads", 1))
    except ValueError as exc:
        print(f"contactcal: error: {exc}", file=sys.stderr)
        return 2
    try:
        threads = getattr(args, "threads", None)  # measure, calibrate (not train: torch_threads)
        with named_stdout(), stop_signals_interrupt():
            with opencv_threads(threads) if threads else nullcontext():
                return int(args.func(args))
    except RunError as exc:
        print(f"contactcal: {exc}", file=sys.stderr)
        return exc.code
    except (ValueError, OSError) as exc:
        print(f"contactcal: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:  # staged outputs were discarded on the way out
        said = getattr(exc, "after_outputs", None) or INTERRUPTED.get(
            args.command, "its outputs are all or nothing: none was written"
        )
        if isinstance(exc, Terminated):  # SIGTERM, SIGHUP: the shell's status for the signal
            print(f"contactcal {args.command}: stopped by {exc}; {said}", file=sys.stderr)
            return 128 + exc.signum
        print(f"contactcal {args.command}: interrupted; {said}", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
