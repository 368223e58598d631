"""The Inertial Sense ISB packet codec (protocol 2.1) and typed decoders of
the data sets the emulated IMX-5 serves.

A packet is ``EF 49 | flags | did | size (u16 LE) | payload | a b`` where
``a, b`` is a Fletcher-style 8-bit sum over every byte before it
(``a += x; b += a``). The packet type is the low nibble of ``flags``; flag
0x20 means the payload starts with a ``u16`` offset into the data set.

Field names, offsets and units are those of the SDK's ``data_sets.h``
(protocol 2.1), from ``isb_layouts`` (generated from
``imu-emu isb-layouts --json``), and the columns those of
``imu-emu client --protocol isb decode --to json`` (``python/tests`` checks
the two agree).
"""

import struct
from dataclasses import dataclass
from typing import Dict, List, Optional, Sequence, Tuple, Union

PREAMBLE = b"\xEF\x49"
ACK, NACK, GET_DATA, DATA, SET_DATA = 1, 2, 3, 4, 5
STOP_BROADCASTS_ALL_PORTS, STOP_DID_BROADCAST, STOP_BROADCASTS_CURRENT_PORT = 6, 7, 8
FLAG_OFFSET = 0x20
MAX_PACKET = 2048

# The DIDs served (``DEV_INFO``, ``IMU``, ...) and their layouts: generated
# from the program's own declarations (``scripts/isb-layouts.py``).
from .isb_layouts import *  # noqa: F401,F403
from .isb_layouts import LAYOUTS

# Field kinds: struct format and item count.
_KINDS = {
    "u8": ("B", 1),
    "u16": ("H", 1),
    "u32": ("I", 1),
    "u64": ("Q", 1),
    "f32": ("f", 1),
    "f64": ("d", 1),
    "f32x3": ("3f", 3),
    "f32x4": ("4f", 4),
    "f64x3": ("3d", 3),
    "ver": ("4B", 4),
    "str24": ("24s", 1),
}

Field = Tuple[str, int, str]

#: Data sets served: DID -> (name, size, fields as (name, offset, kind)).
SETS: Dict[int, Tuple[str, int, Sequence[Field]]] = {
    did: (name, size, tuple((f, off, kind) for f, off, kind, _ in fields))
    for did, (name, _, size, fields) in LAYOUTS.items()
}

Value = Union[int, float, str]


def checksum(data: bytes) -> bytes:
    """The two checksum bytes of ``data`` (preamble through payload)."""
    a = b = 0
    for x in data:
        a = (a + x) & 0xFF
        b = (b + a) & 0xFF
    return bytes((a, b))


def encode(flags: int, did: int, payload: bytes) -> bytes:
    """One packet."""
    head = PREAMBLE + bytes((flags, did)) + struct.pack("<H", len(payload)) + payload
    return head + checksum(head)


def get_data(did: int, period: int = 0, size: int = 0, offset: int = 0) -> bytes:
    """GET_DATA of set ``did``: once (``period`` 0, which also stops its
    stream) or every ``period`` source periods."""
    return encode(GET_DATA, 0, struct.pack("<4H", did, size, offset, period))


def set_data(did: int, offset: int, data: bytes) -> bytes:
    """SET_DATA of ``data`` at ``offset`` of set ``did``."""
    return encode(SET_DATA | FLAG_OFFSET, did, struct.pack("<H", offset) + data)


def stop_all() -> bytes:
    """STOP_BROADCASTS_ALL_PORTS (ACKed)."""
    return encode(STOP_BROADCASTS_ALL_PORTS, 0, b"")


@dataclass
class Packet:
    """A checked packet."""

    flags: int
    did: int
    payload: bytes

    @property
    def kind(self) -> int:
        """The packet type (low nibble of ``flags``)."""
        return self.flags & 0x0F

    @property
    def ident(self) -> int:
        """The DID of a DATA packet, else ``-kind`` (so that
        :meth:`imu_emu.Uart.frame` waits for data sets by DID)."""
        return self.did if self.kind == DATA else -self.kind

    @property
    def raw(self) -> bytes:
        """The packet's bytes."""
        return encode(self.flags, self.did, self.payload)

    def whole_set(self) -> Optional[bytes]:
        """The data set's bytes if this is a DATA packet of a whole set."""
        if self.kind == DATA and not self.flags & FLAG_OFFSET:
            return self.payload
        return None


