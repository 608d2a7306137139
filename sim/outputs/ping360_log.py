"""The scanning sonar's pings as Blue Robotics ping-protocol messages: a per-ping log a Ping360
user's tools read ([Ping360]).

Each ping of a sensor of kind ``msis`` becomes one ``PING360_DEVICE_DATA`` (id 2300) message,
packed with the ``bluerobotics-ping`` package (module ``brping``, its ``definitions``), and the
packets are written back to back into ``<sensor>.bin`` (the protocol frames itself: ``BR``
start bytes, payload length, message id, checksum; ``brping.PingParser`` reads the file byte
by byte). ``<sensor>.csv`` gives each packet's simulated time, byte offset and head angle, which
the protocol does not carry.

Fields: ``mode`` 1; ``gain_setting`` 0 (the simulated receiver's gain is ``gain_db`` of the
sensor config, not one of the device's three settings); ``angle`` the head angle in gradians,
rounded to the device's integer steps (0-399); ``transmit_duration`` (us), ``sample_period``
(25 ns ticks) and ``number_of_samples`` as the ping was made; ``transmit_frequency`` 750 kHz
(the Ping360's); ``data`` the ping's uint8 intensities.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from sim.events.records import MissionInfo, MissionSummary, ObserverBase

PING360_FREQUENCY_KHZ = 750  # the Ping360 transmits at 750 kHz ([Ping360])
GRAD_PER_TURN = 400


def device_data_packet(ping: Any) -> bytes:
    """One :class:`autonomy.messages.MsisPing` as a packed ``PING360_DEVICE_DATA`` message."""
    from brping import PingMessage, definitions

    data = bytes(ping.intensity.tobytes())
    msg = PingMessage(definitions.PING360_DEVICE_DATA)
    msg.mode = 1
    msg.gain_setting = 0
    msg.angle = int(round(float(ping.angle_grad))) % GRAD_PER_TURN
    msg.transmit_duration = int(round(float(ping.transmit_duration_us)))
    msg.sample_period = int(ping.sample_period_ticks)
    msg.transmit_frequency = PING360_FREQUENCY_KHZ
    msg.number_of_samples = len(data)
    msg.data_length = len(data)
    msg.data = bytearray(data)
    msg.pack_msg_data()
    return bytes(msg.msg_data)


class Ping360LogRecorder(ObserverBase):
    """Writes every scanning-sonar ping of a run into ``folder/<sensor>.bin`` (packets) and
    ``folder/<sensor>.csv`` (``index,t_s,offset_bytes,angle_grad``).

    Raises:
        ValueError: (at :meth:`on_start`) the mission has no sensor of kind ``msis``.
    """

    sonar_frames = False  # reads no forward-looking sonar frame
    sonar_truth = False

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)
        self._bin: dict[str, Any] = {}
        self._csv: dict[str, Any] = {}
        self._n: dict[str, int] = {}
        self._offset: dict[str, int] = {}

    def on_start(self, info: MissionInfo) -> None:
        names = [n for n, kind in info.sensors.items() if kind == "msis"]
        if not names:
            raise ValueError("ping360 log: the scenario has no sensor of kind msis (a scanning sonar)")
        from sim.sensors.msis import MsisRender  # the scenario has a scanning sonar: its module loads anyway

        self._render_type = MsisRender
        self.close()
        self.folder.mkdir(parents=True, exist_ok=True)
        for name in names:
            self._bin[name] = open(self.folder / f"{name}.bin", "wb")  # noqa: SIM115 (closed at on_end)
            self._csv[name] = open(self.folder / f"{name}.csv", "w")  # noqa: SIM115
            self._csv[name].write("index,t_s,offset_bytes,angle_grad\n")
            self._n[name] = self._offset[name] = 0

    def on_message(self, name: str, msg: Any) -> None:
        f = self._bin.get(name)
        if f is None or not isinstance(msg, self._render_type):
            return
        ping = msg.ping
        packet = device_data_packet(ping)
        f.write(packet)
        self._csv[name].write(f"{self._n[name]},{ping.t_s!r},{self._offset[name]},{float(ping.angle_grad)!r}\n")
        self._n[name] += 1
        self._offset[name] += len(packet)

    def on_end(self, summary: MissionSummary) -> None:
        self.close()

    def close(self) -> None:
        for f in (*self._bin.values(), *self._csv.values()):
            f.close()
        self._bin.clear()
        self._csv.clear()

    @property
    def counts(self) -> dict[str, int]:
        """Pings written per sensor."""
        return dict(self._n)
