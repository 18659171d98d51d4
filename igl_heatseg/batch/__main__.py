"""``python -m igl_heatseg.batch``: the job server a batch worker starts (see
:mod:`igl_heatseg.batch.server`); not a user command (``igl-heatseg batch`` is)."""

import sys

from .server import main

if __name__ == "__main__":
    sys.exit(main())
