"""Subprocesses of the tests run the checkout under test, as the wheel lays it out
(``docs/hooks/installed_layout.py``): a view of the checkout made of links goes first on their
``PYTHONPATH``, and they start outside the checkout, whose root would shadow it."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location(
    "installed_layout", ROOT / "docs" / "hooks" / "installed_layout.py"
)
assert _spec is not None and _spec.loader is not None
layout = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(layout)

_VIEW: list[Path] = []


def installed_view() -> Path:
    """This process's linked view of the checkout (made once, removed at exit)."""
    if not _VIEW:
        _VIEW.append(layout.temporary_layout(copy=False))
    return _VIEW[0]


def checkout_env(**extra: str) -> dict[str, str]:
    """This process's environment with the checkout's view first on ``PYTHONPATH``."""
    env = dict(os.environ, **extra)
    rest = env.get("PYTHONPATH")
    view = str(installed_view())
    env["PYTHONPATH"] = view if not rest else os.pathsep.join([view, rest])
    return env


def run_python(*args: str, cwd: str | Path | None = None, **kwargs: Any):
    """``python ARGS`` of this interpreter on the checkout, output captured as text. The
    working directory defaults to the view's parent: ``-c`` and ``-m`` put the working
    directory first on the path, where the checkout's root would shadow the view."""
    env = kwargs.pop("env", None) or checkout_env()
    return subprocess.run(
        [sys.executable, *args],
        capture_output=True,
        text=True,
        cwd=installed_view().parent if cwd is None else cwd,
        env=env,
        **kwargs,
    )
