"""``python -m magtact`` runs the command-line interface."""

from magtact.cli import main

main()
