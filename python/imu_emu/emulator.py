"""Start the imu-emu binary and talk to it (UART and control socket)."""

import os
import shutil
import socket
import subprocess
import struct
import threading
import time
import warnings
from pathlib import Path
from typing import Any, List, Optional, Sequence, Union

from .isb import PacketReader
from .kernel import (
    BAUD_RATE,
    BAUD_RATES,
    DATA_RATE,
    READ_RAM,
    SAVE_FLASH,
    FrameReader,
    RateLoweredWarning,
    effective_rate,
    read_ram,
    save_flash,
)

_REPO = Path(__file__).resolve().parents[2]


def find_binary():
    """The ``imu-emu`` binary, looked for in this order: ``$IMU_EMU_BIN``
    (a path, or a name on ``PATH``); ``release/imu-emu`` then ``debug/imu-emu`` under
    ``$CARGO_TARGET_DIR``, the repository's ``target/`` (when the package
    runs from a clone) and ``~/.cache/imu-emu/target`` (where ``.ci/run``
    builds); then ``imu-emu`` on ``PATH``. Raises :class:`FileNotFoundError`
    listing every place it looked."""
    env = os.environ.get("IMU_EMU_BIN")
    if env:
        found = shutil.which(env)
        if found is None:
            raise FileNotFoundError(
                "IMU_EMU_BIN=%s is not an executable file (build one with "
                "`cargo build --release -p imu-emu-host`, or unset IMU_EMU_BIN to look "
                "in the cargo target directories and on PATH)" % env
            )
        return found
    dirs = [os.environ.get("CARGO_TARGET_DIR"), str(_REPO / "target"),
            os.path.expanduser("~/.cache/imu-emu/target")]
    looked = ["$IMU_EMU_BIN (not set)"]
    for d in filter(None, dirs):
        for profile in ("release", "debug"):
            p = Path(d) / profile / "imu-emu"
            looked.append(str(p))
            if p.is_file() and os.access(p, os.X_OK):
                return str(p)
    found = shutil.which("imu-emu")
    if found:
        return found
    looked.append("imu-emu on PATH")
    raise FileNotFoundError(
        "imu-emu binary not found; looked at: %s. Build it (cargo build --release "
        "-p imu-emu-host) or set IMU_EMU_BIN to its path" % ", ".join(looked)
    )


class EmulatorStartError(RuntimeError):
    """``imu-emu`` did not start (a bad option, a port in use, ...):
    :attr:`stderr` is what it said, :attr:`returncode` its exit status."""

    def __init__(self, cmd: Sequence[str], stderr: str, returncode: Optional[int]):
        self.cmd = list(cmd)
        self.stderr = stderr
        self.returncode = returncode
        super().__init__(
            "imu-emu did not start (exit status %s): %s\ncommand: %s"
            % (returncode, stderr.strip() or "(nothing on stderr)", " ".join(self.cmd))
        )


class Control:
    """The control socket: one reply line per command; lines starting with
    ``event `` (TOV edges, ...) are kept in :attr:`events`."""

    def __init__(self, addr, timeout=5.0):
        host, port = addr.rsplit(":", 1)
        self.sock = socket.create_connection((host, int(port)), timeout=timeout)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.file = self.sock.makefile("r", encoding="utf-8", newline="\n")
        self.events = []

    def cmd(self, line):
        """Sends ``line``; returns the reply text after ``ok`` (maybe
        empty); raises :class:`RuntimeError` on ``error ...``."""
        self.sock.sendall(line.encode() + b"\n")
        while True:
            reply = self.file.readline()
            if not reply:
                raise ConnectionError("control socket closed")
            reply = reply.rstrip("\n")
            if reply.startswith("event "):
                self.events.append(reply[len("event "):])
                continue
            if reply == "ok":
                return ""
            if reply.startswith("ok "):
                return reply[3:]
            raise RuntimeError(reply)

    def status(self):
        """``status`` as a dict of strings."""
        return dict(w.split("=", 1) for w in self.cmd("status").split())

    def link(self, *words):
        """A ``link ...`` fault (``link("corrupt", 1, "tx")``)."""
        return self.cmd("link " + " ".join(str(w) for w in words))

    def pps(self):
        """A 1PPS rising edge now."""
        return self.cmd("pps")

    def close(self):
        """Closes the socket."""
        self.file.close()
        self.sock.close()


