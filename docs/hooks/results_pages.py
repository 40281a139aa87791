"""An mkdocs hook: the results files of ``benchmarks/results/`` (each benchmark's tables and
figures, written by the command at its head) become the site's pages under ``results/``, as
they are in the checkout, so that a page citing a results file has one a reader can open."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from mkdocs.structure.files import File, Files

RESULTS = Path(__file__).resolve().parents[2] / "benchmarks" / "results"
KINDS = (".md", ".png", ".gif")


def results_files() -> list[Path]:
    """The results files the site publishes: every table and figure (the JSON stays data)."""
    return sorted(p for p in RESULTS.iterdir() if p.suffix in KINDS)


def on_files(files: Files, config: Any) -> Files:
    for path in results_files():
        uri = f"results/{path.name}"
        if path.suffix == ".md":
            files.append(File.generated(config, uri, content=path.read_text()))
        else:
            files.append(File.generated(config, uri, abs_src_path=str(path)))
    return files
