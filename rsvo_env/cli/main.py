"""rsvo: responsibility-associated multi-agent collision avoidance (R-SVO weights, R-CBF filter).

Commands: demo (the filter alone on plain arrays), simulate (one scenario, its metrics, a GIF
and a figure), reproduce (the paper's experiments: tables, figures and GIFs). Run
"rsvo COMMAND --help" for the options of each.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import NoReturn

COMMANDS = {
    "demo": "filter a two-agent head-on swap on plain arrays and print the distance kept",
    "simulate": "run one scenario with the scripted controller; print its metrics, write a GIF "
    "and a trajectory figure",
    "reproduce": "the paper's experiments: tables (paper.md), figures and GIFs",
}


class UserError(ValueError):
    """A mistake of the user's (a bad argument, a value the library refuses, a path that cannot
    be written), reported as one line and exit status 2. Only these are: any other exception
    is a bug and keeps its traceback."""


class Parser(argparse.ArgumentParser):
    """argparse, with its errors as one line (no usage block) and exit status 2."""

    def error(self, message: str) -> NoReturn:
        print(f"{self.prog}: error: {message}", file=sys.stderr)
        sys.exit(2)


@contextmanager
def user_input() -> Iterator[None]:
    """Around the step that hands the user's values to the library: its refusals (ValueError,
    TypeError naming the field and the value) are the user's mistakes."""
    try:
        yield
    except (ValueError, TypeError) as exc:
        raise UserError(str(exc)) from None


def check_output(path: Path | None, suffix: str | None = None, directory: bool = False) -> None:
    """Refuse, before any work, an output path that cannot be written."""
    from rsvo_env.cli.arguments import output_problem

    problem = None if path is None else output_problem(path, suffix, directory)
    if problem:
        raise UserError(problem)


def main(argv: list[str] | None = None) -> int:
    parser = Parser(
        prog="rsvo", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, text in COMMANDS.items():
        sub.add_parser(name, help=text, add_help=False)
    args, rest = parser.parse_known_args(argv)
    try:
        if args.command == "demo":
            from rsvo_env.cli import demo

            return demo.main(rest)
        if args.command == "simulate":
            from rsvo_env.cli import simulate

            return simulate.main(rest)
        from rsvo_env.cli import reproduce

        return reproduce.main(rest)
    except UserError as exc:
        print(f"rsvo {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
