"""The benchmarks as a package: a handful of files at the top, every script importable as
``benchmarks.<kind>.<name>``, the machine line and the results folder written once (the
harness), and a test layout of folders by layer."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BENCHMARKS = ROOT / "benchmarks"
SCRIPTS = sorted(p for p in BENCHMARKS.glob("*/*.py") if p.name != "__init__.py")
# the RLlib benchmark runs in the RLlib venv (tests_rllib's), where ray is installed
NEEDS_RAY = {"rllib_speed"}


def test_the_top_holds_at_most_ten_scripts_and_tests_are_grouped():
    assert len(list(BENCHMARKS.glob("*.py"))) <= 10
    assert len(SCRIPTS) >= 20
    tests = ROOT / "tests"
    folders = [p for p in tests.iterdir() if p.is_dir() and (p / "__init__.py").exists()]
    assert len(folders) >= 4 and len(list(tests.glob("*.py"))) <= 15


@pytest.mark.parametrize("script", [p for p in SCRIPTS if p.stem not in NEEDS_RAY], ids=str)
def test_every_script_imports_as_a_module_of_the_package(script):
    importlib.import_module(f"benchmarks.{script.parent.name}.{script.stem}")


def test_the_machine_line_and_the_results_folder_have_one_owner():
    """Only the harness asks the platform what machine this is, and only it names the results
    folder; a script that wrote its own once put its results beside itself."""
    offenders = []
    for path in SCRIPTS:
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and node.attr in ("machine", "processor"):
                if isinstance(node.value, ast.Name) and node.value.id == "platform":
                    offenders.append(f"{path.name}:{node.lineno} platform.{node.attr}")
            if isinstance(node, ast.Constant) and node.value == "results":
                offenders.append(f"{path.name}:{node.lineno} its own results folder")
    assert not offenders, offenders
    from benchmarks import harness

    assert harness.RESULTS == BENCHMARKS / "results" and harness.RESULTS.is_dir()
