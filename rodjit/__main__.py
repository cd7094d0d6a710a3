"""``python -m rodjit`` runs the command line (``rodjit.entry.main``, as the installed
``rodjit`` command does)."""
from .entry import main

main()
