"""The error of a scene field whose value is well formed but cannot be honoured."""

from __future__ import annotations

from regopack.base.errors import ConfigError
from regopack.base.messages import format_value

__all__ = ["FieldValueError"]


class FieldValueError(ConfigError):
    """A scene field's value that is well formed but that the run cannot honour.

    Parameters
    ----------
    field
        The dotted scene field (e.g. ``density.phi``).
    value
        That field's value (shown in the message), or ``None``.
    text
        Why it cannot be honoured and what is allowed.

    Attributes
    ----------
    field, value, text
        As given; ``str(err)`` is ``"<field> = <value>: <text>"``.
    """

    def __init__(self, field: str, value: object, text: str) -> None:
        self.field = field
        self.value = value
        self.text = text
        super().__init__(self.located(None))

    def located(self, source: str | None) -> str:
        """Return the one-line message, prefixed with ``source`` (a file or ``--set``) if given."""
        shown = format_value(self.value) if self.value is not None else None
        head = f"{self.field} = {shown}" if shown is not None else self.field
        return f"{source}: {head}: {self.text}" if source else f"{head}: {self.text}"
