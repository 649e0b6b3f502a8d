"""``python -m frenbrdf.cli``: the ``frenbrdf`` command (torchrun launches it so)."""

import sys

from . import main

sys.exit(main())
