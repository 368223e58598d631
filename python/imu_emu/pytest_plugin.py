"""The pytest plugin (registered by the ``pytest11`` entry point when the
package is installed): an ``emulator`` fixture, a fresh
:class:`imu_emu.Emulator` per test, stopped afterwards.

Configure it with the ``imu_emu`` marker or by indirect parametrization;
the keys are those of :func:`imu_emu.emulator.options` (``model``,
``protocol``, ``seed``, ``speed``, ``args``)::

    @pytest.mark.imu_emu(model="K120", seed=3)
    def test_k120(emulator):
        emulator.request(imu_emu.start("GA"), 0x8F)

    @pytest.mark.parametrize("emulator", [{"protocol": "isb"}], indirect=True)
    def test_imx(emulator):
        emulator.request(imu_emu.isb.get_data(imu_emu.isb.DEV_INFO), imu_emu.isb.DEV_INFO)

Without the entry point (the package on ``sys.path`` only), a
``conftest.py`` can load it: ``pytest_plugins = ["imu_emu.pytest_plugin"]``.
"""

from typing import Any, Dict, Iterator

import pytest

from .emulator import Emulator, options

_KEYS = ("model", "protocol", "seed", "speed", "args")


def pytest_configure(config: Any) -> None:
    config.addinivalue_line(
        "markers",
        "imu_emu(model=None, protocol=None, seed=None, speed=None, args=()): "
        "options of the emulator fixture",
    )


def _settings(request: Any) -> Dict[str, Any]:
    settings: Dict[str, Any] = {}
    marker = request.node.get_closest_marker("imu_emu")
    if marker is not None:
        settings.update(marker.kwargs)
    settings.update(getattr(request, "param", None) or {})
    unknown = set(settings) - set(_KEYS)
    if unknown:
        raise TypeError(
            "imu_emu fixture: unknown setting(s) %s; expected %s"
            % (", ".join(sorted(unknown)), ", ".join(_KEYS))
        )
    return settings


@pytest.fixture
def emulator(request: Any) -> Iterator[Emulator]:
    """A running emulator (loopback TCP + control socket), configured by
    the ``imu_emu`` marker or an indirect parameter."""
    with Emulator(options(**_settings(request))) as emu:
        yield emu
