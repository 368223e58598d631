"""Tests of the Python helper, against the real emulator binary."""

import json
import os
import struct
import subprocess
import tempfile
import time
import unittest
from importlib import metadata
from pathlib import Path

import imu_emu
from imu_emu import isb, kernel


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

    def test_the_ga_acknowledgement_is_not_decoded_as_data(self):
        # The device acknowledges the GA command with a frame of GA's ident
        # whose 2-byte payload is the command's checksum (ICD 5.3.1).
        with self.assertRaisesRegex(ValueError, "acknowledgement of the GA command"):
            kernel.decode_ga(imu_emu.start("GA")[-2:])
        with self.assertRaisesRegex(ValueError, "32 bytes, not 31"):
            kernel.decode_ga(bytes(31))

    def test_formula_5_1_gives_table_5_28(self):
        # ICD Table 5.28: GA and Calibrated HR at 38 400 ... 2 000 000 bit/s.
        for baud, ga, hr in ((38_400, 80, 50), (115_200, 250, 125), (460_800, 1000, 500),
                             (2_000_000, 2000, 2000)):
            self.assertEqual(imu_emu.max_rate(baud, 32), ga)
            self.assertEqual(imu_emu.effective_rate(2000, baud, "Calibrated HR"), hr)
        self.assertEqual(imu_emu.effective_rate(100, 115_200, "GA"), 100)


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
            # The current datasheet's figures (docs/sensors.md); no aux
            # accelerometer, so no [aux] section.
            self.assertAlmostEqual(p["gyro"]["datasheet"]["arw_deg_rt_h"], 0.23, places=6)
            self.assertAlmostEqual(p["gyro"]["datasheet"]["bias_instability_deg_h"], 2.0, places=5)
            self.assertAlmostEqual(p["acc"]["datasheet"]["vrw_m_s_rt_h"], 0.02, places=6)
            self.assertAlmostEqual(p["acc"]["datasheet"]["bias_instability_ug"], 27.0, places=3)
            self.assertNotIn("aux", p)
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

    def test_set_data_rate_says_when_the_device_lowers_it(self):
        with self.assertWarnsRegex(
            imu_emu.RateLoweredWarning,
            r"Data_Rate 1000 Hz: at 115200 bit/s the device sends GA at 250 Hz",
        ):
            self.assertEqual(self.emu.set_data_rate(1000), 250)
        # The stream runs at the rate returned: counter steps of 2000/250.
        self.emu.request(imu_emu.start("GA"), 0x8F)
        frames = [f for f in self.emu.frames(0.3) if f.ident == 0x8F]
        counters = [kernel.decode_ga(f.payload)["counter"] for f in frames]
        self.assertGreaterEqual(len(counters), 10)
        self.assertEqual({(b - a) & 0xFFFF for a, b in zip(counters, counters[1:])}, {8})
        import warnings
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            self.assertEqual(self.emu.set_data_rate(200), 200)

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


class ReadmeTest(unittest.TestCase):
    def test_the_readme_python_snippet_prints_what_it_says(self):
        # The repository's README, from the clone these tests run from.
        import contextlib
        import io
        import re
        readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
        snippet = re.search(r"```python\n(import imu_emu\n.*?)```", readme, re.S).group(1)
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            exec(compile(snippet, "README.md", "exec"), {})
        lines = out.getvalue().splitlines()
        self.assertEqual(len(lines), 3, lines)
        self.assertTrue(lines[0].startswith("b'KERNEL-110-G2000-A40 imu-emu"), lines[0])
        n = int(lines[1].split()[0])
        self.assertGreaterEqual(n, 90)
        # After 1 % of the sent bytes were corrupted, frames failed their
        # checksum at this end (the snippet printed `rejected`, always 0:
        # the device's count of frames it refused).
        self.assertGreater(int(lines[2]), 0, lines)


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


