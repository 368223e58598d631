"""The emulated IMX-5's NMEA read by a Python NMEA parser (pynmea2, in the
package's test extras) and by :mod:`imu_emu.nmea`, against the real
emulator binary."""

import socket
import time
import unittest

import pynmea2

import imu_emu
from imu_emu import isb, nmea

#: Every sentence the IMX-5 prints. pynmea2 knows the GNSS ones and the
#: ``$P…`` proprietary form; INFO, INTEL and the ``$ASCE`` reply are the
#: IMX's own names outside NMEA's talker/proprietary forms (a four- or
#: five-letter name with no ``P``), which no NMEA library parses: they
#: are checked by :func:`imu_emu.nmea.parse` alone.
STANDARD = ["GNGGA", "GNGLL", "GNGSA", "GNRMC", "GNZDA", "GNVTG", "GPGSV",
            "PIMU", "PPIMU", "PRIMU", "PINS1", "PINS2", "PGPSP", "PASHR",
            "PSTRB", "POWGPS", "POWTLV"]
IMX_ONLY = ["INFO", "INTEL", "ASCE"]


class CodecTest(unittest.TestCase):
    def test_asce_and_the_reader(self):
        self.assertEqual(nmea.asce(("PINS1", 2), ("PPIMU", 1), ("GNGGA", 1)),
                         b"$ASCE,0,PINS1,2,PPIMU,1,GNGGA,1*16\r\n")
        self.assertEqual(nmea.asce((15, 1)), b"$ASCE,0,15,1*3D\r\n")
        self.assertEqual(nmea.asce(("GNGGA", 1), ("GNRMC", 1), options=nmea.PERSISTENT),
                         b"$ASCE,512,GNGGA,1,GNRMC,1*13\r\n")
        with self.assertRaises(ValueError):
            nmea.asce(*[(7, 1)] * 21)
        r = nmea.SentenceReader()
        good = b"$GNGLL,4019.83468,N,11143.54896,W,152744.000,A*34\r\n"
        stream = isb.stop_all() + good[:10] + b"$GNGLL,1*00\r\n" + good + isb.get_data(1)
        got = []
        for i in range(0, len(stream), 3):
            got += r.feed(stream[i:i + 3])
        self.assertEqual([s.raw for s in got], [good])
        self.assertEqual(got[0].fields[-1], "A")
        self.assertEqual(r.bad, 2)
        self.assertEqual(nmea.ids(["GNGGA", "PINS1", "GSV"]), [7, 4, 15])


class EmulatorTest(unittest.TestCase):
    def test_every_sentence_parses(self):
        args = ["--protocol", "isb", "--speed", "20", "--gps-time", "2026-03-13T15:27:00Z"]
        with imu_emu.Emulator(args) as emu:
            emu.send(isb.get_data(isb.GPS1_POS, 1))
            deadline = time.monotonic() + 30
            while True:
                p = emu.frame(isb.GPS1_POS)
                if isb.decode_set(p.did, p.payload)["status"] != 0:
                    break
                self.assertLess(time.monotonic(), deadline, "no fix")
            emu.send(nmea.STOP_THIS_PORT)
            # GSV masks come with a period; then every ID once, PSTRB on
            # (a strobe), the table read back.
            emu.send(nmea.asce(("GPGSV", 5)))
            emu.send(nmea.asce(*[(i, 0) for i in range(1, 20) if i != 13], (13, 1)))
            emu.send(nmea.ASCE_QUERY)
            s = emu.uart()
            reader = nmea.SentenceReader()
            got = {}
            strobed = False
            end = time.monotonic() + 10
            while time.monotonic() < end and not all(n in got for n in STANDARD + IMX_ONLY):
                # The strobe once the table is set (the reply to the query
                # came: the control socket is another path to the device).
                if "ASCE" in got and not strobed:
                    emu.control().cmd("strobe")
                    strobed = True
                s.settimeout(0.1)
                try:
                    data = s.recv(65536)
                except socket.timeout:
                    continue
                for sen in reader.feed(data):
                    got.setdefault(sen.name, sen)
            emu.send(nmea.STOP_ALL_PORTS)
        self.assertEqual(sorted(n for n in STANDARD + IMX_ONLY if n not in got), [])
        for name in STANDARD:
            msg = pynmea2.parse(got[name].line, check=True)
            self.assertIsNotNone(msg, name)
        gga = pynmea2.parse(got["GNGGA"].line, check=True)
        self.assertEqual((gga.gps_qual, gga.num_sats), (1, "12"))
        # The built-in site: Newlyn, 50.10167° N (docs/motion.md).
        self.assertAlmostEqual(gga.latitude, 50.10167, places=4)
        rmc = pynmea2.parse(got["GNRMC"].line, check=True)
        self.assertEqual(rmc.datestamp.isoformat(), "2026-03-13")
        gsv = pynmea2.parse(got["GPGSV"].line, check=True)
        self.assertEqual(gsv.num_sv_in_view, "12")
        # GSV went to period 0 (once) with the second $ASCE: only PSTRB stays.
        self.assertEqual(got["ASCE"].fields, ["0", "13", "1"])
        self.assertEqual(got["INFO"].fields[6], "Inertial Sense Inc")


if __name__ == "__main__":
    unittest.main()
