#!/usr/bin/env python3
"""Writes the seed corpora of the fuzz targets into fuzz/corpus/<target>/.

Seeds come from the golden vectors (the ICD's and the ISB page's hex
strings, `vectors.txt`: pass its path, default tests/data/vectors.txt) and from small scripted sessions in the `device` and `store`
targets' script formats (see fuzz/src/lib.rs). Rerun after changing a
script format; the files are committed so a fresh clone fuzzes from them.
"""
import os
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_VECTORS = [
    os.path.join(HERE, "..", "tests", "data", "vectors.txt"),
]


def vectors(path):
    kernel, isb, in_isb = [], [], False
    for line in open(path):
        if line.startswith("# ISB"):
            in_isb = True
        if line.startswith("#") or not line.strip():
            continue
        meaning, hexs = line.split("|", 1)
        b = bytes(int(h, 16) for h in hexs.split())
        (isb if in_isb else kernel).append(b)
    return kernel, isb


def write(target, name, data):
    d = os.path.join(HERE, "corpus", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def frame(payload):
    body = bytes([0, 0]) + struct.pack("<H", len(payload) + 6) + payload
    return b"\xaa\x55" + body + struct.pack("<H", sum(body) & 0xFFFF)


# device script ops (fuzz/src/lib.rs `device`)
def rx(b):
    assert len(b) < 64
    return bytes([0, len(b)]) + b


def cmd(payload):
    return bytes([1, len(payload)]) + payload


CODES = [0x33, 0x8F, 0x9B, 0xA5, 0xA6, 0x82, 0x81, 0x95, 0xFE, 0x12, 0x1A, 0x96, 0x97, 0xC2, 0x41]


def code(c):
    return bytes([3, CODES.index(c)])


def save(i):
    return bytes([4, i])


def ticks(n8):
    return bytes([5, n8])


def pin(t):
    return bytes([6, t])


def cycle(boot=0):
    return bytes([7, boot])


def cut(k, seed, i):
    return bytes([8]) + struct.pack("<HIB", k, seed, i)


def read(n):
    return bytes([9]) + struct.pack("<H", n)


def udd(types):
    return bytes([10, len(types)]) + bytes(types)


def idle():
    return bytes([11])


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else next(p for p in DEFAULT_VECTORS if os.path.exists(p))
    kernel, isb = vectors(path)
    seed = struct.pack("<I", 0x2545F491)
    for i, v in enumerate(kernel):
        write("kernel_frame", f"vector-{i:02}", seed + v)
    write("kernel_frame", "all-vectors", seed + b"".join(kernel))
    write("kernel_frame", "vectors-with-junk", seed + b"\x00\xaa".join(kernel))
    for i, v in enumerate(isb):
        write("isb_packet", f"vector-{i:02}", seed + v)
    write("isb_packet", "all-vectors", seed + b"".join(isb))

    # device: every command vector as a session on each of three models
    for m, model in enumerate([0, 1, 2]):
        for i, v in enumerate(kernel):
            if v[2] != 0 or len(v) >= 64:
                continue
            write("device", f"m{model}-vector-{i:02}", bytes([model, 7]) + rx(v) + ticks(50) + read(600) + cycle())
    sessions = {
        "ga-stream": code(0x8F) + ticks(255) + read(300) + code(0xFE) + cycle(),
        "save-cycle-stream": save(0) + cycle() + code(0x8F) + ticks(100) + save(1) + code(0x8F) + ticks(60),
        "udd-config-stream": udd([0x02, 0x21, 0x53]) + code(0x97) + save(3) + code(0x95) + ticks(200) + cycle(),
        "udd-refused": udd([0x02, 0x77, 0x2F]) + udd([]) + udd([0x21] * 17) + code(0x97),
        "cut-save": save(0) + cut(200, 0x1234, 1) + cut(389, 0x55, 2) + cut(0, 9, 0) + code(0x8F) + ticks(20),
        "baud-2m-commit": save(4) + code(0xC2) + save(2) + code(0x8F) + ticks(40) + read(100) + cycle(),
        "autostart": save(6) + cycle() + ticks(30) + save(7) + cycle() + ticks(30),
        "boot-update": cycle(1) + rx(frame(b"\x1a")) + ticks(10) + cycle(2) + cycle(0) + rx(frame(b"\x12")),
        "extrig": save(11) + save(3) + code(0x8F) + ticks(5) + pin(1) + pin(3) + pin(1) + pin(3) + ticks(5) + read(400),
        "tov-pps": save(10) + code(0x9B) + pin(2) + ticks(100) + pin(0) + pin(2) + ticks(100),
        "truncated-idle": rx(b"\xaa\x55\x00\x00\x07\x01") + rx(frame(b"\x1a")) + idle() + read(50),
        "k201-formats": code(0x33) + code(0x81) + code(0xA5) + ticks(30),
        "garbage": rx(bytes(range(0xA0, 0xDF))) + rx(b"\xaa\x55" * 20) + cmd(b"\xb2\xff\x12\x00\x02\x00\xc8\x00"),
        "get-info-bit": code(0x12) + code(0x1a) + code(0x41) + read(10) + read(200),
    }
    for name, body in sessions.items():
        for model in (0, 1, 2):
            write("device", f"m{model}-{name}", bytes([model, 1]) + body)

    # store: op byte (bit 0: which store, bits 1..3: bytes changed), then
    # (u16 offset, u8 value) per change, u16 cut (low 2 bits: none, half,
    # torn), u32 torn seed
    def op(which, changes, cutv, torn=0):
        b = bytes([which | (len(changes) << 1)])
        for at, v in changes:
            b += struct.pack("<HB", at, v)
        return b + struct.pack("<HI", cutv, torn)

    write("store", "clean-saves", op(0, [(0x12, 200)], 0) + op(1, [(3, 1)], 0) + op(0, [(0x12, 100)], 0))
    write("store", "cuts", op(0, [(0x12, 200)], 0) + op(0, [(0x12, 5)], (100 << 2) | 1) + op(1, [(7, 7)], (40 << 2) | 2, 99))
    write("store", "torn-commit", op(0, [(1, 1)], 0) + op(0, [(2, 2)], (389 << 2) | 3, 1234) + op(0, [(3, 3)], (0 << 2) | 2, 5))

    # feed: u32 chunking seed, then the stream (text rows and binary
    # samples, encoded by the Python helper's imu_emu.feed).
    sys.path.insert(0, os.path.join(HERE, "..", "python"))
    from imu_emu import feed

    seed = b"\x05\x00\x00\x00"
    write("feed", "text_rows", seed + b"time,wx,wy,wz,fx,fy,fz\n0.0,10,0,0,0,0,1\n0.001,10,0,0,0,0,1,25\n")
    write("feed", "binary", seed + feed.encode_sample(0.0, (1, 2, 3), (0, 0, 1))
          + feed.encode_sample(0.0005, (1, 2, 3), (0, 0, 1), temp_c=30, device=2))
    bad = bytearray(feed.encode_sample(0.001, (5, 0, 0), (0, 0, 1)))
    bad[20] ^= 1
    write("feed", "mixed", seed + b"0.0,1,1,1,0,0,1\n0.0001,1" + feed.encode_sample(0.0002, (0, 0, 9), (0, 0, 1))
          + bytes(bad) + b"\ngarbage\n")
    write("feed", "full_state", seed + b"time,lat,lon,height,vn,ve,vd,roll,pitch,yaw\n"
          + b"0.0,45,7,300,10,0,0,0,30,0\n0.01,45.0000009,7,300,10,0,0,0,30,0.1\n"
          + b"0.02,95,7,300,10,0,0,0,30,0.2\n0.03,45,7\n"
          + b"time,lat,lon,height,vn,ve,vd,roll,pitch,yaw,wx,wy,wz,fx,fy,fz,temp\n"
          + b"0.04,45,7,300,10,0,0,0,30,0.4,0,0,10,0,0,-9.8,25\n"
          + b"time,wx,wy,wz,fx,fy,fz\n0.05,1,2,3,0,0,1\n")

    # web_request: the first read's size, then one connection's bytes.
    host = b"Host: 127.0.0.1:8080\r\n"
    write("web_request", "page_and_state", b"\x07GET / HTTP/1.1\r\n" + host + b"\r\n"
          + b"HEAD /app.js HTTP/1.1\r\n" + host + b"\r\n"
          + b"GET /api/state?dev=0&since=3&truth_since=1 HTTP/1.1\r\n" + host
          + b"Connection: close\r\n\r\n")
    write("web_request", "command", b"\x20POST /api/command?dev=0 HTTP/1.1\r\n" + host
          + b"X-Imu-Emu: 1\r\nContent-Length: 10\r\n\r\nfault comm"
          + b"POST /api/command HTTP/1.1\r\n" + host + b"X-Imu-Emu: 1\r\n"
          + b"Content-Length: 4\r\n\r\nhelp")
    write("web_request", "refusals", b"\x03GET /api/devices HTTP/1.1\r\nHost: evil.example\r\n\r\n"
          + b"POST /api/command HTTP/1.1\r\n" + host
          + b"Content-Length: 18446744073709551615\r\n\r\n")
    write("web_request", "http10", b"\x3fGET /api/devices HTTP/1.0\r\n" + host
          + b"Connection: keep-alive\r\n\r\nBREW / HTTP/1.0\r\n\r\n")

    # control_line: lines as the control socket takes them.
    write("control_line", "commands", b"help\nstatus\npps\nextrig high\npower-cycle boot=low\n"
          b"fault gps off\nfault temperature 85.5\nmotion rotate 1 2 3\n"
          b"link drop 0.5 tx\nlink noise 10\nlink stall 100\ntruth\ndevices\n")
    write("control_line", "addressed", b"dev 0 status\ndev 3 motion static 45 90\ndev 01 pps\n"
          b"dev +1 pps\ndev 2 help\ndev\n dev  1   link   clear \n")
    write("control_line", "scripts", b"motion script start 45 7 300 0; hold 10; turn 90 20\n"
          b"motion file /tmp/x.csv\nfault temperature nan\nlink drop 2\n")


if __name__ == "__main__":
    main()
