"""``python -m linkagekit``: the command line, as the ``linkagekit`` script runs it (:func:`linkagekit.cli.main`)."""

from .cli import main

if __name__ == "__main__":
    main()
