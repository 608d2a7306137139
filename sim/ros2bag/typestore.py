"""The rosbags type store used for the bag: ROS 2 Humble's standard messages plus the
``marine_acoustic_msgs`` and ``vision_msgs`` definitions kept as ``.msg`` text in
``sim/ros2bag/msg/`` (they are not part of rosbags' stores)."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

MSG_DIR = Path(__file__).with_name("msg")


def extra_msg_files() -> dict[str, Path]:
    """ROS type name (``pkg/msg/Name``) -> its ``.msg`` file, for every shipped definition."""
    return {f"{p.parent.parent.name}/msg/{p.stem}": p for p in sorted(MSG_DIR.glob("*/msg/*.msg"))}


@lru_cache(maxsize=1)
def make_typestore():
    """A ``rosbags.typesys.store.Typestore`` with ROS 2 Humble's types and the shipped extras.

    Raises:
        ImportError: rosbags is not installed (``pip install rosbags``).
    """
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    types: dict = {}
    for name, path in extra_msg_files().items():
        types.update(get_types_from_msg(path.read_text(), name))
    store.register(types)
    return store
