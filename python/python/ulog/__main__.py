"""``python -m ulog``: the ``ulog`` command-line tool."""

from ._cli import main

main()
