"""``rsvo reproduce``: the paper's experiments (Sec. V) as one command, tables and figures.

Writes ``paper.md`` and PNG figures (and two GIFs) to ``--out`` (default
``benchmarks/results`` in a checkout); the full run also refreshes README's Results section.
Every number in ``paper.md`` comes from this run; the same seed gives the same file, byte for
byte, but for the line that reports the wall time.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from rsvo_env.cli import figures, report
from rsvo_env.cli.studies import Plan, circular, position_swap, ramp_merge, who_benefits

ROOT = Path(__file__).resolve().parents[2]


def reproduce(
    out_dir: Path, quick: bool = False, seed: int = 0, readme: Path | None = None
) -> dict[str, Any]:
    """Run every study, write ``paper.md`` and the figures; returns the headline numbers."""
    from tqdm import tqdm

    out_dir.mkdir(parents=True, exist_ok=True)
    plan = Plan(quick=quick, seed=seed)
    t0 = time.perf_counter()
    with tqdm(total=plan.total_runs, desc="rsvo reproduce", unit="run") as bar:
        ps = position_swap.study(plan, bar.update)
        rm = ramp_merge.study(plan, bar.update)
        cg = circular.study(plan, bar.update, out_dir)
    wb = who_benefits.study(cg)
    figures.position_swap(ps["runs"], out_dir / "position_swap.png")
    figures.ramp_merge(rm["figure_runs"], out_dir / "ramp_merge.png")
    figures.circular(cg["runs"], out_dir)
    wall = time.perf_counter() - t0
    diff = report.differences(ps, rm, cg)
    doc = [
        "# Reproducing the paper",
        "",
        f"Written by `rsvo reproduce{' --quick' if quick else ''}` (seed {seed}). Every "
        "number below comes from this run; the scripted nominal controller runs behind "
        "the R-CBF filter (exact solver).",
        "",
        f"Wall time: {wall:.1f} s",
        "",
        *report.position_swap(ps),
        *report.ramp_merge(rm, plan),
        *report.circular(cg, plan),
        *report.who_benefits(wb, len(cg["sets"])),
        "## Where we differ from the paper",
        "",
        *diff,
        "",
    ]
    (out_dir / "paper.md").write_text("\n".join(doc))
    if readme is not None:
        root = readme.resolve().parent
        rel = (
            out_dir.resolve().relative_to(root)
            if out_dir.resolve().is_relative_to(root)
            else out_dir
        )
        report.write_readme(report.readme_block(ps, rm, cg, diff, rel), readme)
    return {
        "position_swap": ps,
        "ramp_merge": rm,
        "circular": cg,
        "who_benefits": wb,
        "wall_time": wall,
        "paper_md": out_dir / "paper.md",
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="rsvo reproduce", description=__doc__)
    ap.add_argument("--quick", action="store_true", help="a small run (about half a minute)")
    ap.add_argument(
        "--out",
        type=Path,
        default=None,
        help="output folder (default benchmarks/results in a checkout, else ./rsvo-results)",
    )
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--no-readme", action="store_true", help="do not refresh README's Results section"
    )
    args = ap.parse_args(argv)
    in_checkout = (ROOT / "README.md").exists() and (ROOT / "benchmarks").is_dir()
    out = args.out or (ROOT / "benchmarks" / "results" if in_checkout else Path("rsvo-results"))
    readme = None
    if not (args.quick or args.no_readme or args.out is not None) and in_checkout:
        readme = ROOT / "README.md"
    res = reproduce(out, quick=args.quick, seed=args.seed, readme=readme)
    print(f"wrote {res['paper_md']} in {res['wall_time']:.1f} s")
    return 0 if res["circular"]["collisions"] == 0 else 1
