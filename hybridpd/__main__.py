"""``python -m hybridpd`` runs the command-line interface."""
import sys

from hybridpd.cli import main

sys.exit(main())
