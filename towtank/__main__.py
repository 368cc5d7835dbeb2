"""``python -m towtank``: the same command line as the ``towtank`` script."""

import sys

from towtank.cli import main

if __name__ == "__main__":
    sys.exit(main())
