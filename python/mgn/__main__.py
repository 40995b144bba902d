"""``python -m mgn`` runs the command line."""

import sys

from mgn.cli import main

sys.exit(main())
