"""rsvo: responsibility-associated multi-agent collision avoidance (R-SVO weights, R-CBF filter).

Commands: demo (the filter alone on plain arrays), simulate (one scenario, its metrics, a GIF
and a figure), reproduce (the paper's experiments: tables, figures and GIFs), train and
evaluate (a policy behind the filter; the train extra). Run "rsvo COMMAND --help" for the
options of each.
"""

from __future__ import annotations

import argparse
import sys

from rsvo_env.util.arguments import Parser, UserError

COMMANDS = {
    "demo": "filter a two-agent head-on swap on plain arrays and print the distance kept",
    "simulate": "run one scenario with the scripted controller; print its metrics, write a GIF "
    "and a trajectory figure",
    "reproduce": "the paper's experiments: tables (paper.md), figures and GIFs",
    "train": "train a policy behind the filter with Stable-Baselines3 or RLlib (the train extra)",
    "evaluate": "evaluate a trained policy against the scripted controller (the train extra)",
}
TRAINING = ("train", "evaluate")


def main(argv: list[str] | None = None) -> int:
    parser = Parser(
        prog="rsvo", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    from rsvo_env import __version__

    parser.add_argument("--version", action="version", version=f"rsvo {__version__}")
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
        if args.command in TRAINING:
            return training(args.command, rest)
        from rsvo_env.cli import reproduce

        return reproduce.main(rest)
    except UserError as exc:
        print(f"rsvo {args.command}: error: {exc}", file=sys.stderr)
        return 2


def training(command: str, rest: list[str]) -> int:
    """``rsvo train`` / ``rsvo evaluate``: the training package's own command line."""
    import importlib

    try:
        module = importlib.import_module(f"rsvo_env.training.{command}")
    except ModuleNotFoundError as exc:
        missing = (exc.name or "").split(".")[0]
        if missing in ("stable_baselines3", "torch", "yaml", "tensorboard"):
            raise UserError(
                f"needs {missing}, from the train extra: pip install 'rsvo-env[train]'"
            ) from exc
        raise
    return module.main(rest, prog=f"rsvo {command}")


if __name__ == "__main__":
    sys.exit(main())
