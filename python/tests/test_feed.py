"""The helper's feed API (imu_emu.feed) against docs/feed.md and the
real emulator."""

import struct
import sys
import unittest
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import imu_emu  # noqa: E402
from imu_emu import feed, kernel  # noqa: E402


class EncodingTest(unittest.TestCase):
    def test_the_checksum_and_the_documented_frame(self):
        self.assertEqual(feed.crc16(b"123456789"), 0x29B1)
        f = feed.encode_sample(0.001, (10, 0, 0), (0, 0, 1), device=0)
        self.assertEqual(len(f), 41)
        self.assertEqual(f[:15], bytes([0xF5, 0xED, 1, 1, 34, 0, 0, 0x40, 0x42, 0x0F, 0, 0, 0, 0, 0]))
        self.assertEqual(f[15:19], struct.pack("<f", 10.0))
        self.assertEqual(struct.unpack("<H", f[39:])[0], feed.crc16(f[2:39]))
        self.assertEqual(len(feed.encode_sample(0, (0, 0, 0), (0, 0, 1), temp_c=25)), 45)
        self.assertEqual(feed.text_row(0.5, (1, 2, 3), (0, 0, 1)), b"0.5,1.0,2.0,3.0,0.0,0.0,1.0\n")


class RealTimeTest(unittest.TestCase):
    def test_udp_samples_move_the_gyros_and_are_counted(self):
        with imu_emu.FeedEmulator(["--seed", "2"], feed_addr="udp:127.0.0.1:0") as emu:
            emu.request(imu_emu.start("GA"), 0x8F)
            emu.feed(0.0, (0.0, 25.0, 0.0))
            emu.feed(0.001, (0.0, 25.0, 0.0), text=True)
            seen = emu.wait_frames(lambda fs: any(
                len(f.payload) == 32 and abs(kernel.decode_ga(f.payload)["gyro"][1] - 25) < 0.5
                for f in fs))
            self.assertTrue(seen)
            s = emu.control().status()
            self.assertEqual(s["feed-samples"], "2")
            self.assertEqual(s["feed-clock"], "realtime")


if __name__ == "__main__":
    unittest.main()
