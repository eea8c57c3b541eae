"""``python -m gpmsa.cli``: the ``gpmsa`` console command."""

import sys

from gpmsa.cli.main import main

sys.exit(main())
