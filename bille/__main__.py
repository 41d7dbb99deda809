"""``python -m bille``: the ``bille`` command line."""
from bille.tools.cli import main

main()
