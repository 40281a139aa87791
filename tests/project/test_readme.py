"""README's quickstart and test command (its Python blocks, and the docs', run in test_docs.py)."""

import re
from pathlib import Path

README = (Path(__file__).resolve().parents[2] / "README.md").read_text()


def test_readme_has_the_quickstart():
    quick = README.split("## Quickstart", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    lines = [ln for ln in quick.strip().splitlines() if ln.strip()]
    assert len(lines) == 5
    assert "gymnasium.make" in lines[1] and "reset" in lines[2]
    assert "nominal_action" in lines[3] and "render" in lines[4]


def test_ci_runs_exactly_the_readme_test_command():
    """README says its test command is exactly what .ci/run does; hold it to that."""
    root = Path(__file__).resolve().parents[2]
    block = README.split("The tests (this is exactly what `.ci/run` does)", 1)[1]
    command = block.split("```bash\n", 1)[1].split("```", 1)[0].strip()
    script = (root / ".ci" / "run").read_text().splitlines()
    steps = [ln.strip() for ln in script if ln.strip() and not ln.startswith(("#", "set ", "cd "))]
    assert command == " && ".join(steps)


def test_property_tests_are_derandomized_unless_exploring():
    """README: the test command draws the same examples every run; the explore profile not."""
    from hypothesis import settings

    assert "--hypothesis-profile=explore" in README
    assert settings.default.derandomize and settings.default.database is None
    assert not settings.get_profile("explore").derandomize


SCENARIOS_DOC = (Path(__file__).resolve().parents[2] / "docs" / "scenarios.md").read_text()
SCENARIO_BLOCKS = re.findall(r"```python\n(.*?)```", SCENARIOS_DOC, flags=re.S)


def test_scenarios_doc_has_a_custom_scene_in_code():
    assert any('parallel_env("custom"' in b for b in SCENARIO_BLOCKS)
