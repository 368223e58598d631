"""The live motion feed (``imu-emu --motion-feed``): encode samples and
drive an emulator from a simulation, in real time or in lockstep.

A sample is what a perfect IMU on the simulated vehicle measures at a
time: body angular rate (deg/s), specific force (g; at rest +1 g along
up) and optionally the sensor temperature (deg C). ``docs/feed.md`` has
the protocol; :func:`encode_sample` writes the binary form (41 or 45
bytes, CRC-16/CCITT-FALSE), :func:`text_row` the text form.

:class:`FeedEmulator` is an :class:`~imu_emu.Emulator` with a feed:
:meth:`FeedEmulator.feed` sends a sample; with ``lockstep=True`` device
time advances only to each sample's time, so :meth:`FeedEmulator.step`
(send a sample, then wait for the GA frames up to a time) closes a loop
deterministically: one feed and one seed give the same bytes.
"""

import socket
import struct
import time

from .emulator import Emulator

SYNC = b"\xF5\xED"
VERSION = 1
KIND_RATES = 1
KIND_RATES_TEMP = 2
#: Device index meaning "the device this feed belongs to".
OWN_DEVICE = 0xFFFF


def crc16(data):
    """CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF): the feed's checksum."""
    crc = 0xFFFF
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else (crc << 1)
            crc &= 0xFFFF
    return crc


def encode_sample(time_s, rate_dps, force_g, temp_c=None, device=OWN_DEVICE):
    """A binary sample (docs/feed.md): time in s (sent as integer ns)."""
    kind = KIND_RATES if temp_c is None else KIND_RATES_TEMP
    values = list(rate_dps) + list(force_g) + ([] if temp_c is None else [temp_c])
    body = struct.pack("<HQ", device, int(round(time_s * 1e9))) + struct.pack(
        "<%df" % len(values), *values
    )
    head = bytes([VERSION, kind, len(body)])
    return SYNC + head + body + struct.pack("<H", crc16(head + body))


def text_row(time_s, rate_dps, force_g, temp_c=None):
    """A text sample: ``time_s, wx, wy, wz, fx, fy, fz[, temp_c]\\n``."""
    values = [time_s] + list(rate_dps) + list(force_g) + ([] if temp_c is None else [temp_c])
    return (",".join(repr(float(v)) for v in values) + "\n").encode()


class Feed:
    """A connection to a feed address (``tcp 127.0.0.1:9000`` or
    ``udp 127.0.0.1:9000``, as the emulator's ``feed on`` line says)."""

    def __init__(self, place, timeout=5.0):
        kind, addr = place.split(" ", 1)
        host, port = addr.rsplit(":", 1)
        self.addr = (host, int(port))
        self.udp = kind == "udp"
        if self.udp:
            self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        else:
            self.sock = socket.create_connection(self.addr, timeout=timeout)
            self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def send_bytes(self, data):
        """Sends raw bytes (a datagram over UDP)."""
        if self.udp:
            self.sock.sendto(data, self.addr)
        else:
            self.sock.sendall(data)

    def send(self, time_s, rate_dps, force_g=(0.0, 0.0, 1.0), temp_c=None,
             device=OWN_DEVICE, text=False):
        """Sends one sample, binary (default) or as a text row."""
        if text:
            self.send_bytes(text_row(time_s, rate_dps, force_g, temp_c))
        else:
            self.send_bytes(encode_sample(time_s, rate_dps, force_g, temp_c, device))

    def close(self):
        """Closes the connection."""
        self.sock.close()


class FeedEmulator(Emulator):
    """An emulator whose motion comes from :meth:`feed`.

    ``lockstep=True`` adds ``--lockstep --speed max``: device time moves
    only with the samples, as fast as they come. ``feed_addr`` is
    ``127.0.0.1:0`` (TCP) or ``udp:127.0.0.1:0``.
    """

    def __init__(self, args=(), lockstep=False, feed_addr="127.0.0.1:0", binary=None,
                 timeout=5.0):
        self._feed = None
        #: Every UART byte :meth:`wait_frames` received, in order.
        self.received = bytearray()
        extra = ["--motion-feed", feed_addr]
        if lockstep:
            extra += ["--lockstep", "--speed", "max"]
        Emulator.__init__(self, list(args) + extra, binary, timeout)
        self.feed_place = self._line("feed on ")

    def feeder(self):
        """The :class:`Feed` connection (opened on first use)."""
        if self._feed is None:
            self._feed = Feed(self.feed_place, self.timeout)
        return self._feed

    def feed(self, time_s, rate_dps, force_g=(0.0, 0.0, 1.0), temp_c=None, text=False):
        """Sends one sample (see :meth:`Feed.send`)."""
        self.feeder().send(time_s, rate_dps, force_g, temp_c, text=text)

    def command_at_start(self, frame):
        """Lockstep: sends a command and waits until the device took it,
        so that it applies at device time 0 (before any sample)."""
        ctl = self.control()
        before = None
        end = time.monotonic() + self.timeout
        while before is None:
            s = ctl.status()
            if s.get("mode") != "off":
                before = int(s["commands"])
            elif time.monotonic() > end:
                raise TimeoutError("the device did not power on")
            else:
                self.uart()
                time.sleep(0.005)
        self.send(frame)
        while int(ctl.status()["commands"]) <= before:
            if time.monotonic() > end:
                raise TimeoutError("the command was not taken")
            time.sleep(0.005)

    def step(self, time_s, rate_dps, force_g=(0.0, 0.0, 1.0), until=None, timeout=None):
        """Lockstep: sends a sample at ``time_s``, then returns the frames
        that arrive until ``until(frames)`` is true (see
        :meth:`wait_frames`; without ``until`` none are waited for)."""
        self.feed(time_s, rate_dps, force_g)
        return [] if until is None else self.wait_frames(until, timeout)

    def wait_frames(self, until, timeout=None):
        """The frames that arrive until ``until(frames)`` (the frames so
        far) is true; every byte is also kept in :attr:`received`."""
        got = []
        end = time.monotonic() + (timeout or self.timeout)
        s = self.uart()
        while not until(got):
            left = end - time.monotonic()
            if left <= 0:
                raise TimeoutError("lockstep: the frames waited for did not come")
            s.settimeout(min(left, 0.05))
            try:
                data = s.recv(65536)
            except socket.timeout:
                continue
            if not data:
                raise ConnectionError("the UART closed")
            self.received.extend(data)
            got += self.reader.feed(data)
        return got

    def _close_uarts(self):
        if self._feed is not None:
            self._feed.close()
            self._feed = None
        Emulator._close_uarts(self)
