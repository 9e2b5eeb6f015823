"""``python -m indoorloc.cli`` runs the command line (same as ``python -m indoorloc``)."""

import sys

from indoorloc.cli import main

sys.exit(main())
