"""``python -m sim.cli``: the ``go2-wbc`` command."""

import sys

from sim.cli import main

sys.exit(main())
