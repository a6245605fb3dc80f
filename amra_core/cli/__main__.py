"""``python -m amra_core.cli``: the same as the ``amra`` command."""
import sys

from . import main

sys.exit(main())
