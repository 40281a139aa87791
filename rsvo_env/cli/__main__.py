import sys

from rsvo_env.cli.main import main

sys.exit(main())
