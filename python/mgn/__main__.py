"""``python -m mgn`` runs the command line."""

import sys

from mgn.cli.main import main

sys.exit(main())