class Uart:
    """One device's UART over TCP: frames split and checked as they come.
    Connected on first use (a device powers on when its first client
    connects)."""

    def __init__(self, addr: str, timeout: float = 5.0, protocol: str = "kernel"):
        self.addr = addr
        self.timeout = timeout
        self.protocol = protocol
        self._uart: Optional[socket.socket] = None
        self._pending: List[Any] = []
        #: KERNEL frames (:class:`imu_emu.kernel.FrameReader`) or ISB
        #: packets (:class:`imu_emu.isb.PacketReader`, ``protocol="isb"``).
        self.reader: Union[FrameReader, PacketReader] = (
            PacketReader() if protocol == "isb" else FrameReader()
        )

    @property
    def port(self):
        """The UART's TCP port."""
        return int(self.addr.rsplit(":", 1)[1])

    def uart(self):
        """The UART socket (connected on first use: the device powers on)."""
        if self._uart is None:
            host, port = self.addr.rsplit(":", 1)
            self._uart = socket.create_connection((host, int(port)), timeout=self.timeout)
            self._uart.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return self._uart

    def send(self, frame):
        """Sends bytes to the device's UART."""
        self.uart().sendall(frame)

    def frames(self, duration):
        """The frames arriving within ``duration`` seconds."""
        s = self.uart()
        out = []
        end = time.monotonic() + duration
        while True:
            left = end - time.monotonic()
            if left <= 0:
                return out
            s.settimeout(min(left, 0.05))
            try:
                data = s.recv(65536)
            except socket.timeout:
                continue
            if not data:
                return out
            out += self.reader.feed(data)

    def frame(self, ident, timeout=None):
        """The next frame with ``ident`` (others skipped); raises
        :class:`TimeoutError`."""
        end = time.monotonic() + (timeout or self.timeout)
        pending = self._pending
        while True:
            while pending:
                f = pending.pop(0)
                if f.ident == ident:
                    self._pending = pending
                    return f
            left = end - time.monotonic()
            if left <= 0:
                self._pending = pending
                raise TimeoutError("no frame with id 0x%02X" % ident)
            pending = self.frames(min(left, 0.05))

    def request(self, frame, ident, timeout=None):
        """Sends ``frame`` and returns the next frame with ``ident``."""
        self.send(frame)
        return self.frame(ident, timeout)

    def set_data_rate(self, rate, fmt="GA", internal_hz=2000):
        """SaveFlash of Data_Rate ``rate`` (KERNEL); returns the rate a
        stream of ``fmt`` runs at over the device's running line rate
        (Formula 5.1, :func:`imu_emu.kernel.effective_rate`; read with
        ReadRAM Baud_Rate). When the device lowers it, a
        :class:`imu_emu.kernel.RateLoweredWarning` names both rates (as
        ``imu-emu client set Data_Rate`` prints). Raises
        :class:`TimeoutError` if the device does not acknowledge (a value
        it refuses gets no answer, ICD 5.3.7)."""
        self.request(save_flash(DATA_RATE, struct.pack("<H", rate)), SAVE_FLASH)
        code = self.request(read_ram(BAUD_RATE, 1), READ_RAM).payload[0]
        baud = BAUD_RATES[code] if code < len(BAUD_RATES) else BAUD_RATES[0]
        eff = effective_rate(rate, baud, fmt, internal_hz)
        if eff != rate:
            warnings.warn(
                "Data_Rate %d Hz: at %d bit/s the device sends %s at %d Hz (Formula 5.1, "
                "ICD 5.5)" % (rate, baud, fmt, eff),
                RateLoweredWarning,
                stacklevel=2,
            )
        return eff

    def close(self):
        """Closes the UART connection, if open."""
        if getattr(self, "_uart", None) is not None:
            self._uart.close()
            self._uart = None


