"""``python -m roe_sep.cli``: the same as ``roe-sep``."""

import sys

from . import main

sys.exit(main())
