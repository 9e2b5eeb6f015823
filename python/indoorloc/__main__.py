"""``python -m indoorloc`` runs the command line."""

import sys

from indoorloc.cli import main

sys.exit(main())
