"""The documentation: every Python block of README.md and docs/ runs as written in a fresh
interpreter, the site builds with ``mkdocs build --strict``, the gallery shows every registered
id and its pages are what ``docs/gallery.py`` makes of the code, README fits a screen."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.checkout import checkout_env

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
PAGES = [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]


def python_blocks(path: Path) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", path.read_text(), flags=re.S | re.M)


BLOCKS = [
    pytest.param(block, id=f"{page.relative_to(ROOT)}[{i}]")
    for page in PAGES
    for i, block in enumerate(python_blocks(page))
]
# what a block's print says, where the page states it
PRINTED = {
    "docs/scenarios.md[0]": lambda out: out.startswith("True 0 "),
    "docs/liveness.md[0]": lambda out: out.strip() == "[]",
    "docs/threads.md[0]": lambda out: out.split() == ["2", "1"],
    "docs/tutorials/own_simulator.md[0]": lambda out: out.strip().endswith("all home: True"),
    "docs/tutorials/walls_for_unicycles.md[0]": lambda out: out.startswith("True 0 "),
    "docs/tutorials/train_behind_the_filter.md[0]": lambda out: out.strip() == "contacts: 0",
    "docs/tutorials/train_behind_the_filter.md[1]": lambda out: (
        out.startswith("filter on contacts: 0\nfilter off contacts: ")
        and not out.strip().endswith("contacts: 0")
    ),
}


def docs_env() -> dict[str, str]:
    """The checkout under test first on the path, figures without a display."""
    return checkout_env(MPLBACKEND="Agg")


def test_every_page_with_code_is_collected():
    """The collector sees the blocks (a fence it missed would pass silently)."""
    fences = sum(p.read_text().count("```python\n") for p in PAGES)
    assert len(BLOCKS) == fences >= 20


@pytest.mark.parametrize("block", BLOCKS)
def test_python_block_runs_as_written(block, request, tmp_path):
    name = request.node.callspec.id
    done = subprocess.run(
        [sys.executable, "-c", block],
        cwd=tmp_path,  # a block that writes files writes them here
        env=docs_env(),
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, f"{name} failed:\n{done.stderr[-3000:]}"
    if name in PRINTED:
        assert PRINTED[name](done.stdout), f"{name} printed {done.stdout!r}"


def load_gallery():
    spec = importlib.util.spec_from_file_location("gallery", DOCS / "gallery.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_gallery_pages_are_made_from_the_code():
    """Each id's page and the gallery are what docs/gallery.py makes of the registry and the
    scenarios' defaults now: run it with --pages after changing either."""
    gallery = load_gallery()
    ids = gallery.registered()
    for env_id, scenario in ids.items():
        page = DOCS / "scenarios" / f"{scenario}.md"
        assert page.read_text() == gallery.scenario_page(env_id, scenario), page
    assert (DOCS / "gallery.md").read_text() == gallery.gallery_page(ids)


def test_gallery_shows_every_registered_id_with_its_picture():
    import gymnasium

    import rsvo_env  # noqa: F401  (registers the ids)

    text = (DOCS / "gallery.md").read_text()
    ids = [k for k in gymnasium.registry if k.startswith("rsvo/")]
    assert len(ids) >= 7
    gallery = load_gallery()
    for env_id in ids:
        scenario = gallery.registered()[env_id]
        assert f"`{env_id}`" in text and f"images/{scenario}.png" in text
        for ext in ("png", "gif"):
            picture = DOCS / "images" / f"{scenario}.{ext}"
            assert picture.stat().st_size > 10_000, picture  # a drawn picture, not a stub
        page = (DOCS / "scenarios" / f"{scenario}.md").read_text()
        assert f"../images/{scenario}.gif" in page


def test_the_site_builds_strictly(tmp_path):
    """``mkdocs build --strict``: a broken link, a missing anchor or an API name mkdocstrings
    cannot find fails it. The reference names the filter and the batched env."""
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(tmp_path / "site")],
        cwd=ROOT,
        env=docs_env() | {"NO_MKDOCS_2_WARNING": "1"},
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    reference = (tmp_path / "site" / "reference" / "index.html").read_text()
    for name in ("SafetyFilter", "BatchedEnv", "FilterConfig", "RCBFSafetyFilter"):
        assert re.search(rf'id="(rsvo_env\.[\w.]*)?{name}"', reference), name
    assert (tmp_path / "site" / "gallery" / "index.html").exists()
    assert (tmp_path / "site" / "results" / "rorca_speed" / "index.html").exists()
    # the formulas are MathML, built in: no script, no network
    maths = (tmp_path / "site" / "math" / "index.html").read_text()
    assert maths.count("<math") >= 20 and "$$" not in maths
    assert (tmp_path / "site" / "images" / "doorway.gif").exists()


def test_every_docs_page_is_in_the_sites_navigation():
    nav = (ROOT / "mkdocs.yml").read_text()
    for page in DOCS.rglob("*.md"):
        assert str(page.relative_to(DOCS)) in nav, page


def test_readme_fits_a_screen_and_leads_with_its_two_commands():
    readme = (ROOT / "README.md").read_text()
    assert len(readme.encode()) <= 15_000
    head = "\n".join(readme.splitlines()[:40])
    assert "rsvo reproduce" in head and "python -m pytest" in head
    for target in re.findall(r"\]\(((?:docs|benchmarks)/[^)#]+)", readme):
        assert (ROOT / target).exists(), target


def test_cli_scene_example_runs(tmp_path, capsys):
    """docs/cli.md's YAML scene, as written, through ``rsvo simulate custom --scene``."""
    from rsvo_env.cli import main as rsvo

    text = (DOCS / "cli.md").read_text()
    scene = re.search(r"^```yaml\n(.*?)^```", text, flags=re.S | re.M).group(1)
    (tmp_path / "scene.yaml").write_text(scene)
    assert rsvo.main(["simulate", "custom", "--scene", str(tmp_path / "scene.yaml")]) == 0
    out = capsys.readouterr().out
    assert re.search(r"n_collision_steps: 0\b", out) and re.search(r"success: True", out)
