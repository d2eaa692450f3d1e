"""The exit codes of SEARCH's exits, for ``tapp search``, ``tapp simulate``'s retargeting and
the JSON that reports them (no numpy: the CLI imports this module on ``--help``)."""


def exit_code(status: str) -> int | None:
    """The exit code of a SEARCH exit: 0 converged, the seed's FLAG + 1 otherwise (3
    diverged, 4 singular); None for a status that is not one of SEARCH's exits."""
    from search import EXIT_FLAG

    flag = EXIT_FLAG.get(status)
    return None if flag is None else 0 if status == "converged" else flag + 1
