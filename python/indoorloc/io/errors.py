"""The one error type of indoorloc's file readers.

Every loader in :mod:`indoorloc.io` reports a damaged or unexpected file with
:class:`FormatError`, a :class:`ValueError` subclass, whose message names the file, the line,
row or variable, and what was expected, e.g.
``indoorloc: argument 'path': walk.txt: line 12: 3 fields, expected at least 5``.
Python's own errors met while parsing a damaged file (IndexError, KeyError, OverflowError,
RecursionError, UnicodeDecodeError, ...) are re-raised as FormatError by :func:`reading`, so a
caller needs one ``except ValueError`` (or ``except FormatError``) around any loader.

What a loader keeps despite damage it reports with :class:`RecordingWarning` instead (the rule
"nothing is lost", docs/errors.md): a damaged optional field is dropped for its line, a truncated
final line is dropped, and a floor reader skips a walk it cannot read; the warning names the file
and the reader's notes keep the counts.
"""

from __future__ import annotations

import contextlib
import functools
import inspect
import os
from typing import Any, Callable, Iterator, Optional, TypeVar, Union

PathLike = Union[str, "os.PathLike[str]"]
F = TypeVar("F", bound=Callable[..., Any])

# What a damaged file can make a parser raise besides ValueError.
_PARSE_ERRORS = (IndexError, KeyError, TypeError, AttributeError, OverflowError, RecursionError,
                 UnicodeError, EOFError)


class FormatError(ValueError):
    """A data file that cannot be read as the format it claims to be.

    Attributes
    ----------
    path : str or None
        The file (or folder) concerned.
    where : str or None
        The line, row, field or variable, when known.
    """

    def __init__(self, message: str, path: Optional[PathLike] = None,
                 where: Optional[str] = None) -> None:
        super().__init__(message)
        self.path = None if path is None else os.fspath(path)
        self.where = where


class RecordingWarning(UserWarning):
    """A recording was read, but not all of it: a damaged optional field dropped for its line, a
    truncated final line dropped, or (floor readers) a walk that could not be read skipped.

    The message names the file; the reader's notes give the counts (e.g. ``IlcWalk.notes``,
    ``IlcWalk.dropped_fields``, ``IlcFloor.load_report()``). Silence it with
    ``warnings.simplefilter("ignore", RecordingWarning)``; make it an error with ``"error"``.
    """


def format_error(path: PathLike, problem: str, *, where: Optional[str] = None,
                 argument: str = "path") -> FormatError:
    """``FormatError("indoorloc: argument '<argument>': <path>: [<where>: ]<problem>")``."""
    place = f"{where}: " if where else ""
    return FormatError(f"indoorloc: argument '{argument}': {os.fspath(path)}: {place}{problem}",
                       path=path, where=where)


@contextlib.contextmanager
def reading(path: PathLike, *, argument: str = "path", what: str = "file") -> Iterator[None]:
    """Re-raises Python's parsing errors inside the block as FormatError naming `path`.

    indoorloc's own ValueErrors (FormatError included) pass unchanged: they already name the
    argument; a bare ValueError from a parser (numpy, json, int()) is wrapped like the others.
    """
    try:
        yield
    except FormatError:
        raise
    except ValueError as exc:  # UnicodeDecodeError is one too
        message = str(exc)
        prefix = f"indoorloc: argument '{argument}"
        if (message.startswith(prefix) and message[len(prefix):len(prefix) + 2] in ("':", " (")
                and not isinstance(exc, UnicodeError)):
            # The reader's own message about the file (or a column of it, "'path (gyroscope
            # columns)'"): the same text, the library's type, and the file named.
            if os.fspath(path) not in message:
                message += f" (file {os.fspath(path)})"
            raise FormatError(message, path=path) from exc
        if message.startswith("indoorloc:") and not isinstance(exc, UnicodeError):
            raise  # about another argument (a rate, a name): not the file's fault
        raise format_error(path, f"damaged {what} ({type(exc).__name__}: {exc})",
                           argument=argument) from exc
    except _PARSE_ERRORS as exc:
        if isinstance(exc, TypeError) and str(exc).startswith("indoorloc:"):
            raise  # the library's own TypeError about an argument of the wrong type
        detail = str(exc) or type(exc).__name__
        if isinstance(exc, RecursionError):
            detail = "nesting too deep"
        raise format_error(path, f"damaged {what} ({type(exc).__name__}: {detail})",
                           argument=argument) from exc


def reads_file(parameter: str = "path", what: str = "file",
               argument: Optional[str] = None) -> Callable[[F], F]:
    """Decorator: the loader's errors about its file or folder become FormatError.

    `parameter` is the loader's parameter holding the file; `argument` the name its messages
    use ("indoorloc: argument '<argument>': ..."), by default the same.
    """
    argument = argument or parameter

    def decorate(fn: F) -> F:
        signature = inspect.signature(fn)

        @functools.wraps(fn)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            try:
                target = signature.bind(*args, **kwargs).arguments.get(parameter, "?")
            except TypeError:
                return fn(*args, **kwargs)  # Python's own message about the call
            label = target if isinstance(target, (str, os.PathLike)) else repr(target)
            with reading(label, argument=argument, what=what):
                return fn(*args, **kwargs)

        return wrapper  # type: ignore[return-value]

    return decorate


__all__ = ["FormatError", "RecordingWarning", "format_error", "reading", "reads_file"]
