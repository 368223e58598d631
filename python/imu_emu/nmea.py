"""The emulated IMX-5's NMEA side (``docs/isb.md`` "NMEA"): build ``$ASCE``
and the other commands, and cut whole, checksum-checked sentences out of a
byte stream that also carries ISB packets.

>>> asce(("GNGGA", 5), ("PINS1", 2))
b'$ASCE,0,GNGGA,5,PINS1,2*72\\r\\n'
>>> r = SentenceReader()
>>> [s.name for s in r.feed(b"\\xef\\x49$GNZDA,152744.000,13,03,2026,00,00*4E\\r\\n")]
['GNZDA']
"""

from typing import List, NamedTuple, Sequence, Tuple, Union

#: The IMX-5's NMEA message IDs (SDK 2.7.1 ``NMEA_MSG_ID_*``, 1-based).
IDS = {
    "PIMU": 1, "PPIMU": 2, "PRIMU": 3, "PINS1": 4, "PINS2": 5, "PGPSP": 6,
    "GGA": 7, "GLL": 8, "GSA": 9, "RMC": 10, "ZDA": 11, "PASHR": 12,
    "PSTRB": 13, "INFO": 14, "GSV": 15, "VTG": 16, "INTEL": 17,
    "POWGPS": 18, "POWTLV": 19,
}
#: ``$ASCE`` options: save the table as persistent (as ``$PERS``).
PERSISTENT = 0x200

#: The commands as the vendor's tool sends them.
INFO = b"$INFO*0E\r\n"
STOP_ALL_PORTS = b"$STPB*15\r\n"
STOP_THIS_PORT = b"$STPC*14\r\n"
SAVE_PERSISTENT = b"$PERS*14\r\n"
SOFTWARE_RESET = b"$SRST*06\r\n"
#: Asks for the ``$ASCE`` table (the reply is ``$ASCE,0{,id,period}``).
ASCE_QUERY = b"$ASCE*14\r\n"

MAX_SENTENCE = 256


def checksum(body: bytes) -> int:
    """XOR of the bytes between ``$`` and ``*``."""
    x = 0
    for b in body:
        x ^= b
    return x


def sentence(body: str) -> bytes:
    """``$body*CS\\r\\n`` with the checksum in upper-case hex."""
    raw = body.encode("ascii")
    return b"$%s*%02X\r\n" % (raw, checksum(raw))


def asce(*pairs: Tuple[Union[str, int], int], options: int = 0) -> bytes:
    """``$ASCE``: each ``(id, period)`` turns on a sentence (an ID number,
    or a name the device knows: ``PINS1``, ``GNGGA``, ``GPGSV_1``…) every
    ``period`` updates of its source (0: once); ``options`` e.g.
    :data:`PERSISTENT`. At most 20 pairs."""
    if len(pairs) > 20:
        raise ValueError("$ASCE carries at most 20 pairs")
    body = "ASCE,%d" % options
    for ident, period in pairs:
        if not 0 <= int(period) <= 255:
            raise ValueError("period %r: 0..255" % (period,))
        body += ",%s,%d" % (ident, int(period))
    return sentence(body)


class Sentence(NamedTuple):
    """A whole sentence with a valid checksum."""

    #: The first field without ``$`` (``GNGGA``, ``PINS1``, ``ASCE``).
    name: str
    #: The fields after the name.
    fields: List[str]
    #: The sentence as received, ``$`` to LF.
    raw: bytes

    @property
    def line(self) -> str:
        """The sentence without CR LF (what NMEA parsers take)."""
        return self.raw.decode("ascii").rstrip("\r\n")


def parse(raw: bytes) -> Sentence:
    """One ``$…*CS\\r\\n`` sentence; :class:`ValueError` if its form or
    checksum is wrong."""
    if not (raw.startswith(b"$") and raw.endswith(b"\r\n") and len(raw) >= 6 and raw[-5:-4] == b"*"):
        raise ValueError("not a sentence: %r" % raw[:40])
    body = raw[1:-5]
    if int(raw[-4:-2], 16) != checksum(body):
        raise ValueError("bad checksum: %r" % raw[:40])
    parts = body.decode("ascii").split(",")
    return Sentence(parts[0], parts[1:], bytes(raw))


class SentenceReader:
    """Cuts whole sentences out of a byte stream in any chunking; ISB
    packets, noise and sentences with a bad checksum are skipped (``bad``
    counts candidates dropped: a ``$`` that started no whole sentence
    with a valid checksum, including one inside an ISB packet's bytes)."""

    def __init__(self) -> None:
        self._buf = bytearray()
        self.bad = 0

    def feed(self, data: bytes) -> List[Sentence]:
        out = []
        for b in data:
            if b == 0x24:  # '$'
                if self._buf:
                    self.bad += 1
                self._buf = bytearray(b"$")
                continue
            if not self._buf:
                continue
            self._buf.append(b)
            if b == 0x0A:
                raw, self._buf = bytes(self._buf), bytearray()
                try:
                    out.append(parse(raw))
                except ValueError:
                    self.bad += 1
            elif len(self._buf) > MAX_SENTENCE or not (b == 0x0D or 0x20 <= b < 0x7F):
                self._buf = bytearray()
                self.bad += 1
        return out


def ids(names: Sequence[str]) -> List[int]:
    """The ID numbers of sentence names (``GGA`` or ``GNGGA``, ``PINS1``)."""
    out = []
    for n in names:
        key = n if n in IDS else n[2:]
        out.append(IDS[key])
    return out
