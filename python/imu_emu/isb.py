"""The Inertial Sense ISB packet codec (protocol 2.1) and typed decoders of
the data sets the emulated IMX-5 serves.

A packet is ``EF 49 | flags | did | size (u16 LE) | payload | a b`` where
``a, b`` is a Fletcher-style 8-bit sum over every byte before it
(``a += x; b += a``). The packet type is the low nibble of ``flags``; flag
0x20 means the payload starts with a ``u16`` offset into the data set.

Field names, offsets and units are those of the SDK's ``data_sets.h``
(protocol 2.1) as the repository's ``docs/isb-data-sets.md`` lists them,
and the columns those of ``imu-emu client --protocol isb decode --to json``
(``python/tests`` checks the two agree).
"""

import struct
from dataclasses import dataclass
from typing import Dict, List, Optional, Sequence, Tuple, Union

PREAMBLE = b"\xEF\x49"
ACK, NACK, GET_DATA, DATA, SET_DATA = 1, 2, 3, 4, 5
STOP_BROADCASTS_ALL_PORTS, STOP_DID_BROADCAST, STOP_BROADCASTS_CURRENT_PORT = 6, 7, 8
FLAG_OFFSET = 0x20
MAX_PACKET = 2048

DEV_INFO, PIMU, SYS_CMD, RMC, SYS_PARAMS, FLASH_CONFIG = 1, 3, 7, 9, 10, 12
IMU, BIT, STROBE_IN_TIME, IMU_RAW = 58, 64, 68, 97
INS_1, INS_2, INS_3, INS_4, GPS1_POS, GPS1_VEL = 4, 5, 65, 66, 13, 30
MAGNETOMETER, BAROMETER, IMU_MAG, PIMU_MAG, SYS_SENSORS = 52, 53, 85, 86, 11
SYS_FAULT, GPS1_VERSION, MAG_CAL, GPS1_SIG, IMU3_RAW = 2, 17, 19, 45, 96
PORT_MONITOR = 75
RTOS_INFO, CAN_CONFIG = 38, 90

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

_IMU: Sequence[Field] = (("time", 0, "f64"), ("status", 8, "u32"), ("pqr", 12, "f32x3"), ("acc", 24, "f32x3"))
_PIMU: Sequence[Field] = (
    ("time", 0, "f64"), ("dt", 8, "f32"), ("status", 12, "u32"), ("theta", 16, "f32x3"), ("vel", 28, "f32x3"),
)
_INS_HEAD: Sequence[Field] = (("week", 0, "u32"), ("timeOfWeek", 4, "f64"), ("insStatus", 12, "u32"), ("hdwStatus", 16, "u32"))
_MAG_AT = lambda at: (("magTime", at, "f64"), ("mag", at + 8, "f32x3"))  # noqa: E731

