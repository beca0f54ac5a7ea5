"""The one error type for refused input: every bad file, setting or campaign gyrocal refuses raises
an `InputError` that names the file, where in it (line, column or key) and what is wrong, and
says what to do where it knows. The command line and every pipeline step print it without a
traceback and exit non-zero."""

__all__ = ["ECHO_MAX_CHARS", "InputError", "excerpt"]

ECHO_MAX_CHARS = 60
"""A value echoed in a message is cut to this many characters of its ``repr`` (an 8 MB cell is
named, not printed)."""


def excerpt(value, limit: int = ECHO_MAX_CHARS) -> str:
    """``repr(value)``, cut to ``limit`` characters with its full length said where it is longer."""
    text = repr(value)
    if len(text) <= limit:
        return text
    size = f"{len(value)} characters" if isinstance(value, (str, bytes)) else f"{len(text)} characters written"
    return f"{text[:limit]}... ({size})"


class InputError(ValueError):
    """Refused input. ``str(error)`` is the whole message: ``<file>: <where>: <what>. <what to do>``."""

    def __init__(self, message: str, *, path=None, where: str = "", todo: str = ""):
        super().__init__(message)
        self.path = None if path is None else str(path)
        self.where = where
        self.todo = todo

    @classmethod
    def at(cls, path, what: str, where: str = "", todo: str = "") -> "InputError":
        """The error for ``what`` is wrong at ``where`` in the file ``path``, and what to do."""
        message = f"{path}: " + (f"{where}: " if where else "") + what + (f". {todo[:1].upper()}{todo[1:]}" if todo else "")
        return cls(message, path=path, where=where, todo=todo)
