"""``python -m workcell.cli``: the ``multiarm`` command."""

import sys

from workcell.cli.main import main

sys.exit(main())
