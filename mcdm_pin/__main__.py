"""``python -m mcdm_pin``: the command line."""

import sys

from .cli import main

sys.exit(main())
