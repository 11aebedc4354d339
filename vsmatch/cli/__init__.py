"""The ``vsmatch`` command: thin wrappers over the library, one module per command and
what they share in ``common``.

Exit status: 0 success; 1 a problem with the inputs, data, config or outputs (one line on
stderr, no traceback, no output file left behind), or an unexpected error (one line;
``--debug`` or ``VSMATCH_DEBUG=1`` shows the traceback); 2 a usage error (bad option or
argument); 130 interrupted (Ctrl-C); 143 terminated (SIGTERM).

``main`` (the Click group) is loaded when first asked for, with every command; the
console script starts in :mod:`vsmatch.cli.console`, which loads it.
"""

from __future__ import annotations

__all__ = ["main"]


def load_group():
    """The ``vsmatch`` group with every command registered."""
    from . import (batch, bench, datasets, demo, eval, rectify, run,  # noqa: F401 - registers
                   video)
    from .main import main as group

    globals()["main"] = group  # the group, not the submodule of the same name
    return group


def __getattr__(name: str):
    if name == "main":
        return load_group()
    raise AttributeError(f"module 'vsmatch.cli' has no attribute '{name}'")
