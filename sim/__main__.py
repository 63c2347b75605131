"""`python -m sim`: the headless command line."""

import sys

from sim.commands import main

sys.exit(main())
