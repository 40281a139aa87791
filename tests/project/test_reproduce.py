"""``rsvo reproduce --quick``: the tables' structure, the paper's claims, byte-for-byte reruns."""

import re
from pathlib import Path

import pytest
from PIL import Image

from rsvo_env.cli.reproduce import reproduce
from tests.support.checkout import run_python

ROOT = Path(__file__).resolve().parents[2]


def checkout_state():
    """What a run must not touch: README and the committed results."""
    files = [ROOT / "README.md", *sorted((ROOT / "benchmarks" / "results").iterdir())]
    return {str(f): f.read_bytes() for f in files}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The command as a user runs it, from a folder outside the checkout, and the function."""
    elsewhere = tmp_path_factory.mktemp("elsewhere")
    before = checkout_state()
    out = run_python("-m", "rsvo_env.cli", "reproduce", "--quick", cwd=elsewhere)
    assert out.returncode == 0, out.stderr[-2000:]
    assert checkout_state() == before  # the checkout is untouched
    a = elsewhere / "rsvo-results"
    written = [
        ln.removeprefix("wrote ") for ln in out.stdout.splitlines() if ln.startswith("wrote ")
    ]
    assert sorted(Path(w).name for w in written) == sorted(p.name for p in a.iterdir())
    b = tmp_path_factory.mktemp("b")
    res = reproduce(b, quick=True)
    return a, b, res


def strip_wall_time(text):
    return re.sub(r"^Wall time: .*$", "", text, flags=re.M)


def test_rerun_is_byte_identical_but_for_wall_time(runs):
    a, b, _ = runs
    text_a, text_b = (a / "paper.md").read_text(), (b / "paper.md").read_text()
    assert re.search(r"^Wall time: \d+\.\d s$", text_a, flags=re.M)
    assert strip_wall_time(text_a) == strip_wall_time(text_b)


FIXTURE = Path(__file__).parents[1] / "fixtures" / "paper_quick.md"


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


def test_figures_explain_themselves(runs):
    """The trajectory figure names every agent with its theta and role, every marker, the
    marked events, and has a colour bar for theta (read back from the matplotlib artists)."""
    import matplotlib.pyplot as plt

    from rsvo_env.cli.figures import event_marks
    from rsvo_env.envs.rendering import plot_trajectories

    out = runs[2]["circular"]["runs"]["asym"]
    marks, labels = event_marks(out)
    fig = plot_trajectories(
        out["trajectory"], out["goals"], out["theta"], 1.0, marks=marks, mark_labels=labels
    )
    ax = fig.axes[0]
    legend = ax.get_legend() or fig.legends[0]  # below the axes, placed by the layout
    entries = [t.get_text() for t in legend.get_texts()]
    assert "agent 1: theta = 2 (altruist)" in entries
    assert "agent 2: theta = 1 (egoist)" in entries
    for text in ("start", "goal", "path", "final position (disc: R/2; number: agent)"):
        assert text in entries
    assert f"positions at deadlock onset (step {out['deadlock_onset']})" in entries
    assert f"positions at resolved (step {out['deadlock_resolved']})" in entries
    bar = fig.axes[1]  # the colour bar's axes
    assert "egoist" in bar.get_ylabel() and "altruist" in bar.get_ylabel()
    numbers = {t.get_text() for t in ax.texts}
    assert numbers == {str(i + 1) for i in range(6)}  # each label sits on its agent's disc
    plt.close(fig)


def test_gif_frames_have_real_durations(runs):
    a, _, _ = runs
    gif = Image.open(a / "circular_asymmetric.gif")
    durations = []
    for k in range(gif.n_frames):
        gif.seek(k)
        durations.append(gif.info["duration"])
    # rsvo simulate writes every 5th step of dt = 0.01 s: 20 frames per second, 50 ms each
    assert gif.n_frames > 10 and set(durations) == {50}
