"""ROS 2 bags of ``grid_map_msgs/GridMap``: a recorded elevation map read, a scored map written.

Read and written with the ``rosbags`` library (no ROS installation needed), in
either storage of ROS 2 bags: SQLite 3 (``.db3``) and MCAP (``.mcap``). A bag is
a bag folder (``metadata.yaml`` and its storage files) or a single storage file.
The cells' conventions are grid_map's (:mod:`footfall.terrain.grid_map`).

Reading picks one message: the topic (needed only where the bag holds grid maps on
more than one), the layer (default ``elevation``) and the message (default the
last one on the topic; or its index, negative from the end; or the last at or
before a time since the bag's start). Its resolution, position, frame and
circular-buffer start are read from the message; NaN cells stay holes.
"""

from __future__ import annotations

import hashlib
import math
import os
import shutil
import sqlite3
import struct
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import apsw  # rosbags' SQLite 3 storage reads through it: its errors are a damaged bag's
import numpy as np
from rosbags.rosbag2 import Reader, ReaderError, StoragePlugin, Writer
from rosbags.serde import SerdeError
from rosbags.typesys import Stores, TypesysError, get_types_from_msg, get_typestore
from rosbags.typesys.stores.ros2_humble import builtin_interfaces__msg__Time as Time
from rosbags.typesys.stores.ros2_humble import geometry_msgs__msg__Point as Point
from rosbags.typesys.stores.ros2_humble import geometry_msgs__msg__Pose as Pose
from rosbags.typesys.stores.ros2_humble import geometry_msgs__msg__Quaternion as Quaternion
from rosbags.typesys.stores.ros2_humble import std_msgs__msg__Float32MultiArray as F32Array
from rosbags.typesys.stores.ros2_humble import std_msgs__msg__Header as Header
from rosbags.typesys.stores.ros2_humble import std_msgs__msg__MultiArrayDimension as Dim
from rosbags.typesys.stores.ros2_humble import std_msgs__msg__MultiArrayLayout as Layout

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.limits import current_limits
from footfall.terrain.grid_map import (
    DEFAULT_LAYER,
    GRID_MAP_INFO_MSG,
    GRID_MAP_INFO_TYPE,
    GRID_MAP_MSG,
    GRID_MAP_TYPE,
    GridGeometry,
    check_lengths,
    check_orientation,
    heights_of,
    layer_matrix,
    layer_of,
)
from footfall.terrain.raster import file_sha256

BAG_SUFFIXES = (".mcap", ".db3")  # a bag's single storage file; a bag folder has no suffix
NS = 1_000_000_000  # nanoseconds a second


@dataclass(frozen=True)
class BagChoice:
    """Which map of a bag to read (``None``: the default)."""

    topic: str | None = None  # the GridMap topic; needed where there are several
    layer: str = DEFAULT_LAYER
    message: int | None = None  # the message's index on the topic; negative from the end
    time: float | None = None  # [s] since the bag's start: the last message at or before it


def grid_map_typestore() -> Any:
    """A ``rosbags`` type store of ROS 2 Humble's messages with grid_map_msgs registered."""
    store = get_typestore(Stores.ROS2_HUMBLE)
    types = {}
    types.update(get_types_from_msg(GRID_MAP_INFO_MSG, GRID_MAP_INFO_TYPE))
    types.update(get_types_from_msg(GRID_MAP_MSG, GRID_MAP_TYPE))
    store.register(types)
    return store


# What a damaged bag raises inside rosbags and its storage libraries.
_READ_ERRORS = (ReaderError, SerdeError, TypesysError, apsw.Error, OSError, ValueError, KeyError,
                IndexError, TypeError, AttributeError, AssertionError, EOFError, struct.error,
                sqlite3.Error, UnicodeError, OverflowError, MemoryError, RuntimeError)


def check_bag_path(path: Path) -> None:
    """Refuse a bag path that is neither a bag folder nor a bag's storage file, or is too big."""
    if not path.exists():
        raise FootfallError(f"no such file or bag folder: {path}")
    if path.is_dir():
        if not (path / "metadata.yaml").is_file():
            raise FootfallError(f"{path}: a folder, but not a ROS 2 bag (no metadata.yaml)")
        files = [f for f in path.iterdir() if f.is_file()]
    else:
        files = [path]
    limit = current_limits().max_file_bytes
    size = sum(f.stat().st_size for f in files)
    if size > limit:
        raise FootfallError(f"{path}: the bag is {size} bytes, above the limit of {limit} "
                            f"(raise it with --limit max_file_bytes=N)")


