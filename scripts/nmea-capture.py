#!/usr/bin/env python3
"""Captures one line of every NMEA sentence of the emulated IMX-5, as listed
in docs/isb.md "Every sentence, captured from the emulator".

Usage: scripts/nmea-capture.py [path/to/imu-emu]

Runs the binary (--protocol isb over TCP, --gps-time 2026-03-13T15:27:00Z,
--speed 20, seed 0), streams GPGSV at period 5 from power-on, and after 54
of its groups (its source, GPS1_SAT, is 1 s: about 300 s of device time)
asks for every ID once with PSTRB on, reads the table back and strobes;
prints each sentence's first line in the order received (GSV's three lines
as they came).
"""
import os
import re
import socket
import subprocess
import sys
import time


def sentence(body):
    s = 0
    for b in body.encode():
        s ^= b
    return f"${body}*{s:02X}\r\n".encode()


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def main():
    exe = sys.argv[1] if len(sys.argv) > 1 else "target/release/imu-emu"
    port, ctl = free_port(), free_port()
    emu = subprocess.Popen(
        [exe, "--protocol", "isb", "--tcp", f"127.0.0.1:{port}", "--control",
         f"127.0.0.1:{ctl}", "--gps-time", "2026-03-13T15:27:00Z", "--speed", "20",
         "--seed", "0"],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        for line in emu.stdout:
            if line.startswith("listening"):
                break
        c = socket.create_connection(("127.0.0.1", port))
        # After the one-shots nothing streams: reads time out, and end.
        c.settimeout(1.0)
        c.sendall(sentence("ASCE,0,GPGSV,5"))
        buf, first, asked, done = b"", {}, False, None
        deadline = time.time() + 600
        while time.time() < deadline:
            try:
                buf += c.recv(65536)
            except socket.timeout:
                if done:
                    break
                continue
            while b"\n" in buf:
                raw, buf = buf.split(b"\n", 1)
                i = raw.find(b"$")
                if i < 0:
                    continue
                text = raw[i:].decode("ascii", "replace").rstrip("\r")
                if not re.match(r"^\$[A-Z]+.*\*[0-9A-F]{2}$", text):
                    continue
                name = text[1:].split(",")[0].split("*")[0]
                if name == "GPGSV" and not asked:
                    # GSV carries no time: its groups are counted.
                    first.setdefault("_gsv_seconds", 0)
                    if text.startswith("$GPGSV,3,1,") or text.startswith("$GPGSV,1,1,"):
                        first["_gsv_seconds"] += 1
                    if first["_gsv_seconds"] >= 54:
                        ids = ",".join(f"{i},0" for i in [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12,
                                                          14, 15, 16, 17, 18, 19])
                        c.sendall(sentence(f"ASCE,0,{ids},13,1"))
                        c.sendall(b"$ASCE*14\r\n")
                        asked = True
                        done = time.time() + 3
                        first = {}
                    continue
                if asked:
                    if name == "ASCE" and "strobed" not in first:
                        first["strobed"] = True
                        with socket.create_connection(("127.0.0.1", ctl)) as k:
                            k.sendall(b"strobe\n")
                            k.recv(4096)
                    if name == "GPGSV":
                        first.setdefault(name, [])
                        if len(first[name]) < 3:
                            first[name].append(text)
                    elif name not in first:
                        first[name] = text
            if done and time.time() > done:
                break
        for k, v in first.items():
            if k == "strobed":
                continue
            for line in (v if isinstance(v, list) else [v]):
                print(line)
    finally:
        emu.terminate()
        emu.wait()


if __name__ == "__main__":
    main()
