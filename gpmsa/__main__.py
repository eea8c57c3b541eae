"""``python -m gpmsa``: the ``gpmsa`` console command (as ``python -m gpmsa.cli``)."""

import sys

from gpmsa.cli.main import main

sys.exit(main())
