"""Tests of the Python helper, against the real emulator binary."""

import struct
import sys
import unittest
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import imu_emu  # noqa: E402
from imu_emu import kernel  # noqa: E402


class CodecTest(unittest.TestCase):
    def test_commands_are_the_icd_vectors(self):
        self.assertEqual(imu_emu.get_dev_info(), bytes.fromhex("AA55000007001219 00".replace(" ", "")))
        self.assertEqual(imu_emu.start("GA"), bytes.fromhex("AA5500000700 8F9600".replace(" ", "")))
        self.assertEqual(imu_emu.stop(), bytes.fromhex("AA5500000700FE0501"))
        self.assertEqual(
            imu_emu.save_flash(0x0012, struct.pack("<H", 2000)),
            bytes.fromhex("AA5500000E00B2FF12000200D007AA02"),
        )
        self.assertEqual(imu_emu.read_ram(0x0012, 2), bytes.fromhex("AA5500000C00B1FF12000200D001"))

    def test_reader_resynchronises_in_any_chunking(self):
        good = kernel.encode(1, 0x8F, bytes(range(32)))
        bad = bytearray(good)
        bad[-1] ^= 1
        stream = b"\x00\xAA" + bytes(bad) + good + good
        r = kernel.FrameReader()
        frames = []
        for i in range(0, len(stream), 3):
            frames += r.feed(stream[i : i + 3])
        self.assertEqual([f.raw for f in frames], [good, good])
        self.assertGreaterEqual(r.bad, 1)

    def test_ga_decoding(self):
        p = struct.pack("<6iHHhh", 100000, 0, -250000, 0, 0, 1000000, 40, 0, 0, 253)
        d = kernel.decode_ga(p)
        self.assertEqual(d["gyro"], (1.0, 0.0, -2.5))
        self.assertEqual(d["acc"][2], 1.0)
        self.assertEqual(d["counter"], 40)
        self.assertEqual(d["temp_c"], 25.3)


class ProfileTest(unittest.TestCase):
    def test_a_shown_builtin_profile_reads_with_its_datasheet_figures(self):
        import subprocess
        import tempfile
        text = subprocess.run([imu_emu.find_binary(), "sensor-profile", "show", "IMX-5"],
                              check=True, capture_output=True).stdout
        with tempfile.TemporaryDirectory() as d:
            path = Path(d) / "imx5.toml"
            path.write_bytes(text)
            p = imu_emu.read_profile(path)
            self.assertEqual(p["gyro"]["range"], 4000.0)
            self.assertAlmostEqual(p["gyro"]["datasheet"]["arw_deg_rt_h"], 0.16, places=6)
            self.assertAlmostEqual(p["gyro"]["datasheet"]["bias_instability_deg_h"], 1.5, places=5)
            self.assertAlmostEqual(p["acc"]["datasheet"]["vrw_m_s_rt_h"], 0.02, places=6)
            self.assertAlmostEqual(p["acc"]["datasheet"]["bias_instability_ug"], 19.0, places=3)
            path.write_bytes(text.replace(b"resolution", b"resolutoin", 1))
            with self.assertRaisesRegex(imu_emu.ProfileError, "gyro.resolutoin"):
                imu_emu.read_profile(path)


