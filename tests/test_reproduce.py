"""``rsvo reproduce --quick``: the tables' structure, the paper's claims, byte-for-byte reruns."""

import re
from pathlib import Path

import pytest

from rsvo_env.cli import main as cli
from rsvo_env.cli.reproduce import reproduce


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    a = tmp_path_factory.mktemp("a")
    b = tmp_path_factory.mktemp("b")
    assert cli.main(["reproduce", "--quick", "--out", str(a)]) == 0
    res = reproduce(b, quick=True)
    return a, b, res


def strip_wall_time(text):
    return re.sub(r"^Wall time: .*$", "", text, flags=re.M)


def test_rerun_is_byte_identical_but_for_wall_time(runs):
    a, b, _ = runs
    text_a, text_b = (a / "paper.md").read_text(), (b / "paper.md").read_text()
    assert re.search(r"^Wall time: \d+\.\d s$", text_a, flags=re.M)
    assert strip_wall_time(text_a) == strip_wall_time(text_b)


FIXTURE = Path(__file__).parent / "fixtures" / "paper_quick.md"


def numbers_of(text):
    """Every table row, and every decimal number of the prose, but the wall time."""
    lines = [ln for ln in text.splitlines() if not ln.startswith("Wall time")]
    tables = [ln for ln in lines if ln.startswith("|")]
    prose = " ".join(ln for ln in lines if not ln.startswith("|"))
    return tables, re.findall(r"-?\d+\.\d+", prose)


def test_same_numbers_as_before_the_batch_core(runs):
    """The quick run prints the numbers the pre-batch-core code printed (a committed copy)."""
    a, _, _ = runs
    tables, prose = numbers_of((a / "paper.md").read_text())
    want_tables, want_prose = numbers_of(FIXTURE.read_text())
    assert len(tables) > 40
    assert tables == want_tables
    assert prose == want_prose


def test_tables_and_figures(runs):
    a, _, _ = runs
    text = (a / "paper.md").read_text()
    for heading in (
        "## 1. Position swap",
        "## 2. Ramp merge",
        "## 3. Circular game",
        "## 4. Who benefits the most?",
        "## Where we differ from the paper",
    ):
        assert heading in text
    swap_rows = re.findall(r"^\| [12] \| 0\.\d / 0\.\d \|.*\| (\d+) \|$", text, flags=re.M)
    assert len(swap_rows) == 6 and all(c == "0" for c in swap_rows)  # no collision step
    assert re.search(r"^\| symmetric \| \d+ \| 140 \| \d+ \| 390 \| \d+ \| 620 \|", text, re.M)
    assert re.search(r"^\| asymmetric \| \d+ \| 142 \| \d+ \| 275 \| \d+ \| 415 \|", text, re.M)
    assert "Collision steps over all random sets: 0;" in text
    assert (
        len(re.findall(r"^\| (capability|sign_aware|paper) \| (braking|hocbf) \| 3 \|", text, re.M))
        == 6
    )
    for name in (
        "position_swap.png",
        "ramp_merge.png",
        "circular_symmetric.png",
        "circular_asymmetric.png",
        "avg_min_distance.png",
        "circular_symmetric.gif",
        "circular_asymmetric.gif",
    ):
        assert (a / name).stat().st_size > 5000, name


def test_the_papers_claims_hold(runs):
    _, _, res = runs
    cg = res["circular"]
    assert cg["collisions"] == 0
    o_s, r_s, c_s = cg["sym"]
    o_a, r_a, c_a = cg["asym"]
    assert c_s is not None and c_a is not None
    assert cg["no_rule"]["symmetric"][2] is None  # deadlock without the right-hand rule
    assert r_a - o_a < r_s - o_s  # the asymmetric game resolves the deadlock faster
    assert res["position_swap"]["ratio_min"] > 1.0
    cap, pap = res["ramp_merge"]["capability"], res["ramp_merge"]["paper"]
    assert cap["egoist_first"] == cap["unequal"] > 0
    assert cap["unsafe"] == 0 and cap["infeasible"] == 0
    assert pap["egoist_first"] == 0  # the literal split makes the egoist yield
