"""``python -m gtsp_bench.cli``: the command line."""

import sys

from gtsp_bench.cli import main

sys.exit(main())
