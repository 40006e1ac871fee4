"""User-facing errors.

Every error a user can cause with a bad file or a bad argument is a
:class:`FootfallError`; the command line prints its message on one line and
exits with status 2.
"""


class FootfallError(ValueError):
    """A problem with the user's input: a bad file, argument or configuration."""
