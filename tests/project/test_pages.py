"""The site's pages are written for readers: the result, the method, the argument. How a result
was reached (issue numbers, the commits it was measured at) belongs in the changelog."""

from __future__ import annotations

import re

from tests.support.checkout import ROOT

HISTORY = re.compile(r"\b[Ii]ssues? #?\d+|\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*\d)[0-9a-f]{7,40}\b")


def history_in(text: str) -> list[str]:
    return [m.group(0) for m in HISTORY.finditer(text)]


def test_no_issue_number_or_commit_hash_in_a_page():
    found = {
        str(p.relative_to(ROOT)): history_in(p.read_text())
        for p in sorted((ROOT / "docs").rglob("*.md"))
        if history_in(p.read_text())
    }
    assert not found, found


def test_the_check_finds_both():
    assert history_in("since issue 45, measured at 230d50f") == ["issue 45", "230d50f"]
    assert history_in("a 1,000-agent crowd, seed 1008, colour #1f77b4") == []


def test_every_results_file_is_a_page_of_the_site():
    """The results files the pages cite are published (``docs/hooks/results_pages.py``) and
    each is in the navigation."""
    nav = (ROOT / "mkdocs.yml").read_text()
    results = sorted((ROOT / "benchmarks" / "results").glob("*.md"))
    assert len(results) >= 20
    missing = [p.name for p in results if f"results/{p.name}" not in nav]
    assert not missing, missing
    assert "docs/hooks/results_pages.py" in nav


def test_formulas_become_mathml_and_code_stays_code():
    import importlib.util

    spec = importlib.util.spec_from_file_location("maths", ROOT / "docs" / "hooks" / "maths.py")
    assert spec is not None and spec.loader is not None
    maths = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(maths)
    out = maths.render("weight $\\omega_i$, paid `$5`, and\n\n$$h^+ \\ge 0$$\n\n```\n$x$\n```\n")
    assert out.count("<math") == 2 and 'display="block"' in out
    assert "`$5`" in out and "```\n$x$\n```" in out
