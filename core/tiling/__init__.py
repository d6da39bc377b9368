"""One packing built in tiles: a schedule of independent tasks, the same packing on any workers."""

from regopack.tiling.layout import Tile, TileLayout, tile_layout

__all__ = ["Tile", "TileLayout", "tile_layout"]
