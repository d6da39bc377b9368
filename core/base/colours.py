"""Colours of the minerals, chosen by name so that a mineral keeps its colour in every scene.

The palette is Okabe and Ito's, which stays distinguishable with the common
forms of colour blindness. The Chang'e-5 minerals have fixed colours (names
compared in lower case). Any other name takes a colour picked by a hash of
the name among the colours that no Chang'e-5 mineral has, so it too keeps
its colour from scene to scene, except when two phases of one packing would
share a colour: then, in alphabetical order of the names, the later one
moves to the next free colour. The colours of a
packing depend on the set of its names, never on the order of its phases,
and are distinct as long as there are at most 16 phases.
"""

from __future__ import annotations

import zlib
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

    Known minerals keep their fixed colour; other names take the colour of a
    hash of the name, moved on to the next free one when taken (see the
    module's description).

    Examples
    --------
    >>> mineral_colours(["glass", "pyroxene"])
    ['#009E73', '#E69F00']
    >>> mineral_colours(["pyroxene", "glass"])
    ['#E69F00', '#009E73']
    >>> mineral_colours(["b", "a"]) == mineral_colours(["a", "b"])[::-1]
    True
    """
    reserved = set(MINERAL_COLOURS.values())
    wheel = [c for c in dict.fromkeys((*_EXTRA, *PALETTE)) if c not in reserved]
    wheel += [c for c in PALETTE if c in reserved]  # reached only when the others are taken
    free = len(wheel) - len(reserved)
    chosen: dict[str, str] = {}
    used: set[str] = set()
    unique = sorted(set(names))
    known = [n for n in unique if n.lower() in MINERAL_COLOURS]
    for name in known:  # fixed colours first, so that an unknown name never takes one
        colour = MINERAL_COLOURS[name.lower()]
        if colour not in used:
            chosen[name] = colour
            used.add(colour)
    for name in unique:
        if name in chosen:
            continue
        start = zlib.crc32(name.encode("utf-8")) % free
        for step in range(len(wheel)):
            colour = wheel[(start + step) % len(wheel)]
            if colour not in used:
                break
        else:  # more phases than colours: share, still by name
            colour = wheel[start]
        chosen[name] = colour
        used.add(colour)
    return [chosen[n] for n in names]
