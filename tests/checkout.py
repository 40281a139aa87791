"""Subprocesses of the tests run the checkout under test, not whatever ``rsvo_env`` is installed:
the checkout's root goes first on their ``PYTHONPATH``."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


def checkout_env() -> dict[str, str]:
    """This process's environment with the checkout first on ``PYTHONPATH``."""
    env = dict(os.environ)
    rest = env.get("PYTHONPATH")
    env["PYTHONPATH"] = str(ROOT) if not rest else os.pathsep.join([str(ROOT), rest])
    return env


def run_python(*args: str, cwd: str | Path | None = None, **kwargs: Any):
    """``python ARGS`` of this interpreter on the checkout, output captured as text."""
    return subprocess.run(
        [sys.executable, *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=checkout_env(),
        **kwargs,
    )
