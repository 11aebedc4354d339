"""``python -m vsmatch``: the same as the ``vsmatch`` command."""

from .cli.console import main

main()