class EmulatorTest(unittest.TestCase):
    def setUp(self):
        self.emu = imu_emu.Emulator(["--seed", "1"])

    def tearDown(self):
        self.emu.stop()

    def test_get_dev_info_and_a_ga_stream(self):
        info = self.emu.request(imu_emu.get_dev_info(), 0x12)
        self.assertEqual(len(info.payload), 166)
        self.assertTrue(info.payload[8:48].startswith(b"KERNEL-110"))
        ack = self.emu.request(imu_emu.start("GA"), 0x8F)
        self.assertEqual(ack.payload, imu_emu.start("GA")[-2:])
        frames = [f for f in self.emu.frames(0.5) if f.ident == 0x8F]
        counters = [kernel.decode_ga(f.payload)["counter"] for f in frames]
        self.assertGreaterEqual(len(counters), 30)
        for a, b in zip(counters, counters[1:]):
            self.assertEqual((b - a) & 0xFFFF, 20)
        az = kernel.decode_ga(frames[0].payload)["acc"][2]
        self.assertAlmostEqual(az, 1.0, delta=0.05)

    def test_control_status_link_faults_and_errors(self):
        self.emu.request(imu_emu.start("GA"), 0x8F)
        ctl = self.emu.control()
        st = ctl.status()
        self.assertEqual(st["mode"], "continuous")
        self.assertEqual(st["format"], "0x8f")
        self.assertEqual(st["line-rate"], "115200")
        self.assertEqual(ctl.link("corrupt", 1, "tx"), "")
        self.emu.frames(0.1)
        self.assertEqual(self.emu.frames(0.3), [])
        ctl.link("clear")
        self.emu.frames(0.05)
        self.assertGreaterEqual(len(self.emu.frames(0.3)), 10)
        with self.assertRaises(RuntimeError) as e:
            ctl.cmd("extrig sideways")
        self.assertEqual(str(e.exception), "error bad syntax: extrig sideways; expected extrig high|low")
        self.assertTrue(ctl.cmd("help").startswith("commands: help | status"))

    def test_tov_events_are_kept_apart_from_replies(self):
        ctl = self.emu.control()
        # TOV_Control = 1 (ICD Table 5.24, ID 0x0499), then GA.
        self.emu.request(imu_emu.save_flash(0x0499, b"\x01"), 0xB2)
        self.emu.request(imu_emu.start("GA"), 0x8F)
        self.emu.frames(0.2)
        self.assertEqual(ctl.cmd("status").split()[0], "mode=continuous")
        self.assertGreater(len(ctl.events), 0)
        self.assertTrue(all(e.split()[0] == "tov" for e in ctl.events))


class FleetTest(unittest.TestCase):
    def setUp(self):
        self.fleet = imu_emu.Fleet(3, ["--seed", "1"])

    def tearDown(self):
        self.fleet.stop()

    def test_each_device_streams_at_its_own_rate_and_takes_its_own_faults(self):
        devs = self.fleet.devices
        self.assertEqual(len({d.port for d in devs}), 3)
        # Device 1 at 50 Hz (Data_Rate, ICD Table 5.24 ID 0x0012), the others at 100 Hz.
        devs[1].request(imu_emu.save_flash(0x0012, (50).to_bytes(2, "little")), 0xB2)
        for d in devs:
            d.request(imu_emu.start("GA"), 0x8F)
        for k, d in enumerate(devs):
            frames = [f for f in d.frames(0.4) if f.ident == 0x8F]
            counters = [kernel.decode_ga(f.payload)["counter"] for f in frames]
            self.assertGreaterEqual(len(counters), 10)
            for a, b in zip(counters, counters[1:]):
                self.assertEqual((b - a) & 0xFFFF, 40 if k == 1 else 20)
        self.assertEqual(self.fleet.status(2)["mode"], "continuous")
        self.assertEqual(self.fleet.dev(2, "fault", "comm", "on"), "")
        # USW bit 1 (sensor communication) on device 2 only (Table 5.7: USW at 26).
        for k, d in enumerate(devs):
            last = [f for f in d.frames(0.2) if f.ident == 0x8F][-1]
            usw = int.from_bytes(last.payload[26:28], "little")
            self.assertEqual(usw, 2 if k == 2 else 0, k)
        with self.assertRaises(RuntimeError) as e:
            self.fleet.control().cmd("status")
        self.assertEqual(
            str(e.exception),
            "error this run has 3 devices: address one, dev <K> <command> (K = 0..2)",
        )


class PluginTest(unittest.TestCase):
    def test_the_fixture_module_imports_where_pytest_is(self):
        try:
            import pytest  # noqa: F401
        except ImportError:
            self.skipTest("pytest not installed")
        from imu_emu import pytest_plugin

        self.assertTrue(callable(pytest_plugin.emulator))


if __name__ == "__main__":
    unittest.main()
