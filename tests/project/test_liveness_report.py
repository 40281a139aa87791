"""benchmarks/reports/liveness_report.py: the figures of the crowd of 10,000 that docs/liveness.md
quotes (the least ratio of the shares at goal, the diagnosis table) computed from the runs'
arrival series, and the figures written in benchmarks/results/liveness.md consistent with its
own share table."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from benchmarks.reports import liveness_report as report

ROOT = Path(__file__).resolve().parents[2]


def _run(shares: np.ndarray) -> dict:
    return {"arrived": shares, "closest": 1.0}


def test_the_least_ratio_is_the_least_over_every_step_from_its_start_orca_held_once_done():
    steps = 40
    ours = np.linspace(0.01, 0.5, steps)
    orca = np.linspace(0.02, 1.0, 30)  # ORCA finishes at step 30: its share held at 1.0 after
    ours[35] = 0.05  # the dip: 0.05 against ORCA's held 1.0
    ours[5] = 0.0  # before the start (25 steps of 0.05 s = 1.25 s): counted at every time only
    rows = [{"n": 10, "seed": 3, "ours": _run(ours), "orca": _run(orca)}]
    line = report.least_ratio(rows, start=1.25)[0]
    assert "at every time, the share at goal is at least 0.00 times ORCA's" in line
    theirs = f"{100 * orca[5]:.2f} %, 2 agents"
    assert f"(the least at 0.30 s: 0.00 %, 0 agents against {theirs}, under 0.9 times" in line
    assert "it last at 2.00 s (50.00 %, 5 agents against 100.00 %, 10 agents)" in line
    assert "from 1 s on, at least 0.05 times ORCA's" in line
    assert "(the least at 1.80 s: 5.0 % against 100.0 %)" in line
    ours[35] = 0.5
    ours[5] = orca[5]
    line = report.least_ratio(rows, start=1.25)[0]
    late = min(ours[k] / orca[min(k, 29)] for k in range(24, steps))
    every = min(ours[k] / orca[min(k, 29)] for k in range(steps))
    assert f"at every time, the share at goal is at least {every:.2f} times" in line
    assert f"on, at least {late:.2f} times" in line
    assert ("under 0.9 times" in line) == (every < 0.9)


def test_a_step_where_orca_has_no_agent_home_bounds_nothing():
    ours = np.array([0.0, 0.0, 0.1, 0.2])
    orca = np.array([0.0, 0.0, 0.1, 0.4])
    rows = [{"n": 10, "seed": 0, "ours": _run(ours), "orca": _run(orca)}]
    least = "at every time, the share at goal is at least {} times"
    assert least.format("0.50") in report.least_ratio(rows, 0.1)[0]
    orca[1] = 0.1  # ORCA has an agent home at a step where we have none
    assert least.format("0.00") in report.least_ratio(rows, 0.1)[0]


def test_the_diagnosis_rows_read_each_share_at_its_mark_and_divide_by_orcas_at_the_last():
    marks = report.DIAGNOSIS_MARKS
    steps = int(round(marks[-1] / report.DT))
    orca = np.full(steps, 0.5)
    ours = np.full(steps, 0.1)
    for t, share in zip(marks, (0.1, 0.2, 0.3, 0.4), strict=True):
        ours[int(round(t / report.DT)) - 1] = share
    ours[200] = 0.01  # before 25 s: not counted in the least ratio
    ours[1500] = 0.04  # the dip, at 75.05 s
    rows = [{"label": "a", "ours": _run(ours)}, {"label": "ORCA", "ours": _run(orca)}]
    long = [{"label": "b", "ours": _run(np.linspace(0.0, 1.0, report.BIG_CAP))}]
    table = report.diagnosis_section(rows, long)
    row = next(line for line in table if line.startswith("| a |"))
    assert row == "| a | 10.0 % | 20.0 % | 30.0 % | 40.0 % | 0.80 | 0.08 (75.05 s) | 1.0000 |"
    row = next(line for line in table if line.startswith("| b |"))
    want = [100 * (round(t / report.DT) - 1) / (report.BIG_CAP - 1) for t in report.BIG_MARKS]
    assert row == "| b | " + " | ".join(f"{x:.1f} %" for x in want) + " | 1.0000 |"


def _section(text: str, heading: str) -> str:
    body = text[text.index(heading + "\n") :]
    return body[: body.find("\n## ", 1)]


def test_the_written_crowds_meet_what_docs_liveness_says_of_them():
    """The crowds as benchmarks/results/liveness.md records them (the crowd's defaults, routed):
    the crowd of 10,000 of seed 0 (issue 45's) at least 0.9 times ORCA's share at every time, and
    every seed of the section from 25 s on (the written least no more than its share table's),
    every agent home by 450 s; the crowds of 1,000 of both seed sets every agent home, within 1.2
    times ORCA's makespan."""
    text = (ROOT / "benchmarks/results/liveness.md").read_text()
    big = _section(text, report.BIG_HEADING)
    for seed in report.BIG_SEEDS:
        line = re.search(rf"- N = 10,000, seed {seed}: (.*)\n", big)[1]
        every, late = (float(x) for x in re.findall(r"at least ([0-9.]+) times", line))
        cells = re.search(rf"\| 10,000 \| {seed} \| (.*) \|\n", big)[1].split(" | ")
        pairs = [[float(x) for x in re.findall(r"([0-9.]+) %", c)] for c in cells]
        assert every <= late <= min(a / b for a, b in pairs) + 0.005
        assert late >= 0.9 and (seed != 0 or every >= 0.9)
        assert pairs[report.BIG_MARKS.index(450.0)][0] >= 99.9
    rows = [
        re.search(
            r"\| 1,000 \| 10 \| ([0-9.]+) %, ([0-9.]+) % \|.*\| ([0-9.]+), [0-9.]+ \(",
            _section(text, heading),
        ).groups()
        for heading in ("## Crowd", report.HELD_OUT_HEADING)
    ]
    for mean, worst, ratio in rows:
        assert float(mean) == float(worst) == 100.0 and float(ratio) <= 1.2
