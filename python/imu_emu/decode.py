"""Typed decoders of what a KERNEL sends: every fixed format (Inertial Labs
KERNEL ICD rev 1.42, Tables 5.5-5.12) and every User Defined Data type
(Tables 5.14, 5.15), with the scales of Table 5.6.

The column names and values are those of ``imu-emu client decode --to json``
(the Rust decoder, ``imu_emu::kernel::decode``); ``python/tests`` checks the
two agree on frames of every format and every UDD type the emulator sends.
"""

import re
import struct
from typing import Callable, Dict, List, Optional, Sequence, Tuple

#: Scales (Table 5.6 and the per-field notes of Tables 5.5-5.15).
RATE_HR_SCALE = 100_000  # LSB per deg/s, 32-bit gyro fields
ACC_HR_SCALE = 1_000_000  # LSB per g, 32-bit accelerometer fields
ANGLE_SCALE = 100  # LSB per deg, 16-bit angles
ANGLE_HR_SCALE = 1000  # LSB per deg, 32-bit angles
QUAT_SCALE = 10_000  # LSB per unit, quaternion
TEMPERATURE_SCALE = 10  # LSB per deg C
VOLTAGE_SCALE = 100  # LSB per V

#: KG (LSB per deg/s) of the 16-bit gyro fields by gyro range (Table 5.6).
KG = {450: 50, 950: 20, 2000: 10}
#: KA (LSB per g) of the 16-bit accelerometer fields by range (Table 5.6).
KA = {8: 4000, 15: 2000, 40: 500}


def scales(product: str = "KERNEL-110-G2000-A40") -> Tuple[int, int]:
    """(KG, KA) of a product code (``KERNEL-110-G450-A8``, Table 5.6)."""
    g = re.search(r"-G(\d+)", product)
    a = re.search(r"-A(\d+)", product)
    if not (g and a) or int(g.group(1)) not in KG or int(a.group(1)) not in KA:
        raise ValueError("not a KERNEL product code with G and A ranges: %r" % product)
    return KG[int(g.group(1))], KA[int(a.group(1))]


Reader = Callable[[bytes, int, int], List[float]]


def _ints(fmt: str, k: float) -> Reader:
    def read(b: bytes, kg: int, ka: int) -> List[float]:
        return [x / k for x in struct.unpack("<" + fmt, b)]

    return read


def _euler(b: bytes, kg: int, ka: int) -> List[float]:
    h, p, r = struct.unpack("<Hhh", b)
    return [h / ANGLE_SCALE, p / ANGLE_SCALE, r / ANGLE_SCALE]


def _lowres(which: str) -> Reader:
    def read(b: bytes, kg: int, ka: int) -> List[float]:
        k = kg if which == "g" else ka
        return [x / k for x in struct.unpack("<3h", b)]

    return read


def _word(b: bytes, kg: int, ka: int) -> List[float]:
    return [struct.unpack("<H", b)[0]]


#: Field kinds: name -> (size, columns, reader). Sizes from Table 5.15.
FIELDS: Dict[str, Tuple[int, Sequence[str], Reader]] = {
    "Euler": (6, ("heading", "pitch", "roll"), _euler),
    "EulerHr": (12, ("heading", "pitch", "roll"), _ints("3i", ANGLE_HR_SCALE)),
    "Quat": (8, ("q0", "q1", "q2", "q3"), _ints("4h", QUAT_SCALE)),
    "Gyro": (6, ("gyro_x", "gyro_y", "gyro_z"), _lowres("g")),
    "Acc": (6, ("acc_x", "acc_y", "acc_z"), _lowres("a")),
    "GyroHr": (12, ("gyro_x", "gyro_y", "gyro_z"), _ints("3i", RATE_HR_SCALE)),
    "AccHr": (12, ("acc_x", "acc_y", "acc_z"), _ints("3i", ACC_HR_SCALE)),
    "AuxAccHr": (12, ("aux_acc_x", "aux_acc_y", "aux_acc_z"), _ints("3i", ACC_HR_SCALE)),
    "GyroBiasCompHr": (12, ("gyro_bc_x", "gyro_bc_y", "gyro_bc_z"), _ints("3i", RATE_HR_SCALE)),
    "GyroBiasHr": (12, ("gyro_bias_x", "gyro_bias_y", "gyro_bias_z"), _ints("3i", RATE_HR_SCALE)),
    "FilteredAccHr": (12, ("acc_f_x", "acc_f_y", "acc_f_z"), _ints("3i", ACC_HR_SCALE)),
    "FilteredAuxAccHr": (
        12,
        ("aux_acc_f_x", "aux_acc_f_y", "aux_acc_f_z"),
        _ints("3i", ACC_HR_SCALE),
    ),
    "Usw": (2, ("usw",), _word),
    "UswExt": (2, ("usw_ext",), _word),
    "Counter": (2, ("counter",), _word),
    "TimeFlags": (2, ("time_flags",), _word),
    "Temperature": (2, ("temp_c",), _ints("h", TEMPERATURE_SCALE)),
    "SecondFraction": (4, ("second_fraction_ns",), _ints("I", 1)),
    "ImuTime": (8, ("imu_time_ns",), _ints("Q", 1)),
    "SupplyVoltage": (2, ("supply_v",), _ints("H", VOLTAGE_SCALE)),
}


