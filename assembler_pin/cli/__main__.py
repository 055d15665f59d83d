"""``python -m assembler_pin.cli``: the ``assembler-pin`` command."""

import sys

from .app import main

sys.exit(main())
