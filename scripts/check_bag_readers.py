"""Decode every message of a run's ROS 2 bag with the ``mcap`` library's ROS 2 decoder and
compare the per-topic counts with what ``rosbags`` (the writer's library) reads.

Exit status 0 when every message decodes and the counts agree, 1 otherwise, 2 on bad input.
Needs the ``test`` and ``rosbag`` extras (``mcap``, ``mcap-ros2-support``, ``rosbags``).

Example: ``auvsim run cssn_lawnmower --set duration_s=60 --rosbag --no-rerun --out runs/bag`` then
``python scripts/check_bag_readers.py runs/bag/rosbag``
"""

from __future__ import annotations

from pathlib import Path
import sys
import time

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sim.cli.app import run_script, script_parser  # noqa: E402
from sim.cli.errors import CliError  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    p = script_parser("check_bag_readers.py", __doc__.splitlines()[0])
    p.add_argument("bag", type=Path, help="the rosbag2 folder of a run (OUT/rosbag)")
    return run_script(p, check, argv)


def check(args) -> int:
    bag = args.bag
    if not bag.exists():
        raise CliError(f"bag {bag}: no such file or folder")
    if bag.is_file() and bag.suffix == ".mcap":
        bag = bag.parent  # the .mcap file itself: its rosbag2 folder
    if bag.is_dir() and (bag / "rosbag").is_dir() and not list(bag.glob("*.mcap")):
        raise CliError(f"bag {bag}: a run folder; give its bag folder, {bag / 'rosbag'}")
    files = sorted(bag.glob("*.mcap")) if bag.is_dir() else []
    if len(files) != 1:
        raise CliError(f"bag {bag}: expected a rosbag2 folder holding one .mcap file, found {len(files)}")
    try:
        from mcap.reader import make_reader
        from mcap_ros2.decoder import DecoderFactory
        from rosbags.rosbag2 import Reader
    except ImportError as exc:
        raise CliError(f"needs mcap, mcap-ros2-support and rosbags (pip install 'auvsim[test,rosbag]'): {exc}") from None
    t0 = time.process_time()
    by_mcap: dict[str, int] = {}
    try:
        with open(files[0], "rb") as f:
            reader = make_reader(f, decoder_factories=[DecoderFactory()])
            for _, channel, _, _ in reader.iter_decoded_messages(log_time_order=False):
                by_mcap[channel.topic] = by_mcap.get(channel.topic, 0) + 1
    except Exception as exc:  # a truncated or foreign file: the reader's own error, in one line
        raise CliError(f"bag {files[0]}: not a readable MCAP file ({type(exc).__name__}: {exc})"[:300]) from None
    mcap_cpu = time.process_time() - t0
    by_rosbags: dict[str, int] = {}
    try:
        with Reader(bag) as reader:
            for connection, _, _ in reader.messages():
                by_rosbags[connection.topic] = by_rosbags.get(connection.topic, 0) + 1
    except Exception as exc:
        raise CliError(f"bag {bag}: rosbags cannot read it ({type(exc).__name__}: {exc})"[:300]) from None
    topics = sorted(set(by_mcap) | set(by_rosbags))
    print(f"{'topic':40s} {'mcap (decoded)':>15s} {'rosbags':>10s}")
    for t in topics:
        print(f"{t:40s} {by_mcap.get(t, 0):15d} {by_rosbags.get(t, 0):10d}")
    same = by_mcap == by_rosbags
    print(f"{sum(by_mcap.values())} messages on {len(by_mcap)} topics decoded with mcap's ROS 2 decoder in "
          f"{mcap_cpu:.1f} CPU s; counts {'equal' if same else 'DIFFER'} to rosbags'")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
