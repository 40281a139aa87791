"""The paper's reproduction as committed in this checkout: ``rsvo reproduce`` (the same code,
in rsvo_env/cli) writing to benchmarks/results and refreshing README's results block.

python -m benchmarks.studies.reproduce_paper [--quick] [--seed N]
"""

import sys

from benchmarks.harness import RESULTS, ROOT
from rsvo_env.cli.reproduce import main

if __name__ == "__main__":
    args = sys.argv[1:]
    defaults = ["--out", str(RESULTS)]
    if "--quick" not in args:
        defaults += ["--readme", str(ROOT / "README.md")]
    sys.exit(main(defaults + args))
