"""Terrain generation: LittleDog-like terrain modules and boards made of them."""

from footfall.terrain.file_modules import FileModule
from footfall.terrain.geometry import MODULE_CELLS, MODULE_RESOLUTION, MODULE_SIZE
from footfall.terrain.kinds import KINDS, register_kind, unregister_kind
from footfall.terrain.modules import make_board, make_module, parse_board_spec, parse_module_spec

__all__ = ["KINDS", "MODULE_CELLS", "MODULE_RESOLUTION", "MODULE_SIZE", "FileModule",
           "make_board", "make_module", "parse_board_spec", "parse_module_spec", "register_kind",
           "unregister_kind"]
