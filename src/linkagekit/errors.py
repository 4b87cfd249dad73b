"""One exception family for everything linkagekit reports to a user.

Every message names what is wrong and where (file, key, joint, link), so that the
command line can print it as one line and exit with the status the error carries.

>>> issubclass(InputError, ValueError) and issubclass(UnknownNameError, LookupError)
True
"""

from __future__ import annotations

#: the longest quoted value in a message; the longest message line the CLI prints
MAX_QUOTE = 60
MAX_MESSAGE = 300


def shorten(text: str, limit: int = MAX_QUOTE) -> str:
    r"""A value for a message: control characters escaped, cut to ``limit`` characters with an ellipsis.

    >>> shorten("a\nb" + "x" * 100, 10)
    'a\\nbxxxxx…'
    """
    clean = "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in str(text))
    return clean if len(clean) <= limit else clean[: limit - 1] + "…"


def shorten_path(path: str, limit: int = MAX_QUOTE) -> str:
    r"""A file path for a message, cut at its start so that its file name stays readable.

    >>> shorten_path("/a/very/long/directory/name/target.yaml", 20)
    '…ry/name/target.yaml'
    """
    clean = shorten(path, len(str(path)) * 4 + 1)  # escaped, not cut
    return clean if len(clean) <= limit else "…" + clean[len(clean) - limit + 1 :]


def one_line(message: str, limit: int = MAX_MESSAGE) -> str:
    """A message as one printable line of at most ``limit`` characters."""
    return shorten(" ".join(str(message).split("\n")), limit)


class LinkageError(Exception):
    """Base class of every error linkagekit raises on purpose.

    Attributes
    ----------
    exit_code : int
        The command line's exit status for this error (2: bad input, 1: anything else).
    """

    exit_code = 1


class InputError(LinkageError, ValueError):
    """A bad argument: input values, driver names, options."""

    exit_code = 2


class MechanismFileError(InputError):
    """A mechanism file (or dictionary) is malformed or inconsistent."""

    exit_code = 2


class UnknownNameError(LinkageError, KeyError):
    """A joint, link, driver or column name that the mechanism or result does not have.

    A :class:`KeyError` (so a :class:`LookupError`) whose text is the plain message.
    """

    exit_code = 2

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class NotSolvableError(LinkageError):
    """A valid mechanism that the closed-form solver cannot handle."""

    exit_code = 1


class MethodNotApplicableError(NotSolvableError, InputError):
    """A method asked for (``method="vector-loop"``) that does not cover this mechanism: a bad argument."""

    exit_code = 2
