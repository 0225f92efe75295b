"""``contactcal`` command line. Subcommands import their heavy dependencies lazily.

Each concept adds its own subcommands (``add_parsers`` in ``pipeline/commands.py``,
``calibration/command.py``, ``bench/command.py``, ``evaluate/command.py``); the optional roles
(``synth``, ``train``) add theirs through the :data:`COMMAND_GROUP` entry points.

Exit codes: 0 success, 1 a run that found nothing usable (e.g. no contact in any frame),
2 bad input or usage (one-line message on stderr, nothing written).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from importlib.metadata import entry_points

from contactcal.infer.bench import command as bench_command
from contactcal.infer.calibration import command as calibrate_command
from contactcal.infer.errors import RunError
from contactcal.infer.evaluate import command as evaluate_command
from contactcal.infer.pipeline import commands as pipeline_commands

#: Entry-point group through which other roles add subcommands (see pyproject.toml).
COMMAND_GROUP = "contactcal.commands"


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for tests and docs)."""
    from contactcal.infer import __version__

    parser = argparse.ArgumentParser(
        prog="contactcal",
        description="Contact-area calibration of pneumatic fingertip displays from rig images.",
    )
    parser.add_argument("--version", action="version", version=f"contactcal {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    pipeline_commands.add_parsers(sub)  # measure, demo
    calibrate_command.add_parsers(sub)
    bench_command.add_parsers(sub)
    evaluate_command.add_parsers(sub)
    add_plugin_commands(sub)
    return parser


def add_plugin_commands(sub: argparse._SubParsersAction) -> None:
    """Subcommands registered by other roles (``synth``, ``train``) as entry points.

    Each entry point of the group :data:`COMMAND_GROUP` is a function taking the subparsers
    object; the core names no role, so it imports none.
    """
    for ep in sorted(entry_points(group=COMMAND_GROUP), key=lambda e: e.name):
        ep.load()(sub)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``contactcal`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)  # recorded in calibration.json
    if getattr(args, "threads", 1) < 1:
        parser.error("--threads must be >= 1")
    try:
        return int(args.func(args))
    except RunError as exc:
        print(f"contactcal: {exc}", file=sys.stderr)
        return exc.code
    except (ValueError, OSError) as exc:
        print(f"contactcal: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
