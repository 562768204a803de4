"""``python -m warpsim.cli``: the ``warpsim`` command (as ``python -m warpsim``)."""

import sys

from .main import main

sys.exit(main())