class PacketReader:
    """Splits a byte stream, fed in any chunking, into checked packets;
    a bad checksum or size is dropped one byte at a time (``bad``)."""

    def __init__(self) -> None:
        self.buf = bytearray()
        self.bad = 0
        self.skipped = 0

    def feed(self, data: bytes) -> List[Packet]:
        """Adds bytes; returns the packets they complete."""
        self.buf += data
        out: List[Packet] = []
        while True:
            i = self.buf.find(PREAMBLE)
            if i < 0:
                keep = 1 if self.buf[-1:] == b"\xEF" else 0
                self.skipped += len(self.buf) - keep
                del self.buf[: len(self.buf) - keep]
                return out
            self.skipped += i
            del self.buf[:i]
            if len(self.buf) < 6:
                return out
            (size,) = struct.unpack_from("<H", self.buf, 4)
            total = size + 8
            if total > MAX_PACKET:
                self.bad += 1
                del self.buf[:1]
                continue
            if len(self.buf) < total:
                return out
            if checksum(self.buf[: total - 2]) != bytes(self.buf[total - 2 : total]):
                self.bad += 1
                del self.buf[:1]
                continue
            out.append(Packet(self.buf[2], self.buf[3], bytes(self.buf[6 : total - 2])))
            del self.buf[:total]


def _read(kind: str, b: bytes, off: int) -> List[Value]:
    fmt, n = _KINDS[kind]
    vals = struct.unpack_from("<" + fmt, b, off)
    if kind == "ver":
        return [".".join(str(v) for v in vals)]
    if kind == "str24":
        text = vals[0].split(b"\0", 1)[0]
        return ["".join(chr(c) if 0x20 <= c < 0x7F else "?" for c in text)]
    if kind in ("f32", "f32x3", "f32x4"):
        # Shortest text that reads back as the same f32, as the Rust client prints.
        return [float(_f32_repr(v)) for v in vals]
    return list(vals)


def _f32_repr(x: float) -> str:
    for digits in range(1, 10):
        s = "%.*g" % (digits, x)
        if struct.unpack("<f", struct.pack("<f", float(s)))[0] == struct.unpack("<f", struct.pack("<f", x))[0]:
            return s
    return repr(x)


def columns(did: int) -> List[str]:
    """The column names of set ``did`` (vectors as ``name_x`` ...)."""
    _, _, fields = SETS[did]
    out: List[str] = []
    for name, _, kind in fields:
        if kind in ("f32x3", "f64x3"):
            out += [name + "_x", name + "_y", name + "_z"]
        elif kind == "f32x4":
            out += [name + "_w", name + "_x", name + "_y", name + "_z"]
        else:
            out.append(name)
    return out


def decode_set(did: int, data: bytes) -> Dict[str, Value]:
    """A whole data set's bytes as ``{column: value}`` (units of
    ``data_sets.h``: s, rad/s, m/s^2, rad, m/s, ms, deg C). Raises
    :class:`ValueError` for a DID not served or a wrong size."""
    if did not in SETS:
        raise ValueError("data set %d is not one the emulated IMX-5 serves" % did)
    name, size, fields = SETS[did]
    if len(data) != size:
        raise ValueError("%s is %d bytes, got %d" % (name, size, len(data)))
    values: List[Value] = []
    for _, off, kind in fields:
        values += _read(kind, data, off)
    return dict(zip(columns(did), values))


#: Names of the field that carries a set's device time (as the binary's
#: decoder reads it): s since boot, GPS s of the week, or GPS ms of the week.
TIME_FIELDS = ("time", "timeOfWeek", "timeOfWeekMs")


def device_time(did: int, data: bytes) -> Optional[float]:
    """The device time a set carries, s: its first field named in
    :data:`TIME_FIELDS` (``time`` since boot of the IMU, PIMU,
    magnetometer, barometer and sensor sets; the GPS time of week of
    INS_1..4, INL2_*, GPS1_*; ``timeOfWeekMs`` / 1000 of STROBE_IN_TIME and
    SYS_PARAMS); ``None`` for a set with none."""
    if did not in LAYOUTS:
        return None
    for name, off, kind, unit in LAYOUTS[did][3]:
        if name in TIME_FIELDS:
            (value,) = struct.unpack_from("<d" if kind == "f64" else "<I", data, off)
            return value / 1000.0 if unit == "ms" else float(value)
    return None


def set_by_name(name: str) -> int:
    """A served set's DID by name (``IMU``, ``did_pimu``)."""
    bare = name.upper()
    if bare.startswith("DID_"):
        bare = bare[4:]
    for did, (n, _, _) in SETS.items():
        if n == bare:
            return did
    raise KeyError(name)
