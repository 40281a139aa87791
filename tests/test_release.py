"""What a packager checks: one version, read from one place and printed by ``rsvo --version``;
the licence and the type marker shipped."""

import importlib.metadata
import re
import subprocess
from pathlib import Path

from checkout import run_python

import rsvo_env

ROOT = Path(__file__).resolve().parents[1]


def test_one_version_everywhere_written_once():
    version = rsvo_env.__version__
    assert re.fullmatch(r"\d+\.\d+\.\d+", version)
    assert importlib.metadata.version("rsvo-env") == version
    out = run_python("-m", "rsvo_env.cli", "--version")
    assert out.returncode == 0 and out.stdout.strip() == f"rsvo {version}"
    tracked = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True)
    written = [
        name for name in tracked.stdout.split()
        if name.endswith((".py", ".toml", ".cfg")) and f'"{version}"' in (ROOT / name).read_text()
    ]  # fmt: skip
    assert written == ["rsvo_env/__init__.py"], written


def test_the_licence_and_the_type_marker_are_declared():
    meta = importlib.metadata.metadata("rsvo-env")
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")
    assert "LICENSE" in (meta.get_all("License-File") or [])
    assert "Typing :: Typed" in (meta.get_all("Classifier") or [])
    assert (ROOT / "rsvo_env" / "py.typed").exists()
    pyproject = (ROOT / "pyproject.toml").read_text()
    assert '"rsvo_env" = ["py.typed"]' in pyproject
