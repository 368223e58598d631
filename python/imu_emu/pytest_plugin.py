"""A pytest fixture: ``emulator``, a fresh :class:`imu_emu.Emulator` per
test (stopped afterwards).

Use it from a ``conftest.py``::

    pytest_plugins = ["imu_emu.pytest_plugin"]

    def test_ga(emulator):
        f = emulator.request(imu_emu.start("GA"), 0x8F)
"""

import pytest

from .emulator import Emulator


@pytest.fixture
def emulator():
    """A running emulator (loopback TCP + control socket)."""
    with Emulator() as emu:
        yield emu
