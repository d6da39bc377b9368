"""The warm-up that conftest.py starts on a cold cache asks for valid scenes."""

from __future__ import annotations

import kernel_warmup

import regopack


def test_every_warmup_step_is_a_valid_scene() -> None:
    # the warm-up runs with its output discarded: a step broken by a renamed
    # field would only make the suite slower, so it is checked here
    kinds = set()
    for changes, threads in kernel_warmup.STEPS:
        resolved = regopack.scene("small", **{**kernel_warmup.TINY, **changes})
        kinds.add((resolved.insertion.kind, threads))
    assert ("available-arc", 2) in kinds and ("rsa", 1) in kinds
    box = regopack.scene("small", **{**kernel_warmup.TINY, **kernel_warmup.BOX})
    assert box.insertion.kind == "available-surface"