def _zero(n: int) -> str:
    return "Zero%d" % n


#: The fixed formats: data command code -> (name, fields), Tables 5.5-5.12.
KERNEL_FORMATS: Dict[int, Tuple[str, Sequence[str]]] = {
    0x33: ("Orientation", ("Euler", "Gyro", "Acc", _zero(6), _zero(4), "Usw", _zero(2), "Temperature")),
    0x8F: ("GA", ("GyroHr", "AccHr", "Counter", "Usw", _zero(2), "Temperature")),
    0x9B: ("GAm", ("GyroHr", "AccHr", "TimeFlags", "SecondFraction", "Temperature")),
    0xA5: ("GAA", ("GyroHr", "AccHr", "AuxAccHr", _zero(2), "Usw", _zero(2), "Temperature")),
    0xA6: ("GAAm", ("GyroHr", "AccHr", "AuxAccHr", "TimeFlags", "SecondFraction", "Temperature")),
    0x82: ("Quaternion", ("Euler", "Quat", _zero(14), "Usw", _zero(2), "Temperature")),
    0x81: (
        "Calibrated HR",
        ("EulerHr", "GyroHr", "AccHr", _zero(6), "Counter", _zero(2), "Usw", _zero(2), "Temperature"),
    ),
}

#: User Defined Data: type code -> (name, field), Tables 5.14, 5.15.
UDD_TYPES: Dict[int, Tuple[str, str]] = {
    0x02: ("IMU Time", "ImuTime"),
    0x05: ("Second Fraction", "SecondFraction"),
    0x07: ("Orientation Angles", "Euler"),
    0x08: ("Orientation Angles HR", "EulerHr"),
    0x09: ("Quaternion of Orientation", "Quat"),
    0x20: ("Gyro Data", "Gyro"),
    0x21: ("Gyro Data HR", "GyroHr"),
    0x22: ("Accelerometer Data", "Acc"),
    0x23: ("Accelerometer Data HR", "AccHr"),
    0x2D: ("Bias-compensated Gyro Data", "GyroBiasCompHr"),
    0x2E: ("Gyro Bias", "GyroBiasHr"),
    0x2F: ("Aux Accelerometer", "AuxAccHr"),
    0x91: ("Filtered Low-G Accels HR", "FilteredAccHr"),
    0x92: ("Filtered High-G Accels HR", "FilteredAuxAccHr"),
    0x50: ("Supply Voltage", "SupplyVoltage"),
    0x52: ("Temperature", "Temperature"),
    0x53: ("Unit Status Word", "Usw"),
    0x5B: ("Unit Status Word Extended", "UswExt"),
}

#: The UDD data command (Table 5.16).
UDD = 0x95


def _size(field: str) -> int:
    if field.startswith("Zero"):
        return int(field[4:])
    return FIELDS[field][0]


def _read_fields(fields: Sequence[str], body: bytes, kg: int, ka: int) -> Dict[str, float]:
    if sum(_size(f) for f in fields) != len(body):
        raise ValueError(
            "payload of %d bytes, the layout has %d" % (len(body), sum(_size(f) for f in fields))
        )
    out: Dict[str, float] = {}
    at = 0
    for f in fields:
        n = _size(f)
        if not f.startswith("Zero"):
            _, cols, read = FIELDS[f]
            out.update(zip(cols, read(body[at : at + n], kg, ka)))
        at += n
    return out


def decode_kernel(ident: int, payload: bytes, product: str = "KERNEL-110-G2000-A40") -> Dict[str, float]:
    """A KERNEL data frame's payload as ``{column: value}`` in the ICD's
    units (deg/s, g, deg, deg C, V, ns), ``ident`` its format code.

    UDD frames (0x95) carry their own type list (Table 5.13: N, N type
    codes, the data). ``product`` gives KG/KA of the 16-bit gyro and
    accelerometer fields (Table 5.6). Raises :class:`ValueError` for an
    unknown format or type, or a payload of the wrong length.
    """
    kg, ka = scales(product)
    if ident == UDD:
        if not payload:
            raise ValueError("empty UDD payload")
        n = payload[0]
        types = payload[1 : 1 + n]
        if len(types) != n:
            raise ValueError("UDD payload shorter than its type list")
        try:
            fields = [UDD_TYPES[t][1] for t in types]
        except KeyError as e:
            raise ValueError("unknown UDD type 0x%02X" % e.args[0]) from None
        return _read_fields(fields, payload[1 + n :], kg, ka)
    if ident not in KERNEL_FORMATS:
        raise ValueError("unknown KERNEL format 0x%02X" % ident)
    return _read_fields(KERNEL_FORMATS[ident][1], payload, kg, ka)


def format_name(ident: int) -> Optional[str]:
    """The Table 5.4 name of a format code (``GA``), or None."""
    if ident == UDD:
        return "UDD"
    f = KERNEL_FORMATS.get(ident)
    return f[0] if f else None