class PackageTest(unittest.TestCase):
    def test_installed_with_its_pytest_entry_point_and_types(self):
        self.assertEqual(metadata.version("imu-emu"), imu_emu.__version__)
        eps = metadata.entry_points()
        group = eps.select(group="pytest11") if hasattr(eps, "select") else eps.get("pytest11", [])
        self.assertIn("imu_emu.pytest_plugin", [e.value for e in group])
        typed = os.path.join(os.path.dirname(imu_emu.__file__), "py.typed")
        self.assertTrue(os.path.isfile(typed))

    def test_a_missing_binary_error_says_where_it_looked(self):
        import sys
        with tempfile.TemporaryDirectory() as d:
            env = {"PATH": d, "HOME": d, "CARGO_TARGET_DIR": os.path.join(d, "tgt")}
            run = [sys.executable, "-c", "import imu_emu; imu_emu.find_binary()"]
            err = subprocess.run(run, env=env, capture_output=True, text=True)
            self.assertNotEqual(err.returncode, 0)
            self.assertIn("imu-emu binary not found; looked at: $IMU_EMU_BIN (not set), "
                          + os.path.join(d, "tgt", "release", "imu-emu"), err.stderr)
            self.assertIn("imu-emu on PATH. Build it", err.stderr)
            env["IMU_EMU_BIN"] = os.path.join(d, "nothing")
            err = subprocess.run(run, env=env, capture_output=True, text=True)
            self.assertIn("IMU_EMU_BIN=%s is not an executable file" % env["IMU_EMU_BIN"],
                          err.stderr)

    def test_a_failed_start_says_why(self):
        with self.assertRaises(imu_emu.EmulatorStartError) as e:
            imu_emu.Emulator(["--model", "K999"])
        self.assertEqual(e.exception.returncode, 2)
        self.assertIn("K999", e.exception.stderr)
        self.assertTrue(
            str(e.exception).startswith(
                "imu-emu did not start (exit status 2): error: invalid value 'K999' for "
                "'--model <MODEL>'"
            ),
            str(e.exception),
        )


def _record(emu, start_frame, ident, seconds=0.5):
    """Raw bytes of ``seconds`` of a stream started with ``start_frame``."""
    emu.request(start_frame, ident)
    emu.frames(0.05)
    s = emu.uart()
    raw = b""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        s.settimeout(0.05)
        try:
            raw += s.recv(65536)
        except OSError:
            pass
    return raw


def _binary_rows(raw, *args):
    """``imu-emu client [args] decode`` of ``raw`` as JSON rows."""
    with tempfile.NamedTemporaryFile(suffix=".bin") as f:
        f.write(raw)
        f.flush()
        out = subprocess.run(
            [imu_emu.find_binary(), "client", *args, "decode", f.name, "--to", "json"],
            check=True, capture_output=True, text=True,
        ).stdout
    rows = [json.loads(line) for line in out.splitlines()]
    for r in rows:
        for k in ("frame", "format", "did", "device_time_s"):
            r.pop(k, None)
    return rows


