"""The one error type for refused input: every bad file, setting or campaign gyrocal refuses raises
an `InputError` that names the file, where in it (line, column or key) and what is wrong, and
says what to do where it knows. The command line and every pipeline step print it without a
traceback and exit non-zero."""

import errno

__all__ = ["ECHO_MAX_CHARS", "InputError", "OutputError", "excerpt"]

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


class OutputError(OSError):
    """A result gyrocal could not write (a full disk, a quota, a read-only directory): not refused
    input, so no variant is marked refused for it; the command line and every pipeline step print
    its message without a traceback and exit non-zero. Nothing was written at ``path`` (results
    are written whole or not at all) and the temporary beside it was removed."""

    def __init__(self, path, cause: OSError):
        code = errno.errorcode.get(cause.errno, "") if cause.errno else ""
        reason = cause.strerror or str(cause)
        todo = ("free space on its disk" if cause.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)
                else "check that its directory is writable")
        super().__init__(cause.errno, f"{path}: could not be written: {reason}" + (f" ({code})" if code else "")
                         + f"; nothing was written there and its temporary was removed. {todo[:1].upper()}{todo[1:]}, "
                         "and run again")
        self.path = str(path)
        self.todo = todo

    def __str__(self) -> str:
        return self.strerror
