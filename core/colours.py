"""Colours of the minerals, chosen by name so that a mineral keeps its colour in every scene.

The palette is Okabe and Ito's, which stays distinguishable with the common
forms of colour blindness. The Chang'e-5 minerals have fixed colours; other
names take the colours left over, in alphabetical order, so that the same set
of names always gets the same colours whatever the order of the phases.
"""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["MINERAL_COLOURS", "PALETTE", "mineral_colours"]

PALETTE: tuple[str, ...] = (
    "#E69F00",  # orange
    "#56B4E9",  # sky blue
    "#009E73",  # bluish green
    "#F0E442",  # yellow
    "#0072B2",  # blue
    "#D55E00",  # vermillion
    "#CC79A7",  # reddish purple
    "#999999",  # grey
)
"""Okabe–Ito colours."""

MINERAL_COLOURS: dict[str, str] = {
    "pyroxene": PALETTE[0],
    "feldspar": PALETTE[1],
    "plagioclase": PALETTE[1],
    "glass": PALETTE[2],
    "olivine": PALETTE[3],
    "ilmenite": PALETTE[4],
    "others": PALETTE[5],
}
"""Fixed colours of the minerals of the built-in scenes (names compared in lower case)."""

_EXTRA: tuple[str, ...] = (
    PALETTE[6],
    PALETTE[7],
    "#882255",
    "#44AA99",
    "#117733",
    "#332288",
    "#AA4499",
    "#DDCC77",
    "#88CCEE",
    "#661100",
)
"""Colours for other names: the rest of the palette, then Tol's muted scheme."""


def mineral_colours(names: Sequence[str]) -> list[str]:
    """Return the colour of each mineral, in the order of ``names``.

    Known minerals keep their fixed colour; other names take unused colours in
    alphabetical order of the names, cycling when there are many.

    Examples
    --------
    >>> mineral_colours(["glass", "pyroxene"])
    ['#009E73', '#E69F00']
    >>> mineral_colours(["pyroxene", "glass"])
    ['#E69F00', '#009E73']
    >>> mineral_colours(["b", "a"]) == mineral_colours(["a", "b"])[::-1]
    True
    """
    fixed = {n: MINERAL_COLOURS[n.lower()] for n in names if n.lower() in MINERAL_COLOURS}
    used = set(fixed.values())
    spare = [c for c in (*_EXTRA, *PALETTE) if c not in used] or list(PALETTE)
    others = sorted({n for n in names if n not in fixed})
    chosen = {n: spare[k % len(spare)] for k, n in enumerate(others)}
    return [fixed.get(n) or chosen[n] for n in names]
