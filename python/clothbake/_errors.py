"""The exceptions clothbake raises: one hierarchy under clothbake.Error.

A failed call of the C interface raises the subclass of its cb_result, carrying the result's name
(``code``, e.g. ``"CB_ERROR_INVALID_ASSET"``), its number (``result``) and the library's message
(``message``: the asset's path or "asset in memory", the check ID ``CBK-Ennn`` when there is one,
and the reader's words). A failed bake raises BakeError, whose ``code`` is the name of the
`clothbake` command's exit code (``"input"``, ``"usage"``, ``"invalid_asset"``, ``"internal"``).
Bad array shapes and dtypes are not clothbake errors: they raise ValueError and TypeError naming
the argument.
"""

from __future__ import annotations


class Error(Exception):
    """Base class of every clothbake error: ``code`` names it, ``message`` says what failed."""

    code: str
    result: int | None
    message: str

    def __init__(self, code: str, message: str, result: int | None = None) -> None:
        super().__init__(f"{code}: {message}")
        self.code = code
        self.message = message
        self.result = result


class InvalidArgumentError(Error, ValueError):
    """CB_ERROR_INVALID_ARGUMENT: a bad footprint, direction, option, lobe mask or random number."""


class FileError(Error, OSError):
    """CB_ERROR_IO: the asset file cannot be opened, sized or mapped."""


class InvalidAssetError(Error):
    """CB_ERROR_INVALID_ASSET: not an asset, another major version, truncated, corrupt or failing
    validation (the message names the check, CBK-Ennn)."""


class NotFoundError(Error):
    """CB_ERROR_NOT_FOUND: the asset lacks what the evaluator or the method needs."""


class UnsupportedError(Error):
    """CB_ERROR_UNSUPPORTED: valid but not readable here, or the evaluator's own tables could not
    be allocated."""


class OutOfMemoryError(Error, MemoryError):
    """CB_ERROR_OUT_OF_MEMORY: an allocation of the C interface failed."""


class OutOfPlanError(Error):
    """CB_ERROR_OUT_OF_PLAN: a scene-planned asset left out what the query needs (estimate it
    with method="brute", which reads no tables, or shade it as 0)."""


class BakeError(Error):
    """A bake failed: ``code`` is "input" (bad fabric, maps, unwritable output, too large for
    max_memory), "usage", "invalid_asset" or "internal"; nothing was written at the output."""


_BY_RESULT: dict[int, type[Error]] = {
    1: InvalidArgumentError,
    2: FileError,
    3: InvalidAssetError,
    4: NotFoundError,
    5: UnsupportedError,
    6: OutOfMemoryError,
    7: OutOfPlanError,
}


def error_for(result: int, name: str, message: str) -> Error:
    """The exception for a failed C call: the subclass of ``result`` (Error for an unknown one)."""
    return _BY_RESULT.get(result, Error)(name, message, result)
