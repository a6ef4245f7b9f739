"""``python -m catenary_env.cli ...``: the ``catenary`` command."""

import sys

from . import main

sys.exit(main())
