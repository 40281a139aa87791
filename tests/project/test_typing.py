"""The type checker: mypy over ``rsvo_env`` as the wheel lays it out (the wrappers and training
inside it), at the strictness pyproject.toml's ``[tool.mypy]`` documents, with zero errors."""

from __future__ import annotations

import subprocess
import sys

from tests.support.checkout import ROOT, layout


def test_mypy_finds_no_error_in_the_package(tmp_path):
    site = layout.lay_out(tmp_path / "site", copy=True)
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "mypy",
            "-p",
            "rsvo_env",
            "--config-file",
            str(ROOT / "pyproject.toml"),
            "--cache-dir",
            str(tmp_path / "cache"),
        ],
        cwd=site,
        capture_output=True,
        text=True,
        timeout=1200,
    )
    assert done.returncode == 0, done.stdout[-6000:] + done.stderr[-2000:]
    assert "Success: no issues found" in done.stdout
    checked = int(done.stdout.split("in ")[-1].split()[0])
    assert checked >= 120  # every module, the wrappers and training among them
