"""``python -m workcell.cli``: the ``multiarm`` command."""

import sys

from workcell.cli.main import main

if __name__ == "__main__":
    sys.exit(main())
