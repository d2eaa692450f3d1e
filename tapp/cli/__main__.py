"""``python -m tapp.cli``: the same as the ``tapp`` console script."""

from tapp.cli import main

main()
