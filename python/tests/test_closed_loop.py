"""A closed loop through the emulator (the live motion feed), and the example of it.

A rigid body turns about its z axis (inertia 1, so the torque is the
angular acceleration); an attitude controller sees it only through the
emulated KERNEL: it reads GA frames over TCP with the helper's decoder,
calibrates the gyro's bias while the body is still (the first 2.5 s, the
unit's alignment), integrates the z rate into a heading estimate, and
commands a torque (PD) towards a set-point. The simulation integrates the body and sends
what a perfect IMU on it measures back through the feed in lockstep
(``--lockstep --speed max``): device time advances to each sample's time,
so the loop runs as fast as the simulation and two runs with one seed give
the same bytes.

Run as a script to print the trace: ``python3 python/tests/test_closed_loop.py -v``.
"""

import sys
import time
import unittest
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import imu_emu  # noqa: E402
from imu_emu import kernel  # noqa: E402

GA = 0x8F
#: Simulation and control step, s (the GA stream's default 100 Hz).
DT = 0.01
#: GA frames are at most this old when used: a 38-byte frame takes 3.3 ms
#: at 115 200 bit/s, so one stamped 5 ms before the device's time is whole.
MARGIN_S = 0.005
SET_POINT_DEG = 30.0
KP, KD = 4.0, 4.0
SECONDS = 10.0
#: Samples at rest before the controller starts: the KERNEL's initial
#: alignment (Initial_Alignment_Time, 2 s by default) estimates the gyro
#: bias from them, as a real unit must be still while it aligns.
WARM_UP = 250


def closed_loop(seed):
    """Runs the loop; the true heading and rate at the end, the heading
    estimate, and every UART byte received."""
    with imu_emu.FeedEmulator(["--seed", str(seed)], lockstep=True) as emu:
        emu.command_at_start(imu_emu.start("GA"))
        theta, omega = 0.0, 0.0  # true heading (deg) and rate (deg/s)
        estimate, rate, bias = 0.0, 0.0, 0.0  # the controller's, from GA frames
        first = last = None  # 2 kHz counters (unwrapped)
        pending = []  # GA payloads received, not yet used

        def read_until(done):
            def more(frames):
                pending.extend(kernel.decode_ga(f.payload) for f in frames[len(seen):]
                               if f.ident == GA and len(f.payload) == 32)
                seen[:] = frames
                return done()
            seen = []
            emu.wait_frames(more)

        steps = int(round(SECONDS / DT))
        for k in range(steps + 1):
            t = k * DT
            emu.feed(t, (0.0, 0.0, omega))
            u = 0.0
            if k >= WARM_UP:
                if first is None:
                    # At rest so far: the gyro's bias is the mean of what
                    # it read (a real unit's turn-on bias; the controller
                    # calibrates it out, as a flight controller does).
                    read_until(lambda: pending)
                    first = pending[0]["counter"]
                    target = _target(t, first)
                    read_until(lambda: _unwrap(pending[-1]["counter"], first) >= target)
                    still = [g for g in pending if _unwrap(g["counter"], first) <= target]
                    bias = sum(g["gyro"][2] for g in still) / len(still)
                    del pending[: len(still)]
                    last = target
                target = _target(t, first)
                read_until(lambda: pending and _unwrap(pending[-1]["counter"], last) >= target)
                # Every frame up to the target, in order.
                while pending and _unwrap(pending[0]["counter"], last) <= target:
                    g = pending.pop(0)
                    c = _unwrap(g["counter"], last)
                    rate = g["gyro"][2] - bias
                    estimate += rate * (c - last) / 2000.0
                    last = c
                u = KP * (SET_POINT_DEG - estimate) - KD * rate
            # The body over the next step (semi-implicit Euler).
            omega += u * DT
            theta += omega * DT
        # Device time stays at the last sample: let the line empty.
        emu.step((steps + 1) * DT, (0.0, 0.0, omega))
        emu.wait_frames(lambda _f, end=_after(0.3): _now() > end, timeout=1.0)
        return theta, omega, estimate, bytes(emu.received)


def _now():
    return time.monotonic()


def _after(s):
    return time.monotonic() + s


def _unwrap(counter, near):
    """A 16-bit counter as the value closest to ``near``."""
    return near + ((counter - near + 32768) % 65536) - 32768


def _target(t, first):
    """The newest frame wholly received once device time is ``t``: frames
    come every 20 counts from ``first``, and one at least MARGIN_S old is
    whole."""
    newest = int(round((t - MARGIN_S) * 2000))
    return first + ((newest - first) // 20) * 20


class ClosedLoopTest(unittest.TestCase):
    def test_the_attitude_settles_and_two_runs_give_the_same_bytes(self):
        theta, omega, estimate, a = closed_loop(seed=5)
        self.assertAlmostEqual(theta, SET_POINT_DEG, delta=0.3)
        self.assertLess(abs(omega), 0.1)
        self.assertAlmostEqual(estimate, theta, delta=0.5)
        self.assertGreater(len(a), 700 * 38)
        _, _, _, b = closed_loop(seed=5)
        self.assertEqual(a, b)


if __name__ == "__main__":
    unittest.main()
