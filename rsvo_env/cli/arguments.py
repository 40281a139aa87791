"""What the command lines share: argument types that refuse a bad value at parse time, and the
checks of output paths made before any work, so a user's mistake is one ``error:`` line and
exit status 2 and never a traceback after a whole episode."""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable
from pathlib import Path


def count(least: int) -> Callable[[str], int]:
    """An argparse type: an integer >= ``least`` (seeds: 0, episode counts: 1)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"invalid int value: {text!r}") from None
        if value < least:
            raise argparse.ArgumentTypeError(f"{value} must be an integer >= {least}")
        return value

    parse.__name__ = f"integer >= {least}"
    return parse


def output_problem(path: Path, suffix: str | None = None, directory: bool = False) -> str | None:
    """Why ``path`` cannot be written (a file ending in ``suffix``, or a ``directory``), or
    None. Nothing is created: the nearest existing ancestor must be a writable directory."""
    if suffix is not None and path.suffix.lower() != suffix:
        return f"{path} must end in {suffix}"
    if path.exists():
        if directory and not path.is_dir():
            return f"{path} exists and is not a directory"
        if not directory and path.is_dir():
            return f"{path} is a directory"
    for parent in path.resolve().parents:
        if parent.exists():
            if not parent.is_dir():
                return f"{path} cannot be written: {parent} is not a directory"
            if not os.access(parent, os.W_OK | os.X_OK):
                return f"{path} cannot be written: {parent} is not writable"
            break
    return None