def _bag_digest(path: Path) -> str:
    """SHA-256 of a bag's storage file, or of a bag folder's files' digests in name order."""
    if not path.is_dir():
        return file_sha256(path)
    digest = hashlib.sha256()
    for f in sorted(f for f in path.iterdir() if f.is_file()):
        digest.update(f"{f.name}:{file_sha256(f)};".encode())
    return digest.hexdigest()


def read_grid_map(path: str | os.PathLike, choice: BagChoice = BagChoice()
                  ) -> tuple[HeightMap, dict]:
    """One layer of one ``GridMap`` message of a ROS 2 bag as a height map.

    Returns the map (heights [m] of the layer, NaN where it has no data; the
    message's resolution, frame and position) and what was read (topic, layer,
    message index and count, time [s] since the bag's start, the layers there were).

    Raises
    ------
    FootfallError
        In one line naming the bag: not a bag, damaged or truncated, no GridMap topic,
        several and none chosen, a topic that is not a GridMap's, a missing layer
        (the layers listed), a message index or time outside the bag, a rotated map,
        lengths that disagree with the cells, or a map above the ``max_map_cells`` limit.
    """
    p = Path(path)
    check_bag_path(p)
    try:
        msg, info = _pick_message(p, choice)
    except FootfallError as exc:
        raise FootfallError(f"{p}: {exc}") from None
    except _READ_ERRORS as exc:
        raise FootfallError(f"{p}: not a readable ROS 2 bag, or a damaged one "
                            f"({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''})"
                            ) from None
    try:
        return _message_map(msg, choice.layer, p, info), info
    except FootfallError as exc:
        raise FootfallError(f"{p}: {exc}") from None


def _pick_message(p: Path, choice: BagChoice) -> tuple[Any, dict]:
    store = grid_map_typestore()
    with Reader(p) as reader:
        grid_topics = sorted({c.topic for c in reader.connections if c.msgtype == GRID_MAP_TYPE})
        if choice.topic is None:
            if not grid_topics:
                others = sorted({f"{c.topic} ({c.msgtype})" for c in reader.connections})
                raise FootfallError(f"the bag holds no {GRID_MAP_TYPE} topic (it has: "
                                    f"{', '.join(others) or 'no topics'})")
            if len(grid_topics) > 1:
                raise FootfallError(f"the bag holds grid maps on {len(grid_topics)} topics; "
                                    f"choose one with --topic: {', '.join(grid_topics)}")
            topic = grid_topics[0]
        else:
            topic = choice.topic
            types = {c.msgtype for c in reader.connections if c.topic == topic}
            if not types:
                known = sorted({c.topic for c in reader.connections})
                raise FootfallError(f"the bag has no topic {topic!r} (it has: "
                                    f"{', '.join(known) or 'no topics'})")
            if GRID_MAP_TYPE not in types:
                raise FootfallError(f"topic {topic!r} carries {', '.join(sorted(types))}, not "
                                    f"{GRID_MAP_TYPE}")
        connections = [c for c in reader.connections if c.topic == topic]
        count = sum(c.msgcount for c in connections)
        start = reader.start_time
        stamps = ([t for _, t, _ in reader.messages(connections=connections)]
                  if choice.time is not None else None)
        index = _message_index(choice, count, stamps, start)
        for k, (conn, t, raw) in enumerate(reader.messages(connections=connections)):
            if k == index:
                msg = store.deserialize_cdr(raw, conn.msgtype)
                return msg, {"topic": topic, "message": k, "messages": count,
                             "time": (t - start) / NS, "stamp_ns": int(t)}
    raise FootfallError(f"topic {topic!r} holds {count} messages by the bag's index, but "
                        f"fewer could be read (message {index})")


def _message_index(choice: BagChoice, count: int, stamps: list | None, start: int) -> int:
    """The index of the chosen message among ``count`` (times ``stamps`` [ns])."""
    if count == 0:
        raise FootfallError("the topic holds no message")
    if choice.message is not None and choice.time is not None:
        raise FootfallError("choose the message by index or by time, not both")
    if choice.time is not None:
        at = [k for k, t in enumerate(stamps or []) if (t - start) / NS <= choice.time]
        if not at:
            raise FootfallError(f"no message at or before {choice.time:g} s after the bag's "
                                f"start (the first is at {((stamps or [start])[0] - start) / NS:g}"
                                " s)")
        return at[-1]
    if choice.message is None:
        return count - 1
    k = choice.message + count if choice.message < 0 else choice.message
    if not 0 <= k < count:
        raise FootfallError(f"message {choice.message} does not exist: the topic holds "
                            f"{count} (0 .. {count - 1}, or -1 .. -{count} from the end)")
    return k


