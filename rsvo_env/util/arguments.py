"""What the command lines share: argument types that refuse a bad value at parse time, and the
checks of output paths made before any work, so a user's mistake is one ``error:`` line and
exit status 2 and never a traceback after a whole episode."""

from __future__ import annotations

import argparse
import errno
import os
import sys
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import NoReturn

from rsvo_env.util.validation import shown


def count(least: int) -> Callable[[str], int]:
    """An argparse type: an integer >= ``least`` (seeds: 0, episode counts: 1)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"invalid int value: {shown(text)}") from None
        if value < least:
            raise argparse.ArgumentTypeError(f"{value} must be an integer >= {least}")
        return value

    parse.__name__ = f"integer >= {least}"
    return parse


def output_problem(path: Path, suffix: str | None = None, directory: bool = False) -> str | None:
    """Why ``path`` cannot be written (a file ending in ``suffix``, or a ``directory``), or
    None. A file's folder must exist (it is not made for it); a directory is made with its
    missing parents, so its nearest existing ancestor must take one. Each is tried for real,
    with a probe made and removed at once (permission bits do not tell root, nor a read-only
    or virtual file system such as ``/proc``): nothing is left behind."""
    if suffix is not None and path.suffix.lower() != suffix:
        return f"{path} must end in {suffix}"
    if path.exists():
        if directory and not path.is_dir():
            return f"{path} exists and is not a directory"
        if not directory and path.is_dir():
            return f"{path} is a directory"
    folder = path.resolve().parent
    if not directory and not folder.is_dir():
        what = "is not a directory" if folder.exists() else "does not exist"
        return f"{path} cannot be written: its folder {folder} {what}"
    for parent in (path.resolve(), *path.resolve().parents)[0 if directory else 1 :]:
        if parent.exists():
            if not parent.is_dir():
                return f"{path} cannot be written: {parent} is not a directory"
            return _probe(path, parent, directory)
    return None


def _probe(path: Path, folder: Path, directory: bool) -> str | None:
    """Make and remove a directory (or a file) in ``folder``; the reason it failed, or None."""
    try:
        if directory:
            os.rmdir(tempfile.mkdtemp(prefix=".rsvo-probe-", dir=folder))
        else:
            fd, name = tempfile.mkstemp(prefix=".rsvo-probe-", dir=folder)
            os.close(fd)
            os.remove(name)
    except OSError as err:
        reason = err.strerror or str(err)
        if err.errno == errno.ENOENT and folder.is_dir():
            # the folder is there, yet "no such file": a file system that makes no new entries
            reason = "it takes no new files (a virtual file system, such as /proc)"
        return f"{path} cannot be written: {folder}: {reason}"
    return None


class HelpFormatter(argparse.RawDescriptionHelpFormatter, argparse.ArgumentDefaultsHelpFormatter):
    """Keeps the description's lines and shows each option's default once: not where the help
    names it already, nor where there is none to show (None, a flag's False)."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        if "default:" in text or action.default in (None, False, argparse.SUPPRESS):
            return text
        return super()._get_help_string(action)


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
    problem = None if path is None else output_problem(path, suffix, directory)
    if problem:
        raise UserError(problem)