#: Data sets served: DID -> (name, size, fields as (name, offset, kind)).
SETS: Dict[int, Tuple[str, int, Sequence[Field]]] = {
    DEV_INFO: (
        "DEV_INFO",
        84,
        (
            ("hardwareType", 2, "u8"),
            ("hdwRunState", 3, "u8"),
            ("serialNumber", 4, "u32"),
            ("hardwareVer", 8, "ver"),
            ("firmwareVer", 12, "ver"),
            ("buildNumber", 16, "u32"),
            ("protocolVer", 20, "ver"),
            ("repoRevision", 24, "u32"),
            ("manufacturer", 28, "str24"),
            ("buildType", 52, "u8"),
            ("addInfo", 60, "str24"),
        ),
    ),
    PIMU: ("PIMU", 40, _PIMU),
    SYS_CMD: ("SYS_CMD", 8, (("command", 0, "u32"), ("invCommand", 4, "u32"))),
    RMC: ("RMC", 12, (("bits", 0, "u64"), ("options", 8, "u32"))),
    SYS_PARAMS: (
        "SYS_PARAMS",
        64,
        (
            ("timeOfWeekMs", 0, "u32"),
            ("insStatus", 4, "u32"),
            ("hdwStatus", 8, "u32"),
            ("imuTemp", 12, "f32"),
            ("baroTemp", 16, "f32"),
            ("mcuTemp", 20, "f32"),
            ("sysStatus", 24, "u32"),
            ("imuSamplePeriodMs", 28, "u32"),
            ("navOutputPeriodMs", 32, "u32"),
            ("sensorTruePeriod", 36, "f64"),
            ("flashCfgChecksum", 44, "u32"),
            ("navUpdatePeriodMs", 48, "u32"),
            ("genFaultCode", 52, "u32"),
            ("upTime", 56, "f64"),
        ),
    ),
    FLASH_CONFIG: (
        "FLASH_CONFIG",
        288,
        (
            ("size", 0, "u32"),
            ("checksum", 4, "u32"),
            ("key", 8, "u32"),
            ("startupImuDtMs", 12, "u32"),
            ("startupNavDtMs", 16, "u32"),
            ("ser0BaudRate", 20, "u32"),
            ("ser1BaudRate", 24, "u32"),
            ("insRotation", 28, "f32x3"),
            ("insOffset", 40, "f32x3"),
            ("gps1AntOffset", 52, "f32x3"),
            ("dynamicModel", 64, "u8"),
            ("debug", 65, "u8"),
            ("gnssSatSigConst", 66, "u16"),
            ("sysCfgBits", 68, "u32"),
            ("refLla", 72, "f64x3"),
            ("lastLla", 96, "f64x3"),
            ("lastLlaTimeOfWeekMs", 120, "u32"),
            ("lastLlaWeek", 124, "u32"),
            ("lastLlaUpdateDistance", 128, "f32"),
            ("ioConfig", 132, "u32"),
            ("platformConfig", 136, "u32"),
            ("gps2AntOffset", 140, "f32x3"),
            ("zeroVelRotation", 152, "f32x3"),
            ("zeroVelOffset", 164, "f32x3"),
            ("gpsTimeUserDelay", 176, "f32"),
            ("magDeclination", 180, "f32"),
            ("gpsTimeSyncPeriodMs", 184, "u32"),
            ("startupGPSDtMs", 188, "u32"),
            ("RTKCfgBits", 192, "u32"),
            ("sensorConfig", 196, "u32"),
            ("gpsMinimumElevation", 200, "f32"),
            ("ser2BaudRate", 204, "u32"),
            ("magInterferenceThreshold", 268, "f32"),
            ("magCalibrationQualityThreshold", 272, "f32"),
            ("imuRejectThreshGyroLow", 278, "u8"),
            ("imuRejectThreshGyroHigh", 279, "u8"),
            ("imuShockDetectLatencyMs", 280, "u8"),
            ("imuShockRejectLatchMs", 281, "u8"),
            ("imuShockOptions", 282, "u8"),
        ),
    ),
    IMU: ("IMU", 36, _IMU),
    BIT: (
        "BIT",
        56,
        (
            ("command", 0, "u8"),
            ("lastCommand", 1, "u8"),
            ("state", 2, "u8"),
            ("hdwBitStatus", 4, "u32"),
            ("calBitStatus", 8, "u32"),
            ("pqr", 36, "f32"),
            ("acc", 40, "f32"),
            ("pqrSigma", 44, "f32"),
            ("accSigma", 48, "f32"),
            ("testMode", 52, "u8"),
            ("testVar", 53, "u8"),
            ("detectedHardwareId", 54, "u16"),
        ),
    ),
    STROBE_IN_TIME: (
        "STROBE_IN_TIME",
        12,
        (("week", 0, "u32"), ("timeOfWeekMs", 4, "u32"), ("pin", 8, "u16"), ("count", 10, "u16")),
    ),
    IMU_RAW: ("IMU_RAW", 36, _IMU),
    INS_1: ("INS_1", 80, tuple(_INS_HEAD) + (("theta", 20, "f32x3"), ("uvw", 32, "f32x3"), ("lla", 44, "f64x3"), ("ned", 68, "f32x3"))),
    INS_2: ("INS_2", 72, tuple(_INS_HEAD) + (("qn2b", 20, "f32x4"), ("uvw", 36, "f32x3"), ("lla", 48, "f64x3"))),
    INS_3: (
        "INS_3", 76,
        tuple(_INS_HEAD) + (("qn2b", 20, "f32x4"), ("uvw", 36, "f32x3"), ("lla", 48, "f64x3"), ("msl", 72, "f32")),
    ),
    INS_4: ("INS_4", 72, tuple(_INS_HEAD) + (("qe2b", 20, "f32x4"), ("ve", 36, "f32x3"), ("ecef", 48, "f64x3"))),
    GPS1_POS: (
        "GPS1_POS",
        92,
        (
            ("week", 0, "u32"), ("timeOfWeekMs", 4, "u32"), ("status", 8, "u32"), ("ecef", 12, "f64x3"),
            ("lla", 36, "f64x3"), ("hMSL", 60, "f32"), ("hAcc", 64, "f32"), ("vAcc", 68, "f32"),
            ("pDop", 72, "f32"), ("cnoMean", 76, "f32"), ("towOffset", 80, "f64"), ("leapS", 88, "u8"),
            ("satsUsed", 89, "u8"), ("cnoMeanSigma", 90, "u8"), ("status2", 91, "u8"),
        ),
    ),
    GPS1_VEL: ("GPS1_VEL", 24, (("timeOfWeekMs", 0, "u32"), ("vel", 4, "f32x3"), ("sAcc", 16, "f32"), ("status", 20, "u32"))),
    MAGNETOMETER: ("MAGNETOMETER", 20, (("time", 0, "f64"), ("mag", 8, "f32x3"))),
    BAROMETER: (
        "BAROMETER", 24,
        (("time", 0, "f64"), ("bar", 8, "f32"), ("mslBar", 12, "f32"), ("barTemp", 16, "f32"), ("humidity", 20, "f32")),
    ),
    IMU_MAG: ("IMU_MAG", 56, tuple(_IMU) + _MAG_AT(36)),
    PIMU_MAG: ("PIMU_MAG", 60, tuple(_PIMU) + _MAG_AT(40)),
    SYS_FAULT: (
        "SYS_FAULT",
        32,
        tuple((n, 4 * k, "u32") for k, n in enumerate(("status", "g1Task", "g2FileNum", "g3LineNum", "g4", "g5Lr", "pc", "psr"))),
    ),
    # gps_version_t: swVersion[30], hwVersion[10], extension[6][30]; strings
    # the field table (as the Rust one) does not name.
    GPS1_VERSION: ("GPS1_VERSION", 220, ()),
    MAG_CAL: ("MAG_CAL", 12, (("state", 0, "u32"), ("progress", 4, "f32"), ("declination", 8, "f32"))),
    # rtos_info_t: the heap words, then period and last start of tasks 0 and 1 (60 bytes each).
    RTOS_INFO: (
        "RTOS_INFO",
        372,
        (
            ("freeHeapSize", 0, "u32"), ("mallocSize", 4, "u32"), ("freeSize", 8, "u32"),
            ("T0_periodMs", 32, "u32"), ("T0_startTimeUs", 56, "u32"),
            ("T1_periodMs", 92, "u32"), ("T1_startTimeUs", 116, "u32"),
        ),
    ),
    # can_config_t: message 0's period multiple and address, the bus rate, the receive address.
    CAN_CONFIG: (
        "CAN_CONFIG",
        168,
        (
            ("can_period_mult_0", 0, "u16"), ("can_transmit_address_0", 54, "u32"),
            ("can_baudrate_kbps", 162, "u16"), ("can_receive_address", 164, "u32"),
        ),
    ),
    # gps_sig_t: the header and the first 7-byte gps_sig_sv_t.
    GPS1_SIG: (
        "GPS1_SIG",
        708,
        (
            ("timeOfWeekMs", 0, "u32"), ("numSigs", 4, "u32"), ("gnssId", 8, "u8"), ("svId", 9, "u8"),
            ("sigId", 10, "u8"), ("cno", 11, "u8"), ("quality", 12, "u8"),
        ),
    ),
    # port_monitor_t: port 0 (the serial line) of the six 37-byte sets, activePorts.
    PORT_MONITOR: (
        "PORT_MONITOR",
        223,
        (("portInfo", 0, "u8"),)
        + tuple((n, 1 + 4 * k, "u32") for k, n in enumerate((
            "status", "txBytesPerSec", "rxBytesPerSec", "txBytes", "rxBytes", "txDataDrops", "rxOverflows",
            "txBytesDropped", "rxChecksumErrors")))
        + (("activePorts", 222, "u8"),),
    ),
    # imu3_t: time, status, then IMU 1 of the three (they read alike).
    IMU3_RAW: ("IMU3_RAW", 84, (("time", 0, "f64"), ("status", 8, "u32"), ("pqr", 12, "f32x3"), ("acc", 24, "f32x3"))),
    SYS_SENSORS: (
        "SYS_SENSORS",
        80,
        (
            ("time", 0, "f64"), ("temp", 8, "f32"), ("pqr", 12, "f32x3"), ("acc", 24, "f32x3"),
            ("mag", 36, "f32x3"), ("bar", 48, "f32"), ("barTemp", 52, "f32"), ("mslBar", 56, "f32"),
            ("humidity", 60, "f32"), ("vin", 64, "f32"), ("ana", 68, "f32x3"),
        ),
    ),
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


def device_time(did: int, data: bytes) -> Optional[float]:
    """The device time a set carries, s: ``time`` (since boot) of the IMU,
    PIMU, magnetometer, barometer and sensor sets; the GPS time of week of
    INS_1..4, GPS1_POS, GPS1_VEL, GPS1_SIG; ``timeOfWeekMs`` / 1000 of
    STROBE_IN_TIME and SYS_PARAMS."""
    if did in (IMU, IMU_RAW, IMU3_RAW, PIMU, IMU_MAG, PIMU_MAG, MAGNETOMETER, BAROMETER, SYS_SENSORS):
        return struct.unpack_from("<d", data, 0)[0]
    if did in (INS_1, INS_2, INS_3, INS_4):
        return struct.unpack_from("<d", data, 4)[0]
    if did == GPS1_POS:
        return struct.unpack_from("<I", data, 4)[0] / 1000.0
    if did in (GPS1_VEL, GPS1_SIG):
        return struct.unpack_from("<I", data, 0)[0] / 1000.0
    if did == STROBE_IN_TIME:
        return struct.unpack_from("<I", data, 4)[0] / 1000.0
    if did == SYS_PARAMS:
        return struct.unpack_from("<I", data, 0)[0] / 1000.0
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
