"""``python -m sweepik.cli``: the ``sweepik`` command."""

import sys

from sweepik.cli.app import main

sys.exit(main())
