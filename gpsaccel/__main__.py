"""``python -m gpsaccel``: the ``gpsaccel`` command."""

import sys

from gpsaccel.cli import main

sys.exit(main())
