"""The KERNEL frame codec (Inertial Labs KERNEL ICD, Table 5.2).

A frame is ``AA 55 | type | id | len (u16 LE) | payload | sum (u16 LE)``
where ``len = len(payload) + 6`` and ``sum`` is the 16-bit wrapping sum of
every byte from ``type`` through the last payload byte. Commands are
``type 0, id 0`` with the command in the payload; everything the device
sends is ``type 1`` with the format or command code as ``id``.
"""

import struct
from dataclasses import dataclass

HEADER = b"\xAA\x55"
TYPE_COMMAND = 0x00
TYPE_DATA = 0x01

#: Data command codes (ICD Table 5.16) by format name.
FORMATS = {
    "Orientation": 0x33,
    "GA": 0x8F,
    "GAm": 0x9B,
    "GAA": 0xA5,
    "GAAm": 0xA6,
    "Quaternion": 0x82,
    "Calibrated HR": 0x81,
    "UDD": 0x95,
}

#: Payload bytes of each fixed format (Tables 5.5-5.12), for Formula 5.1.
PAYLOAD_LEN = {
    "Orientation": 34,
    "GA": 32,
    "GAm": 32,
    "GAA": 44,
    "GAAm": 44,
    "Quaternion": 34,
    "Calibrated HR": 52,
}

#: Line rate (bit/s) of each Baud_Rate code (Table 5.24).
BAUD_RATES = (
    115_200, 4_800, 9_600, 14_400, 19_200, 38_400, 57_600, 115_200, 230_400, 460_800,
    921_600, 2_000_000, 375_000, 1_843_200, 3_686_400, 1_000_000, 4_000_000,
)

#: Parameter IDs (Table 5.24) the helper reads and writes.
DATA_RATE = 0x0012
BAUD_RATE = 0x03B2

STOP = 0xFE
GET_DEV_INFO = 0x12
GET_BIT = 0x1A
COMMIT_BAUD_RATE = 0xC2
SAVE_FLASH = 0xB2
READ_RAM = 0xB1

#: Largest frame accepted by :class:`FrameReader` (resynchronises beyond).
MAX_FRAME = 4096


def checksum(data):
    """The 16-bit wrapping sum of ``data`` (Table 5.2 "Checksum")."""
    return sum(data) & 0xFFFF


def encode(msg_type, ident, payload):
    """A whole frame with ``payload``."""
    payload = bytes(payload)
    body = bytes([msg_type, ident]) + struct.pack("<H", len(payload) + 6) + payload
    return HEADER + body + struct.pack("<H", checksum(body))


def command(payload):
    """A command frame (type 0, id 0)."""
    if isinstance(payload, int):
        payload = bytes([payload])
    return encode(TYPE_COMMAND, 0, payload)


def start(fmt):
    """The data command that starts format ``fmt`` (a name or a code)."""
    code = FORMATS[fmt] if isinstance(fmt, str) else int(fmt)
    return command(code)


def stop():
    """Stop (ICD 5.3.2)."""
    return command(STOP)


def get_dev_info():
    """GetDevInfo (5.3.3)."""
    return command(GET_DEV_INFO)


def get_bit():
    """GetBIT (5.3.4)."""
    return command(GET_BIT)


def commit_baud_rate():
    """CommitBaudRate (5.3.9)."""
    return command(COMMIT_BAUD_RATE)


def save_flash(param_id, value):
    """SaveFlash of ``value`` (bytes) to parameter ``param_id`` (5.3.7)."""
    value = bytes(value)
    return command(b"\xB2\xFF" + struct.pack("<HH", param_id, len(value)) + value)


def read_ram(param_id, length):
    """ReadRAM of ``length`` bytes of parameter ``param_id`` (5.3.8)."""
    return command(b"\xB1\xFF" + struct.pack("<HH", param_id, length))


def max_rate(baud, payload_len, internal_hz=2000):
    """Formula 5.1 (ICD 5.5): the highest output rate, a divisor of
    ``internal_hz``, with ``rate * 11 * (payload_len + 8) <= baud``; never
    below 1 Hz. The same rule as the emulator's ``kernel::rate``."""
    limit = baud // (11 * (payload_len + 8))
    for k in range(1, internal_hz + 1):
        if internal_hz % k == 0 and internal_hz // k <= limit:
            return internal_hz // k
    return 1


def effective_rate(data_rate, baud, fmt="GA", internal_hz=2000):
    """The rate a stream of ``fmt`` (a name of :data:`PAYLOAD_LEN`, or a
    payload length in bytes) actually runs at: Data_Rate lowered to
    :func:`max_rate` when its frames do not fit the line (ICD 5.5)."""
    n = PAYLOAD_LEN[fmt] if isinstance(fmt, str) else int(fmt)
    return min(max(data_rate, 1), internal_hz, max_rate(baud, n, internal_hz))


class RateLoweredWarning(UserWarning):
    """A Data_Rate the device lowers (Formula 5.1): the message names the
    requested and the effective rate."""


@dataclass
class Frame:
    """A checked frame."""

    msg_type: int
    ident: int
    payload: bytes

    @property
    def raw(self):
        """The frame's bytes."""
        return encode(self.msg_type, self.ident, self.payload)


class FrameReader:
    """Splits a byte stream, fed in any chunking, into checked frames.

    A candidate with a bad length or checksum is dropped one byte at a time
    (``bad`` counts them), so the next good frame is found.
    """

    def __init__(self):
        self.buf = bytearray()
        self.bad = 0
        self.skipped = 0

    def feed(self, data):
        """Adds bytes; returns the complete frames they finish."""
        self.buf += data
        out = []
        while True:
            i = self.buf.find(HEADER)
            if i < 0:
                keep = 1 if self.buf[-1:] == b"\xAA" else 0
                self.skipped += len(self.buf) - keep
                del self.buf[: len(self.buf) - keep]
                return out
            self.skipped += i
            del self.buf[:i]
            if len(self.buf) < 6:
                return out
            (length,) = struct.unpack_from("<H", self.buf, 4)
            total = length + 2
            if length < 6 or total > MAX_FRAME:
                self.bad += 1
                del self.buf[:1]
                continue
            if len(self.buf) < total:
                return out
            (want,) = struct.unpack_from("<H", self.buf, total - 2)
            if checksum(self.buf[2 : total - 2]) != want:
                self.bad += 1
                del self.buf[:1]
                continue
            out.append(Frame(self.buf[2], self.buf[3], bytes(self.buf[6 : total - 2])))
            del self.buf[:total]


def decode_ga(payload):
    """A GA payload (Table 5.7) as a dict: deg/s, g, counter, USW, deg C.

    Raises :class:`ValueError` for a payload that is not 32 bytes: the
    2-byte payload of a frame with GA's ident is the acknowledgement of the
    GA command (the command's checksum, ICD 5.3.1), not data."""
    if len(payload) != PAYLOAD_LEN["GA"]:
        if len(payload) == 2:
            raise ValueError(
                "a 2-byte payload is the acknowledgement of the GA command (ICD 5.3.1: "
                "its checksum), not a GA frame (32 bytes)"
            )
        raise ValueError("a GA payload is 32 bytes, not %d" % len(payload))
    gx, gy, gz, ax, ay, az, counter, usw, _res, temp = struct.unpack("<6iHHhh", payload)
    return {
        "gyro": (gx / 1e5, gy / 1e5, gz / 1e5),
        "acc": (ax / 1e6, ay / 1e6, az / 1e6),
        "counter": counter,
        "usw": usw,
        "temp_c": temp / 10.0,
    }