class DecoderTest(unittest.TestCase):
    """The Python decoders give what the binary's decoder gives, on frames
    of every KERNEL format, every UDD type and the ISB sets the emulator
    streams."""

    def _kernel_agrees(self, emu, product, start_frame, ident):
        raw = _record(emu, start_frame, ident)
        frames = [f for f in kernel.FrameReader().feed(raw) if f.ident == ident]
        self.assertGreater(len(frames), 3)
        want = _binary_rows(raw, "--model", product)
        got = [imu_emu.decode_kernel(f.ident, f.payload, product) for f in frames]
        self.assertEqual(len(got), len(want))
        for g, w in zip(got, want):
            self.assertEqual(g, w)
        return got

    def test_every_kernel_format(self):
        product = "KERNEL-120-G2000-A40A90"
        # At 10x: attitude streams start after the 2 s initial alignment (5.3.1).
        with imu_emu.Emulator(["--model", "K120", "--seed", "2", "--speed", "10"]) as emu:
            for code in imu_emu.decode.KERNEL_FORMATS:
                rows = self._kernel_agrees(emu, product, kernel.command(bytes([code])), code)
                self.assertTrue(any(k.startswith("gyro_") or k == "heading" for k in rows[0]))
                emu.send(imu_emu.stop())
                emu.frames(0.1)

    def test_every_udd_type(self):
        lists = [
            ("K120", "KERNEL-120-G2000-A40A90", [0x02, 0x05, 0x07, 0x08, 0x09, 0x20]),
            ("K120", "KERNEL-120-G2000-A40A90", [0x21, 0x22, 0x23, 0x2D, 0x2E, 0x2F]),
            ("K120", "KERNEL-120-G2000-A40A90", [0x91, 0x92, 0x52, 0x53, 0x5B]),
            ("K100", None, [0x50, 0x52]),
        ]
        seen = set()
        for model, product, types in lists:
            with imu_emu.Emulator(["--model", model, "--speed", "10"]) as emu:
                emu.uart()
                product = product or _product_of(emu)
                # User_Def_Data_config (ICD 5.3.5): the command, then the
                # list; the answer's error bits (byte 2) are 0.
                emu.send(kernel.command(bytes([0x96])))
                answer = emu.request(kernel.command(bytes([0x96, len(types), *types])), 0x96)
                self.assertEqual(answer.payload[2], 0, types)
                rows = self._kernel_agrees(emu, product, imu_emu.start("UDD"), 0x95)
                seen.update(types)
                self.assertEqual(
                    set(rows[0]),
                    {c for t in types for c in imu_emu.decode.FIELDS[imu_emu.decode.UDD_TYPES[t][1]][1]},
                )
        self.assertEqual(seen, set(imu_emu.decode.UDD_TYPES))

    def test_isb_sets(self):
        with imu_emu.Emulator(["--protocol", "isb"]) as emu:
            emu.send(isb.get_data(isb.IMU, 1))
            emu.send(isb.get_data(isb.PIMU, 1))
            raw = b""
            s = emu.uart()
            end = time.monotonic() + 0.3
            while time.monotonic() < end:
                s.settimeout(0.05)
                try:
                    raw += s.recv(65536)
                except OSError:
                    pass
            for d in (isb.DEV_INFO, isb.SYS_PARAMS, isb.FLASH_CONFIG, isb.RMC, isb.BIT, isb.STROBE_IN_TIME,
                      isb.INS_1, isb.INS_2, isb.INS_3, isb.INS_4, isb.GPS1_POS, isb.GPS1_VEL,
                      isb.MAGNETOMETER, isb.BAROMETER, isb.IMU_MAG, isb.PIMU_MAG, isb.SYS_SENSORS,
                      isb.SYS_FAULT, isb.GPS1_VERSION, isb.MAG_CAL, isb.GPS1_SIG, isb.IMU3_RAW,
                      isb.PORT_MONITOR, isb.NMEA_BCAST_PERIOD, isb.GPS1_RCVR_POS, isb.GPS1_SAT,
                      isb.INL2_STATES, isb.INL2_NED_SIGMA, isb.RTOS_INFO, isb.CAN_CONFIG):
                emu.send(isb.get_data(d))
                raw += emu.frame(d).raw
            emu.send(isb.stop_all())
        packets = [p for p in isb.PacketReader().feed(raw) if p.whole_set() is not None]
        got = [isb.decode_set(p.did, p.payload) for p in packets]
        want = _binary_rows(raw, "--protocol", "isb")
        for w in want:
            w.pop("host_time_s", None)
        self.assertEqual(got, want)
        self.assertEqual(
            {p.did for p in packets},
            set(isb.SETS) - {isb.SYS_CMD, isb.IMU_RAW},
        )
        imu = [isb.decode_set(p.did, p.payload) for p in packets if p.did == isb.IMU][-1]
        self.assertAlmostEqual(imu["acc_z"], -9.81, delta=0.1)
        info = next(isb.decode_set(p.did, p.payload) for p in packets if p.did == isb.DEV_INFO)
        self.assertEqual(info["protocolVer"], "2.1.0.0")


def _product_of(emu):
    info = emu.request(imu_emu.get_dev_info(), 0x12).payload
    return info[8:48].split(b" ")[0].decode()


if __name__ == "__main__":
    unittest.main()