def _message_map(msg: Any, layer: str, path: Path, info: dict) -> HeightMap:
    layers = list(msg.layers)
    if len(layers) != len(msg.data):
        raise FootfallError(f"the message names {len(layers)} layers but holds "
                            f"{len(msg.data)}")
    if layer not in layers:
        raise FootfallError(f"the map has no layer {layer!r} (it has: "
                            f"{', '.join(layers) or 'none'}); choose one with --layer")
    array = msg.data[layers.index(layer)]
    dims = array.layout.dim
    labels = tuple(d.label for d in dims)
    sizes = tuple(int(d.size) for d in dims)
    cells = math.prod(sizes) if sizes else 0
    limit = current_limits().max_map_cells
    if cells > limit:
        raise FootfallError(f"the layer has {cells} cells, above the limit of {limit} "
                            f"(raise it with --limit max_map_cells=N)")
    matrix = layer_matrix(np.asarray(array.data), labels, sizes, array.layout.data_offset)
    q = msg.info.pose.orientation
    check_orientation((q.x, q.y, q.z, q.w))
    resolution = float(msg.info.resolution)
    check_lengths(resolution, (float(msg.info.length_x), float(msg.info.length_y)),
                  matrix.shape)
    heights = heights_of(matrix, msg.outer_start_index, msg.inner_start_index)
    if np.isnan(heights).all():
        raise FootfallError(f"layer {layer!r} has no data (every cell is NaN)")
    geometry = GridGeometry(resolution, (float(msg.info.pose.position.x),
                                         float(msg.info.pose.position.y)),
                            msg.header.frame_id or "map")
    meta = {"source": str(path), "source_sha256": _bag_digest(path),
            "source_format": "ros2-bag", "importer": "footfall.terrain.bags",
            "topic": info["topic"], "layer": layer, "layers": layers,
            "message": info["message"], "messages": info["messages"],
            "time": info["time"], "map_centre": list(geometry.centre),
            "start_index": [int(msg.outer_start_index), int(msg.inner_start_index)]}
    return HeightMap(heights, resolution, geometry.origin(heights.shape), geometry.frame, meta)


# --------------------------------------------------------------------- writing
def grid_map_message(store: Any, layers: dict[str, np.ndarray], hmap: HeightMap,
                     stamp_ns: int = 0) -> Any:
    """A ``GridMap`` message of ``layers`` (name -> heights-shaped array) on ``hmap``'s grid."""
    GridMap = store.types[GRID_MAP_TYPE]
    GridMapInfo = store.types[GRID_MAP_INFO_TYPE]
    nx, ny = hmap.shape
    r = hmap.resolution
    x0, y0 = hmap.origin
    centre = Point(x=x0 - r / 2 + nx * r / 2, y=y0 - r / 2 + ny * r / 2, z=0.0)
    data = []
    for values in layers.values():
        flat, dims = layer_of(values)
        data.append(F32Array(
            layout=Layout(dim=[Dim(label=label, size=size, stride=stride)
                               for label, size, stride in dims], data_offset=0),
            data=flat))
    return GridMap(
        header=Header(stamp=Time(sec=int(stamp_ns // NS), nanosec=int(stamp_ns % NS)),
                      frame_id=hmap.frame),
        info=GridMapInfo(resolution=r, length_x=nx * r, length_y=ny * r,
                         pose=Pose(position=centre,
                                   orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0))),
        layers=list(layers), basic_layers=[], data=data, outer_start_index=0,
        inner_start_index=0)


def write_grid_map(path: str | os.PathLike, layers: dict[str, np.ndarray], hmap: HeightMap,
                   topic: str = "/footfall/grid_map", storage: str = "mcap") -> Path:
    """Write one ``GridMap`` message of ``layers`` as a ROS 2 bag file, atomically.

    ``path`` ends in ``.mcap`` (MCAP storage) or ``.db3`` (SQLite 3 storage); the
    single storage file is written, which ``ros2 bag`` and ``rosbags`` open as a bag.
    The bag is made in a temporary folder beside ``path`` and its file renamed into place.
    """
    target = Path(path)
    plugin = {"mcap": StoragePlugin.MCAP, "sqlite3": StoragePlugin.SQLITE3}[storage]
    store = grid_map_typestore()
    msg = grid_map_message(store, layers, hmap)
    folder = Path(tempfile.mkdtemp(prefix=f".{target.name}.{os.getpid()}.",
                                   dir=target.parent if str(target.parent) else "."))
    try:
        bag = folder / "bag"
        with Writer(bag, version=9, storage_plugin=plugin) as writer:
            conn = writer.add_connection(topic, GRID_MAP_TYPE, typestore=store)
            writer.write(conn, 0, store.serialize_cdr(msg, GRID_MAP_TYPE))
        (written,) = [f for f in bag.iterdir() if f.suffix in BAG_SUFFIXES]
        os.replace(written, target)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return target