class _Process:
    """A running ``imu-emu`` whose stdout lines announce its ports."""

    def __init__(self, cmd: Sequence[str], timeout: float):
        self.timeout = timeout
        self.cmd = list(cmd)
        self._control: Optional[Control] = None
        self.stderr_lines: List[str] = []
        self.proc = subprocess.Popen(
            cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
            text=True,
        )
        self._err = threading.Thread(target=self._drain_stderr, daemon=True)
        self._err.start()

    def _drain_stderr(self):
        for line in self.proc.stderr:
            self.stderr_lines.append(line.rstrip("\n"))

    def _line(self, prefix: str) -> str:
        line = self.proc.stdout.readline()
        if not line.startswith(prefix):
            self.stop()
            raise EmulatorStartError(self.cmd, "\n".join(self.stderr_lines), self.proc.returncode)
        return line[len(prefix):].strip()

    def control(self):
        """The :class:`Control` client (connected on first use)."""
        if self._control is None:
            self._control = Control(self.control_addr, self.timeout)
        return self._control

    def _close_uarts(self):
        pass

    def stop(self):
        """Stops the emulator (SIGTERM, then kill)."""
        self._close_uarts()
        if self._control is not None:
            self._control.close()
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        # All of stderr, for the start error's message.
        self._err.join(timeout=2)
        self.proc.stdout.close()
        self.proc.stderr.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()


def options(
    model: Optional[str] = None,
    protocol: Optional[str] = None,
    seed: Optional[int] = None,
    speed: Union[None, str, float] = None,
    args: Sequence[str] = (),
) -> List[str]:
    """The command-line options of these settings (``None``: the default)."""
    out: List[str] = []
    if protocol is not None:
        out += ["--protocol", protocol]
    if model is not None:
        out += ["--model", model]
    if seed is not None:
        out += ["--seed", str(seed)]
    if speed is not None:
        out += ["--speed", str(speed)]
    return out + list(args)


def _protocol_of(args: Sequence[str]) -> str:
    a = list(args)
    for i, w in enumerate(a):
        if w == "--protocol" and i + 1 < len(a):
            return a[i + 1]
        if w.startswith("--protocol="):
            return w.split("=", 1)[1]
    return "kernel"


class Emulator(_Process, Uart):
    """A running ``imu-emu`` on a free loopback port with a control socket.

    Use as a context manager, or call :meth:`stop`. ``args`` are extra
    command-line options (``["--model", "K120", "--seed", "3"]``); with
    ``--protocol isb`` the UART yields ISB packets (:class:`imu_emu.isb.Packet`)
    instead of KERNEL frames. Raises :class:`EmulatorStartError` (with the
    emulator's stderr) when it does not start.
    """

    def __init__(self, args: Sequence[str] = (), binary: Optional[str] = None, timeout: float = 5.0):
        cmd = [binary or find_binary(), "--tcp", "127.0.0.1:0", "--control", "127.0.0.1:0"]
        cmd += list(args)
        _Process.__init__(self, cmd, timeout)
        addr = self._line("listening on tcp ")
        Uart.__init__(self, addr, timeout, _protocol_of(args))
        self.control_addr = self._line("control on tcp ")

    def _close_uarts(self):
        Uart.close(self)


class Fleet(_Process):
    """``count`` devices in one ``imu-emu --count N`` on free loopback
    ports, with one control socket: :attr:`devices` ``[k]`` is device k's
    :class:`Uart`; :meth:`dev` sends a control command to device k.

    ``args`` are extra options for every device (``["--seed", "3"]``:
    device k's seed is 3 + k; ``["--flash", path]``: device k keeps its
    flash in ``path.k``).
    """

    def __init__(self, count: int, args: Sequence[str] = (), binary: Optional[str] = None, timeout: float = 5.0):
        cmd = [binary or find_binary(), "--count", str(count), "--tcp", "127.0.0.1:0",
               "--control", "127.0.0.1:0"]
        cmd += list(args)
        _Process.__init__(self, cmd, timeout)
        self.devices: List[Uart] = []
        protocol = _protocol_of(args)
        self.devices = [Uart(self._line("listening on tcp "), timeout, protocol) for _ in range(count)]
        self.control_addr = self._line("control on tcp ")

    def dev(self, k, *words):
        """A control command for device ``k`` (``dev(2, "fault", "comm",
        "on")``); the reply text after ``ok``."""
        return self.control().cmd("dev %d %s" % (k, " ".join(str(w) for w in words)))

    def status(self, k):
        """Device ``k``'s ``status`` as a dict of strings."""
        return dict(w.split("=", 1) for w in self.dev(k, "status").split())

    def _close_uarts(self):
        for d in getattr(self, "devices", []):
            d.close()
