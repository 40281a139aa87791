"""What a packager checks: one version, read from one place and printed by ``rsvo --version``;
the licence and the type marker shipped."""

import importlib.metadata
import re
import subprocess
from pathlib import Path

import rsvo_env
from tests.support.checkout import run_python

ROOT = Path(__file__).resolve().parents[2]


def test_one_version_everywhere_written_once():
    version = rsvo_env.__version__
    assert re.fullmatch(r"\d+\.\d+\.\d+", version)
    assert importlib.metadata.version("rsvo-env") == version
    out = run_python("-m", "rsvo_env.cli", "--version")
    assert out.returncode == 0 and out.stdout.strip() == f"rsvo {version}"
    tracked = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True)
    written = [
        name
        for name in tracked.stdout.split()
        if name.endswith((".py", ".toml", ".cfg")) and f'"{version}"' in (ROOT / name).read_text()
    ]
    assert written == ["rsvo_env/__init__.py"], written


def test_the_licence_and_the_type_marker_are_declared():
    meta = importlib.metadata.metadata("rsvo-env")
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")
    assert "LICENSE" in (meta.get_all("License-File") or [])
    assert "Typing :: Typed" in (meta.get_all("Classifier") or [])
    assert (ROOT / "rsvo_env" / "py.typed").exists()
    pyproject = (ROOT / "pyproject.toml").read_text()
    assert '"rsvo_env" = ["py.typed"]' in pyproject


def test_the_changelog_has_a_section_for_the_version():
    changelog = (ROOT / "CHANGELOG.md").read_text()
    assert f"## [{rsvo_env.__version__}] - " in changelog
    assert changelog.index("## [Unreleased]") < changelog.index(f"## [{rsvo_env.__version__}]")


def test_the_package_list_is_every_package_folder_and_the_mapped_two():
    """pyproject.toml names the packages (a mapping rules out setuptools' finder): the list is
    every folder with an ``__init__.py`` under rsvo_env/, plus the two mapped folders."""
    import tomllib

    table = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    found = {
        ".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "rsvo_env").rglob("__init__.py")
    }
    mapped = {name for name in table["package-dir"] if name}
    assert set(table["packages"]) == found | mapped
    assert mapped == {"rsvo_env.wrappers", "rsvo_env.training"}


def test_rsvo_reaches_training_from_the_command_line():
    for command in ("train", "evaluate"):
        out = run_python("-m", "rsvo_env.cli", command, "--help")
        assert out.returncode == 0 and out.stdout.startswith(f"usage: rsvo {command}"), out.stderr
    out = run_python("-m", "rsvo_env.training.train", "--help")
    assert out.returncode == 0 and "usage: python -m rsvo_env.training.train" in out.stdout
