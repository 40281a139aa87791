"""Entry point of the ``rsvo`` command."""

from __future__ import annotations

import argparse
import sys


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="rsvo", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("demo", help="filter a two-agent head-on swap and print the distance kept")
    sub.add_parser("simulate", help="run a scenario; metrics, GIF, figure", add_help=False)
    sub.add_parser("reproduce", help="the paper's experiments: tables and figures", add_help=False)
    args, rest = parser.parse_known_args(argv)
    if args.command == "demo":
        from rsvo_env.cli import demo

        return demo.main()
    if args.command == "simulate":
        from rsvo_env.cli import simulate

        return simulate.main(rest)
    if args.command == "reproduce":
        from rsvo_env.cli import reproduce

        return reproduce.main(rest)
    return 2  # pragma: no cover - argparse rejects unknown commands


if __name__ == "__main__":
    sys.exit(main())
