"""The ``vsmatch`` command: thin wrappers over the library, one module per command and
what they share in ``common``.

Exit status: 0 success; 1 a problem with the inputs, data, config or outputs (one line on
stderr, no traceback, no output file left behind), or an unexpected error (one line;
``--debug`` or ``VSMATCH_DEBUG=1`` shows the traceback); 2 a usage error (bad option or
argument); 130 interrupted (Ctrl-C); 143 terminated (SIGTERM).
"""

from . import (batch, bench, datasets, demo, eval, rectify, run,  # noqa: F401 - registers
               video)
from .main import main

__all__ = ["main"]
