"""``python -m rodjit`` runs the command line."""
from .cli import main

main(prog_name="rodjit")
