"""A small TOML writer for the dictionaries regopack produces.

It covers what resolved scenes contain: tables, arrays of tables, strings,
booleans, integers, floats (including ``nan`` and ``inf``), arrays of those
and inline tables. Keys whose value is ``None`` are left out (TOML has no
null). The output reads back with :mod:`tomllib` to the same dictionary.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

__all__ = ["dumps"]

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_ESCAPES = {
    '"': '\\"',
    "\\": "\\\\",
    "\b": "\\b",
    "\t": "\\t",
    "\n": "\\n",
    "\f": "\\f",
    "\r": "\\r",
}


def dumps(data: Mapping[str, Any]) -> str:
    """Serialise ``data`` as a TOML document.

    Examples
    --------
    >>> print(dumps({"name": "a", "domain": {"width": 2.0}}), end="")
    name = "a"
    <BLANKLINE>
    [domain]
    width = 2.0
    """
    lines: list[str] = []
    _table(data, (), lines, header=None)
    return "\n".join(lines).lstrip("\n") + "\n"


def _table(
    data: Mapping[str, Any], path: tuple[str, ...], lines: list[str], header: str | None
) -> None:
    if header is not None:
        if lines:
            lines.append("")
        lines.append(header)
    nested: list[tuple[str, Any]] = []
    in_array = header is not None and header.startswith("[[")
    for key, value in data.items():
        if value is None:
            continue
        if (isinstance(value, Mapping) or _is_table_array(value)) and not in_array:
            nested.append((key, value))
        else:
            lines.append(f"{_key(key)} = {_value(value)}")
    for key, value in nested:  # sub-tables and arrays of tables, in their original order
        sub_path = (*path, key)
        if isinstance(value, Mapping):
            _table(value, sub_path, lines, header=f"[{_dotted(sub_path)}]")
        else:
            for item in value:
                _table(item, sub_path, lines, header=f"[[{_dotted(sub_path)}]]")


def _is_table_array(value: object) -> bool:
    return (
        isinstance(value, Sequence)
        and not isinstance(value, str | bytes)
        and len(value) > 0
        and all(isinstance(v, Mapping) for v in value)
    )


def _dotted(path: tuple[str, ...]) -> str:
    return ".".join(_key(k) for k in path)


def _key(key: str) -> str:
    return key if _BARE_KEY.fullmatch(key) else _string(key)


def _string(text: str) -> str:
    out = []
    for ch in text:
        if ch in _ESCAPES:
            out.append(_ESCAPES[ch])
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _float(value: float) -> str:
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    text = repr(value)
    if "." not in text and "e" not in text:
        text += ".0"
    return text


def _value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return _float(value)
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, Mapping):
        items = (f"{_key(k)} = {_value(v)}" for k, v in value.items() if v is not None)
        return "{ " + ", ".join(items) + " }" if value else "{}"
    if isinstance(value, Sequence) and not isinstance(value, bytes):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    # numpy scalars and other numbers
    if hasattr(value, "item"):
        return _value(value.item())
    raise TypeError(f"cannot write a {type(value).__name__} as TOML")


def first_comment(text: str) -> str:
    """Return the text of a TOML document's leading comment line, or ``""``.

    Only comment lines before the first non-blank, non-comment line count.
    """
    for line in text.splitlines():
        stripped = line.strip()
        if stripped.startswith("#"):
            return stripped.lstrip("#").strip()
        if stripped:
            return ""
    return ""


def parse_toml(text: str, source: str) -> dict[str, Any]:
    """Parse a TOML document; a syntax error becomes one line naming ``source``."""
    import tomllib

    from regopack.base.errors import ConfigError

    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(f"{source}: invalid TOML: {' '.join(str(err).split())}") from err
    except RecursionError:
        raise ConfigError(
            f"{source}: arrays or tables nested too deeply to read (more than Python's "
            "recursion limit); a scene nests a few levels"
        ) from None


def not_a_file(path: Path, what: str) -> str | None:
    """Why ``path`` is no regular file to read as a ``what`` file, or ``None`` when it is one.

    A directory, a named pipe (FIFO), a device or a socket is refused without
    opening it: reading a FIFO would wait for a writer, a device may never end.

    Examples
    --------
    >>> not_a_file(Path("/dev/null"), "scene")
    'is a character device, not a scene file'
    """
    import stat

    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        return f"no such {what} file"
    except OSError as err:
        return f"cannot read the {what} file: {err.strerror or err}"
    if stat.S_ISREG(mode):
        return None
    kinds = (
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISFIFO, "a named pipe (FIFO)"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    )
    kind = next((name for test, name in kinds if test(mode)), "not a regular file")
    article = "an" if what[:1] in "aeiou" else "a"
    return f"is {kind}, not {article} {what} file"


def read_text_file(path: Path, what: str, missing_hint: str = "") -> str:
    """Read a UTF-8 file; a missing or unreadable one is one line naming it.

    ``what`` names the kind of file (``"scene"``, ``"experiment"``);
    ``missing_hint`` is appended to the no-such-file message.
    """
    from regopack.base.errors import ConfigError

    source = str(path)
    problem = not_a_file(path, what)
    if problem is not None:
        raise ConfigError(f"{source}: {problem}{missing_hint if not path.exists() else ''}")
    try:
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise ConfigError(f"{source}: cannot read the {what} file: {err}") from err
