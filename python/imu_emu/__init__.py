"""imu_emu: drive the imu-emu emulator (a KERNEL, or an IMX-5 speaking ISB)
from Python tests.

Standard library only (pytest for the fixture). The parts:

* :mod:`imu_emu.kernel` -- the KERNEL frame codec (ICD Table 5.2): build
  commands, split a byte stream into checked frames, decode GA frames.
* :mod:`imu_emu.decode` -- every KERNEL format and UDD type decoded
  (:func:`decode_kernel`).
* :mod:`imu_emu.isb` -- the ISB packet codec and every data set the
  emulated IMX-5 serves decoded (:func:`decode_set`).
* :mod:`imu_emu.nmea` -- the IMX-5's NMEA: ``$ASCE`` and the other
  commands, whole checksum-checked sentences cut out of a mixed stream.
* :class:`Emulator` -- start the ``imu-emu`` binary on a free TCP port with
  a control socket, connect to its UART, stop it.
* :class:`Fleet` -- N devices in one ``imu-emu --count N``, each a
  :class:`Uart`, with one control socket addressing each.
* :class:`Control` -- the control socket (pins, faults, link faults,
  ``status``), with events kept apart from replies.
* :func:`read_profile` -- a sensor profile file (``--sensor-profile``).

* :class:`FeedEmulator` -- an emulator moved by a live motion feed
  (:mod:`imu_emu.feed`), in real time or in lockstep.

A pytest fixture is in :mod:`imu_emu.pytest_plugin` (registered as a
pytest plugin when the package is installed).
"""

from .kernel import (  # noqa: F401
    Frame,
    FrameReader,
    RateLoweredWarning,
    checksum,
    command,
    commit_baud_rate,
    decode_ga,
    effective_rate,
    encode,
    get_bit,
    get_dev_info,
    max_rate,
    read_ram,
    save_flash,
    start,
    stop,
)
from . import isb  # noqa: F401
from . import nmea  # noqa: F401
from .decode import decode_kernel  # noqa: F401
from .emulator import (  # noqa: F401
    Control,
    Emulator,
    EmulatorStartError,
    Fleet,
    Uart,
    find_binary,
    options,
)
from .feed import Feed, FeedEmulator, encode_sample, text_row  # noqa: F401
from .isb import decode_set  # noqa: F401
from .profile import ProfileError, read_profile  # noqa: F401

__version__ = "0.1.0"
