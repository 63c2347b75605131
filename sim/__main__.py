"""`python -m sim`: the headless command line."""

import sys

from .commands import main

sys.exit(main())
