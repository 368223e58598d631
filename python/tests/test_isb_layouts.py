"""The committed copies of the ISB layouts (``imu_emu/isb_layouts.py`` and
the generated part of ``docs/isb-data-sets.md``) are what the program's
own declarations give (``imu-emu isb-layouts --json``)."""

import importlib.util
import sys
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

    def test_the_installed_table_is_the_dump(self):
        # What the package decodes with (installed or from the clone).
        layouts = _generator().dump(imu_emu.find_binary())
        from imu_emu import isb, isb_layouts

        self.assertEqual(
            {s["did"]: (s["name"], s["struct"], s["size"], tuple((f["name"], f["offset"], f["kind"], f["unit"]) for f in s["fields"])) for s in layouts["data_sets"]},
            isb_layouts.LAYOUTS,
        )
        self.assertEqual(isb.SETS[isb.FLASH_CONFIG][2][4], ("startupNavDtMs", 16, "u32"))


if __name__ == "__main__":
    sys.exit(unittest.main())
