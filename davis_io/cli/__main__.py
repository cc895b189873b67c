"""Allow ``python -m davis_io.cli``."""

import sys

from davis_io.cli import main

sys.exit(main())
