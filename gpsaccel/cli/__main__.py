"""``python -m gpsaccel.cli``: the ``gpsaccel`` command (as ``python -m gpsaccel``)."""

import sys

from gpsaccel.cli import main

sys.exit(main())
