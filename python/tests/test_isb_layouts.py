"""The committed copies of the ISB layouts (``imu_emu/isb_layouts.py`` and
the generated part of ``docs/isb-data-sets.md``) are what the program's
own declarations give (``imu-emu isb-layouts --json``)."""

import importlib.util
import json
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

import imu_emu

ROOT = Path(__file__).resolve().parents[2]


def _generator():
    spec = importlib.util.spec_from_file_location("isb_layouts_script", ROOT / "scripts" / "isb-layouts.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


class LayoutsTest(unittest.TestCase):
    def test_committed_copies_match_the_dump(self):
        gen = _generator()
        layouts = gen.dump(imu_emu.find_binary())
        self.assertEqual(
            (ROOT / "python" / "imu_emu" / "isb_layouts.py").read_text(encoding="utf-8"),
            gen.render_python(layouts),
            "python/imu_emu/isb_layouts.py is stale: run scripts/isb-layouts.py",
        )
        docs = (ROOT / "docs" / "isb-data-sets.md").read_text(encoding="utf-8")
        self.assertEqual(
            docs, gen.render_docs(layouts, docs), "docs/isb-data-sets.md is stale: run scripts/isb-layouts.py"
        )

    def test_the_notes_offsets_are_the_declarations(self):
        # The docs' hand-written notes describe whole structs; where they
        # give a field the declaration names, the offsets agree.
        gen = _generator()
        layouts = gen.dump(imu_emu.find_binary())
        docs = (ROOT / "docs" / "isb-data-sets.md").read_text(encoding="utf-8")
        noted = gen.note_offsets(layouts, docs)
        self.assertGreaterEqual(len(noted), 20)
        self.assertEqual([n for n in noted if n[2] != n[3]], [])

    def test_the_installed_table_is_the_dump(self):
        # What the package decodes with (installed or from the clone).
        layouts = _generator().dump(imu_emu.find_binary())
        from imu_emu import isb, isb_layouts

        self.assertEqual(
            {s["did"]: (s["name"], s["struct"], s["size"], tuple((f["name"], f["offset"], f["kind"], f["unit"]) for f in s["fields"])) for s in layouts["data_sets"]},
            isb_layouts.LAYOUTS,
        )
        self.assertEqual(isb.SETS[isb.FLASH_CONFIG][2][4], ("startupNavDtMs", 16, "u32"))

    def test_device_time_is_the_binarys(self):
        from imu_emu import isb

        with imu_emu.Emulator(["--protocol", "isb"]) as emu:
            raw = b""
            for d in sorted(set(isb.SETS) - {isb.SYS_CMD}):
                emu.send(isb.get_data(d))
                raw += emu.frame(d).raw
        with tempfile.NamedTemporaryFile(suffix=".bin") as f:
            f.write(raw)
            f.flush()
            out = subprocess.run(
                [imu_emu.find_binary(), "client", "--protocol", "isb", "decode", f.name, "--to", "json"],
                check=True, capture_output=True, text=True,
            ).stdout
        rows = [json.loads(line) for line in out.splitlines()]
        packets = [p for p in isb.PacketReader().feed(raw) if p.whole_set() is not None]
        self.assertEqual(len(rows), len(packets))
        timed = 0
        for p, r in zip(packets, rows):
            t = isb.device_time(p.did, p.payload)
            if t is None:
                self.assertNotIn("device_time_s", r, p.did)
            else:
                timed += 1
                self.assertAlmostEqual(t, r["device_time_s"], places=6, msg=str(p.did))
        self.assertEqual(timed, 22)


if __name__ == "__main__":
    sys.exit(unittest.main())
