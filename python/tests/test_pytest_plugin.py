"""The ``emulator`` fixture as a user gets it: loaded by the package's
``pytest11`` entry point (no conftest.py), configured by marker or
parameter."""

import pytest

import imu_emu
from imu_emu import isb


def test_the_default_is_a_k110(emulator):
    info = emulator.request(imu_emu.get_dev_info(), 0x12).payload
    assert info[8:48].startswith(b"KERNEL-110")


@pytest.mark.imu_emu(model="K120", seed=3, speed=2)
def test_a_marker_sets_model_seed_and_speed(emulator):
    info = emulator.request(imu_emu.get_dev_info(), 0x12).payload
    assert info[8:48].startswith(b"KERNEL-120")
    args = emulator.cmd
    assert args[args.index("--seed") + 1] == "3"
    assert args[args.index("--speed") + 1] == "2"


@pytest.mark.parametrize("emulator", [{"protocol": "isb"}], indirect=True)
def test_a_parameter_picks_the_isb_protocol(emulator):
    emulator.send(isb.get_data(isb.DEV_INFO))
    p = emulator.frame(isb.DEV_INFO)
    assert isb.decode_set(p.did, p.payload)["manufacturer"] == "Inertial Sense Inc"


@pytest.mark.imu_emu(args=["--power-on", "now"], warp=9)
def test_an_unknown_setting_is_refused(request):
    with pytest.raises(TypeError, match="unknown setting.*warp"):
        request.getfixturevalue("emulator")
