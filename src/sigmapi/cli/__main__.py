"""``python -m sigmapi.cli``: the ``sigmapi`` command."""

import sys

from sigmapi.cli import main

sys.exit(main())
