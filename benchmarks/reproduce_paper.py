"""The paper's reproduction; the same code as ``rsvo reproduce`` (it lives in rsvo_env/cli).

python benchmarks/reproduce_paper.py [--quick] [--out DIR] [--seed N]
"""

import sys

from rsvo_env.cli.reproduce import main

if __name__ == "__main__":
    sys.exit(main())
