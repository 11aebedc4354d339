"""``python -m vsmatch``: the same as the ``vsmatch`` command."""

from .cli import main

main()
