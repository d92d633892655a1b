"""``python -m magtact.validation``: regenerate the SYNTHETIC example data set."""

from ._synthetic import main

main()
