"""Argument types shared by the commands of ``regopack`` (``cli`` and ``sweep_cli``)."""

from __future__ import annotations

import argparse
from pathlib import Path

__all__ = ["output_path"]


def output_path(text: str) -> Path:
    """Argument type of ``--out``: a path, never the empty string (which would mean ``.``)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(
            f"{text!r} is an empty path; give a folder or file name, e.g. runs/mine"
        )
    return Path(text)
