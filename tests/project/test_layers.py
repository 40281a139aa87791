"""The house (docs/architecture.md): no import cycle in rsvo_env over any form of import, the
layers kept as import-linter's contracts, a top level that shows the subpackages."""

from __future__ import annotations

import ast
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support import checkout
from tests.support.checkout import layout

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "rsvo_env"


def module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def import_graph(root: Path = PACKAGE) -> dict[str, set[str]]:
    """Module -> the package's modules it imports: at module level, under TYPE_CHECKING and
    inside functions alike; ``from a import b`` counts as importing ``a.b`` when b is a module,
    else ``a`` (its ``__init__``)."""
    files = {module_name(p, root): p for p in root.rglob("*.py")}
    top = root.name

    def resolve(name: str) -> str | None:
        while name and name not in files:
            name = name.rpartition(".")[0]
        return name or None

    graph: dict[str, set[str]] = {}
    for name, path in files.items():
        deps: set[str | None] = set()
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                deps |= {resolve(a.name) for a in node.names if a.name.split(".")[0] == top}
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    parts = package.split(".")
                    base = ".".join(parts[: len(parts) - node.level + 1] + ([base] if base else []))
                if base.split(".")[0] != top:
                    continue
                for a in node.names:
                    full = f"{base}.{a.name}"
                    deps.add(full if full in files else resolve(base))
        graph[name] = {d for d in deps if d and d != name}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []
    for start in graph:
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on.add(start)
        while work:
            v, edges = work[-1]
            for w in edges:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    if len(comp) > 1:
                        found.append(sorted(comp))
    return found


def test_no_import_cycle_in_rsvo_env(tmp_path):
    """Over the package as installed: the wrappers and training inside it."""
    site = layout.lay_out(tmp_path / "site", copy=True)
    graph = import_graph(site / "rsvo_env")
    assert "rsvo_env.wrappers.registered" in graph and "rsvo_env.training.train" in graph
    assert cycles(graph) == []


def test_the_cycle_finder_finds_cycles(tmp_path):
    """It sees a cycle through a function-level import, a TYPE_CHECKING one, a relative one
    and one through a package's __init__."""
    pkg = tmp_path / "rsvo_env"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("def f():\n    from rsvo_env import b\n")
    (pkg / "b.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import rsvo_env.a\n"
    )
    (pkg / "sub" / "__init__.py").write_text("from rsvo_env.sub.c import X\n")
    (pkg / "sub" / "c.py").write_text("from .d import Y\nX = 1\n")
    (pkg / "sub" / "d.py").write_text("from rsvo_env.sub import X\nY = 2\n")
    found = cycles(import_graph(pkg))
    assert ["rsvo_env.a", "rsvo_env.b"] in found
    assert ["rsvo_env.sub", "rsvo_env.sub.c", "rsvo_env.sub.d"] in found


def test_import_linter_contracts_are_kept(tmp_path):
    """The layers of pyproject.toml's [tool.importlinter], checked by import-linter itself over
    the package as the wheel lays it out (``rsvo_env.wrappers`` and ``rsvo_env.training`` in
    it): every layer is found, none is empty."""
    lint = shutil.which("lint-imports") or str(Path(sys.executable).parent / "lint-imports")
    if not Path(lint).exists():
        pytest.fail("import-linter is not installed (it is in the dev extra)")
    site = layout.lay_out(tmp_path / "site", copy=True)
    out = subprocess.run(
        [lint, "--no-cache", "--config", str(ROOT / "pyproject.toml")],
        cwd=site,
        env=checkout.checkout_env() | {"PYTHONPATH": str(site)},
        capture_output=True,
        text=True,
    )
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    assert "0 broken" in out.stdout and "Contracts: 2 kept, 0 broken." in out.stdout
    for layer in ("training", "wrappers", "envs", "cli"):
        assert (site / "rsvo_env" / layer / "__init__.py").exists(), layer


def test_the_layout_puts_the_mapped_folders_inside_the_package():
    """What the contract and the type checker read is what the wheel installs."""
    assert layout.mapped_folders() == {
        "rsvo_env.wrappers": "wrappers",
        "rsvo_env.training": "training",
    }


def test_at_most_eight_modules_over_30_lines_at_the_top():
    """The subpackages carry the code; the top level holds the package's face and one-line
    re-exports of the paths README and docs show."""
    big = [p.name for p in PACKAGE.glob("*.py") if len(p.read_text().splitlines()) > 30]
    assert len(big) <= 8, big


def outside(*folders: str) -> list[Path]:
    """The package's modules outside the folder ``folders`` names (a path under the package)."""
    return [
        p for p in PACKAGE.rglob("*.py") if p.relative_to(PACKAGE).parts[: len(folders)] != folders
    ]


