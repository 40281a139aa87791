"""rsvo reproduce: the paper's experiments (Sec. V) as one command: position swap, ramp merge,
circular game and "who benefits", written as paper.md with its figures and GIFs. Each runs the
paper's own scripted controller (move-to-goal and the right-hand rule) behind the filter.

Output goes to --out (default ./rsvo-results, where you run the command); a README's results
block is refreshed only with --readme. Every file written is printed. Every number in paper.md
comes from this run; the same seed gives the same file, byte for byte, but for the wall time.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from rsvo_env.cli import figures, report
from rsvo_env.cli.studies import Plan, circular, position_swap, ramp_merge, who_benefits
from rsvo_env.util.arguments import Parser, UserError, check_output, count


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
    written = [out_dir / "position_swap.png", out_dir / "ramp_merge.png"]
    figures.position_swap(ps["runs"], written[0])
    figures.ramp_merge(rm["figure_runs"], written[1])
    written += figures.circular(cg["runs"], out_dir)
    written += [out_dir / f"circular_{w}.gif" for w in ("symmetric", "asymmetric")]
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
    written.insert(0, out_dir / "paper.md")
    if readme is not None:
        root = readme.resolve().parent
        rel = (
            out_dir.resolve().relative_to(root)
            if out_dir.resolve().is_relative_to(root)
            else out_dir
        )
        report.write_readme(report.readme_block(ps, rm, cg, diff, rel), readme)
        written.append(readme)
    return {
        "position_swap": ps,
        "ramp_merge": rm,
        "circular": cg,
        "who_benefits": wb,
        "wall_time": wall,
        "paper_md": out_dir / "paper.md",
        "written": written,
    }


def main(argv: list[str] | None = None) -> int:
    ap = Parser(
        prog="rsvo reproduce",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument(
        "--quick", action="store_true", help="a small run, about half a minute (default: full)"
    )
    ap.add_argument(
        "--out",
        type=Path,
        default=Path("rsvo-results"),
        help="output folder (default: %(default)s)",
    )
    ap.add_argument(
        "--seed", type=count(0), default=0, help="seed of every run (default: %(default)s)"
    )
    ap.add_argument(
        "--readme",
        type=Path,
        default=None,
        help="also refresh the results block of this README (default: none)",
    )
    args = ap.parse_args(argv)
    check_output(args.out, directory=True)
    if args.readme is not None and not args.readme.is_file():
        raise UserError(f"--readme {args.readme}: no such file")
    res = reproduce(args.out, quick=args.quick, seed=args.seed, readme=args.readme)
    for path in res["written"]:
        print(f"wrote {path}")
    print(f"done in {res['wall_time']:.1f} s")
    return 0 if res["circular"]["collisions"] == 0 else 1
