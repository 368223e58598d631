"""imu_emu: drive the imu-emu KERNEL emulator from Python tests.

Standard library only. Three parts:

* :mod:`imu_emu.kernel` -- the KERNEL frame codec (ICD Table 5.2): build
  commands, split a byte stream into checked frames, decode GA frames.
* :class:`Emulator` -- start the ``imu-emu`` binary on a free TCP port with
  a control socket, connect to its UART, stop it.
* :class:`Fleet` -- N devices in one ``imu-emu --count N``, each a
  :class:`Uart`, with one control socket addressing each.
* :class:`Control` -- the control socket (pins, faults, link faults,
  ``status``), with events kept apart from replies.
* :func:`read_profile` -- a sensor profile file (``--sensor-profile``).

* :class:`FeedEmulator` -- an emulator moved by a live motion feed
  (:mod:`imu_emu.feed`), in real time or in lockstep.

A pytest fixture is in :mod:`imu_emu.pytest_plugin`.
"""

from .kernel import (  # noqa: F401
    Frame,
    FrameReader,
    checksum,
    command,
    commit_baud_rate,
    decode_ga,
    encode,
    get_bit,
    get_dev_info,
    read_ram,
    save_flash,
    start,
    stop,
)
from .emulator import Control, Emulator, Fleet, Uart, find_binary  # noqa: F401
from .feed import Feed, FeedEmulator, encode_sample, text_row  # noqa: F401
from .profile import ProfileError, read_profile  # noqa: F401