def name_comparisons(source: str, names: set[str]) -> list[str]:
    """Every comparison in ``source`` with a string constant among ``names`` (``x == "a"``,
    ``x in ("a", "b")``, ``"a" != x``), as ``line: code``."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Compare):
            constants = [
                c.value
                for operand in [node.left, *node.comparators]
                for c in ast.walk(operand)
                if isinstance(c, ast.Constant) and isinstance(c.value, str)
            ]
            if names & set(constants):
                found.append(f"{node.lineno}: {ast.unparse(node)}")
    return found


def test_the_name_comparison_finder_finds_every_form():
    source = 'a = x == "b"\nif "b" != y: pass\nz = w in ("c", "b")\nq = x == "other"\n'
    assert [f.split(":")[0] for f in name_comparisons(source, {"b"})] == ["1", "2", "3"]


def test_no_branch_on_a_model_outside_dynamics():
    """Nothing outside dynamics/ compares a model's name or asks whether a model has headings:
    it asks the model."""
    from rsvo_env.dynamics import MODELS

    offenders = []
    for path in outside("dynamics"):
        source = path.read_text()
        offenders += [f"{path.name}:{f}" for f in name_comparisons(source, set(MODELS))]
        if "needs_headings" in source:
            offenders.append(f"{path.name} needs_headings")
    assert not offenders, offenders


def test_no_branch_on_a_barrier_outside_the_barrier_modules():
    """Nothing outside dynamics/barriers/ compares a barrier's name: the model and the filter
    ask the barrier the registry gives (``barriers.get``)."""
    from rsvo_env.dynamics.barriers import BARRIERS

    offenders = [
        f"{path.relative_to(PACKAGE)}:{f}"
        for path in outside("dynamics", "barriers")
        for f in name_comparisons(path.read_text(), set(BARRIERS))
    ]
    assert not offenders, offenders


def test_no_branch_on_a_controller_outside_control():
    """Nothing outside control/ compares a controller's name: the scenario asks the controller
    the registry gives (``control.get``)."""
    from rsvo_env.control import CONTROLLERS

    offenders = [
        f"{path.relative_to(PACKAGE)}:{f}"
        for path in outside("control")
        for f in name_comparisons(path.read_text(), set(CONTROLLERS))
    ]
    assert not offenders, offenders


def test_control_holds_at_most_six_modules_and_the_scenario_base_no_controller_setting():
    """R-ORCA is one subpackage; the scenario base neither names a controller's setting nor
    imports a controller's modules, only the registry."""
    from rsvo_env.control import settings

    assert len(list((PACKAGE / "control").glob("*.py"))) <= 6
    base = (PACKAGE / "scenarios" / "base.py").read_text()
    assert settings() and not [key for key in settings() if key in base]
    assert "rorca" not in base


def parameter_counts() -> tuple[list[str], list[str]]:
    """Plain functions over 12 parameters, compiled kernels over 16 (self not counted)."""
    plain, kernels = [], []
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            a = node.args
            n = len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs)
            n += (a.vararg is not None) + (a.kwarg is not None)
            n -= bool(a.args) and a.args[0].arg in ("self", "cls")
            compiled = any("jit" in ast.unparse(d) for d in node.decorator_list)
            if n > (16 if compiled else 12):
                (kernels if compiled else plain).append(f"{path.name}:{node.name} ({n})")
    return plain, kernels


def test_no_plain_function_over_12_parameters_and_few_wide_kernels():
    plain, kernels = parameter_counts()
    assert plain == []
    assert len(kernels) <= 3, kernels


def private_names_crossing(root: Path) -> list[str]:
    """Every ``from m import _x`` and ``m._x`` (m a module of the package, imported) in the
    package's modules: what another module needs is public."""
    found = []
    for path in root.rglob("*.py"):
        tree = ast.parse(path.read_text())
        aliases = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith(root.name):
                for a in node.names:
                    if a.name.startswith("_") and not a.name.startswith("__"):
                        found.append(f"{path.name}:{node.lineno} {node.module}.{a.name}")
                    aliases.add(a.asname or a.name)
            elif isinstance(node, ast.Import):
                aliases |= {a.asname or a.name for a in node.names if a.name.startswith(root.name)}
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Attribute)
                and node.attr.startswith("_")
                and not node.attr.startswith("__")
                and isinstance(node.value, ast.Name)
                and node.value.id in aliases
            ):
                found.append(f"{path.name}:{node.lineno} {node.value.id}.{node.attr}")
    return found


def test_no_module_imports_another_modules_private_name(tmp_path):
    site = layout.lay_out(tmp_path / "site", copy=True)
    assert private_names_crossing(site / "rsvo_env") == []


def test_the_private_name_finder_finds_both_forms(tmp_path):
    pkg = tmp_path / "rsvo_env"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("def _hidden():\n    pass\n")
    (pkg / "b.py").write_text("from rsvo_env.a import _hidden\n")
    (pkg / "c.py").write_text("from rsvo_env import a\n\na._hidden()\n")
    found = private_names_crossing(pkg)
    assert sorted(f.split(" ")[0] for f in found) == ["b.py:1", "c.py:3"], found


def test_the_size_thresholds_have_one_owner():
    """Every module-level number that bounds a size (``*_MAX_*``, ``*_MIN_*``) where the library
    changes its method lives in util/sizes.py; the others read ``sizes.NAME``."""
    import re

    pattern = re.compile(r"^[A-Z_]*_(MAX|MIN)_[A-Z_]*\s*=\s*[0-9]", re.MULTILINE)
    owners = [
        p.relative_to(PACKAGE).as_posix()
        for p in PACKAGE.rglob("*.py")
        if pattern.search(p.read_text())
    ]
    assert owners == ["util/sizes.py"], owners
