"""The paper's reproduction as committed in this checkout: ``rsvo reproduce`` (the same code,
in rsvo_env/cli) writing to benchmarks/results and refreshing README's results block.

python -m benchmarks.studies.reproduce_paper [--quick] [--seed N]
"""

import sys
from pathlib import Path

from rsvo_env.cli.reproduce import main

ROOT = Path(__file__).resolve().parents[2]

if __name__ == "__main__":
    args = sys.argv[1:]
    defaults = ["--out", str(ROOT / "benchmarks" / "results")]
    if "--quick" not in args:
        defaults += ["--readme", str(ROOT / "README.md")]
    sys.exit(main(defaults + args))
