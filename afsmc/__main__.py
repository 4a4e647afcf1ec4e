"""`python -m afsmc`: the same command as `afsmc`."""

import sys

from afsmc.cli import entry

sys.exit(entry())
