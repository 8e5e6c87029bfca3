"""``python -m gcs`` runs the command-line interface."""

import sys

from gcs.cli import main

sys.exit(main())
