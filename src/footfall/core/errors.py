"""User-facing errors.

Every error a user can cause with a bad file or a bad argument is a
:class:`FootfallError`; the command line prints its message on one line and
exits with status 2.
"""


def one_line(message: str) -> str:
    """``message`` on one line: line breaks and runs of white space become one space, other
    control characters (a file name can hold any) their escapes, e.g. ``\\x0c``."""
    text = " ".join(str(message).split())
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


class FootfallError(ValueError):
    """A problem with the user's input: a bad file, argument or configuration.

    Its message is always one line (:func:`one_line`), whatever a library's message it quotes.
    """

    def __init__(self, message: object = "") -> None:
        super().__init__(one_line(str(message)))


class NotFound(FootfallError):
    """Something asked for by name or number is not there: a run, a step, a label."""
