"""The package as the wheel installs it, laid out from the checkout.

The repository keeps ``wrappers/`` and ``training/`` beside ``rsvo_env/`` (the layout the client
fixed); the wheel installs them as ``rsvo_env.wrappers`` and ``rsvo_env.training``
(pyproject.toml's ``package-dir``). Tools that read sources from folders (mkdocstrings,
import-linter, the type checker) read such a layout; the tests' subprocesses import one made of
links. As an mkdocs hook it points mkdocstrings at a copy laid out for the build.
"""

from __future__ import annotations

import atexit
import shutil
import tempfile
from pathlib import Path
from typing import Any

import tomllib

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = "rsvo_env"


def mapped_folders(root: Path = ROOT) -> dict[str, str]:
    """Package name -> the checkout folder pyproject.toml's ``package-dir`` maps it from."""
    table = tomllib.loads((root / "pyproject.toml").read_text())["tool"]["setuptools"]
    return {name: folder for name, folder in table["package-dir"].items() if name}


def lay_out(dest: Path, copy: bool, root: Path = ROOT) -> Path:
    """``dest/rsvo_env`` as installed: the checkout's ``rsvo_env/`` with the mapped folders
    inside it. ``copy``: copies of the sources; else links to them (edits show at once, and the
    compiled kernels' caches are the checkout's). Returns ``dest``."""
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")

    def put(source: Path, target: Path) -> None:
        if not copy:
            target.symlink_to(source, target_is_directory=source.is_dir())
        elif source.is_dir():
            shutil.copytree(source, target, ignore=ignore)
        else:
            shutil.copy2(source, target)

    (dest / PACKAGE).mkdir(parents=True)
    for child in sorted((root / PACKAGE).iterdir()):
        if child.name != "__pycache__":
            put(child, dest / PACKAGE / child.name)
    for name, folder in mapped_folders(root).items():
        put(root / folder, dest.joinpath(*name.split(".")))
    return dest


def temporary_layout(copy: bool) -> Path:
    """A layout in a temporary folder, removed when the process exits."""
    dest = Path(tempfile.mkdtemp(prefix="rsvo-layout-"))
    atexit.register(shutil.rmtree, dest, True)
    return lay_out(dest / "site-packages", copy)


def on_config(config: Any) -> Any:
    """mkdocs: mkdocstrings reads the package from a copy laid out as installed (it finds
    modules by their folders, and ``rsvo_env.wrappers`` has none under ``rsvo_env/``)."""
    handlers = config.plugins["mkdocstrings"].config.handlers
    handlers.setdefault("python", {})["paths"] = [str(temporary_layout(copy=True))]
    return config


on_config.mkdocs_priority = 100  # before mkdocstrings' own on_config reads its handlers
