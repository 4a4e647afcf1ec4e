"""`python -m afsmc`: the same command as `afsmc`."""

import sys

from afsmc.cli import main

sys.exit(main())
