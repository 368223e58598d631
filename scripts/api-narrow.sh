#!/usr/bin/env bash
# Narrows the core crate's `pub` items to `pub(crate)` wherever nothing
# outside the crate needs them: mechanically, so that it can be run again
# after any merge instead of resolving its textual changes by hand.
#
# 1. With `#![warn(unreachable_pub)]` added for the run, `cargo check` of
#    the library without the `internals` feature lists every `pub` item
#    that the public API (lib.rs's public modules and re-exports) does not
#    reach; each of those items' `pub` becomes `pub(crate)`. Struct fields
#    and items a macro expands are left as they are.
# 2. What still needs an item is then checked, and each item an error or
#    warning names is made `pub` again, until nothing changes: the crate's
#    tests and benches and the host's tests and examples (which reach the
#    insides with `internals`), the host runner (without it), the firmware
#    shell's tests, the probes (scripts/v6m-tick, scripts/nav-tick), the
#    fixed-point build, and the dead-code and
#    private-interface lints of the `internals` build (an item left
#    unused, or named by a public signature, stays `pub`).
#
# Usage: scripts/api-narrow.sh   (then scripts/api-count.sh; commit)
# Needs: cargo, python3. Uses $CARGO_TARGET_DIR if set.
set -euo pipefail
cd "$(git rev-parse --show-toplevel)"
exec python3 - <<'PY'
import json, os, re, subprocess, sys

ITEM = re.compile(r"pub\s+(?:(?:const|unsafe|async|extern)\s+)*(fn|const|struct|enum|trait|type|static|mod|use|union)\b")
LIB = "src/lib.rs"
MARK = "#![warn(unreachable_pub)] // api-narrow.sh: removed when it ends\n"

def cargo(args):
    """Runs `cargo check ARGS`; returns the compiler messages (JSON)."""
    p = subprocess.run(["cargo", "check", "--message-format=json", "--quiet"] + args,
                       capture_output=True, text=True)
    out = []
    for line in p.stdout.splitlines():
        try:
            m = json.loads(line)
        except ValueError:
            continue
        if m.get("reason") == "compiler-message":
            out.append(m["message"])
    return out

def local(path):
    """A path in src/ of this repository, or None."""
    path = os.path.relpath(os.path.abspath(path))
    return path if path.startswith("src/") else None

def rewrite(path, line, col, old, new):
    """Replaces `old` with `new` at (line, col) of `path` (1-based)."""
    lines = open(path).read().split("\n")
    text = lines[line - 1]
    i = col - 1
    if text[i:i + len(old)] != old:
        return False
    lines[line - 1] = text[:i] + new + text[i + len(old):]
    open(path, "w").write("\n".join(lines))
    return True

# Step 1: narrow what the public API does not reach.
lib = open(LIB).read()
anchor = "#![deny(missing_docs)]\n"
assert anchor in lib, "lib.rs lost its #![deny(missing_docs)] anchor"
open(LIB, "w").write(lib.replace(anchor, anchor + MARK, 1))
try:
    narrowed = 0
    spans = set()
    # Both builds: `chain/fixed.rs` is compiled only in the fixed-point one.
    for m in cargo(["-p", "imu-emu", "--lib"]) + cargo(["-p", "imu-emu", "--lib", "--features", "fixed-point"]):
        if (m.get("code") or {}).get("code") != "unreachable_pub":
            continue
        for s in m["spans"]:
            if not s["is_primary"] or s.get("expansion"):
                continue
            path = local(s["file_name"])
            if path:
                spans.add((path, s["line_start"], s["column_start"]))
    for path, line, col in sorted(spans, reverse=True):
        text = open(path).read().split("\n")[line - 1]
        if ITEM.match(text[col - 1:]) and rewrite(path, line, col, "pub", "pub(crate)"):
            narrowed += 1
    print(f"api-narrow: {narrowed} items narrowed to pub(crate)", file=sys.stderr)
finally:
    lib = open(LIB).read()
    open(LIB, "w").write(lib.replace(MARK, "", 1))

if os.environ.get("API_NARROW_STEP1_ONLY"):
    sys.exit(0)

# Step 2: make public again what still needs to be.
CHECKS = [
    ["-p", "imu-emu", "--lib", "--features", "internals"],
    ["-p", "imu-emu", "--lib", "--features", "internals,fixed-point"],
    ["-p", "imu-emu", "--lib", "--tests", "--benches"],
    ["-p", "imu-emu", "--lib", "--tests", "--benches", "--features", "fixed-point"],
    ["-p", "imu-emu-host", "--lib", "--bins"],
    ["-p", "imu-emu-host", "--all-targets"],
    ["--manifest-path", "boards/fw-shell/Cargo.toml", "--lib", "--tests"],
    # The probes (bare images, their own workspaces and targets).
    ["--manifest-path", "scripts/v6m-tick/Cargo.toml", "--release", "--target", "thumbv6m-none-eabi"],
    ["--manifest-path", "scripts/nav-tick/Cargo.toml", "--release", "--target", "thumbv7em-none-eabihf"],
    ["--manifest-path", "scripts/nav-tick/Cargo.toml", "--release", "--target", "thumbv6m-none-eabi",
     "--features", "fixed-point"],
]
def definitions(name):
    """(path, line) of each pub(crate) item or re-export named `name`."""
    item = re.compile(r"pub\(crate\)\s+(?:(?:const|unsafe|async)\s+)*"
                      r"(?:fn|const|struct|enum|trait|type|static|mod|union)\s+" + re.escape(name) + r"\b")
    export = re.compile(r"pub\(crate\)\s+use\b[^;]*\b" + re.escape(name) + r"\b")
    for root, _, files in os.walk("src"):
        for f in files:
            if f.endswith(".rs"):
                path = os.path.join(root, f)
                lines = open(path).read().split("\n")
                for i, t in enumerate(lines, 1):
                    # A re-export that is crate-private only without
                    # `internals` (its public twin is the line above it)
                    # stays so.
                    if i > 1 and lines[i - 2].strip() == '#[cfg(not(feature = "internals"))]':
                        continue
                    if item.search(t) or export.search(t):
                        yield path, i

def open_module(path, line, lines):
    """Makes `pub` the pub(crate) module that holds `path`:`line`: an
    inline `mod x {` above it in the file, else the file's own `mod`
    declaration in its parent. Returns 1 if it changed one."""
    indent = len(lines[line - 1]) - len(lines[line - 1].lstrip())
    for l in range(line - 1, 0, -1):
        t = lines[l - 1]
        m = re.match(r"(\s*)pub\(crate\) mod \w+ \{", t)
        if m and len(m.group(1)) < indent:
            lines[l - 1] = t.replace("pub(crate) mod", "pub mod", 1)
            return 1
        if t.strip() and len(t) - len(t.lstrip()) < indent and re.match(r"\s*(pub )?mod \w+ \{", t):
            break
    stem = os.path.splitext(os.path.basename(path))[0]
    folder = os.path.dirname(path)
    if stem == "mod":
        stem, folder = os.path.basename(folder), os.path.dirname(folder)
    for parent in (os.path.join(folder, "mod.rs"), folder + ".rs", os.path.join(folder, "lib.rs")):
        if os.path.exists(parent) and parent != path:
            text = open(parent).read()
            new = re.sub(r"pub\(crate\) mod " + stem + r";", "pub mod " + stem + ";", text, count=1)
            if new != text:
                open(parent, "w").write(new)
                return 1
    return 0

NAMED = re.compile(r"defined here|only usable at visibility|declared here")
for round_ in range(1, 30):
    restored = set()
    for args in CHECKS:
        for m in cargo(args):
            code = (m.get("code") or {}).get("code") or ""
            if m["level"] not in ("error", "warning"):
                continue
            places = []
            if code in ("dead_code",):
                places = [s for s in m["spans"] if s["is_primary"]]
            else:
                for c in m.get("children", []):
                    if NAMED.search(c["message"]) or code in ("E0603", "E0624", "private_interfaces", "private_bounds"):
                        places += c["spans"]
                places += [s for s in m["spans"] if not s["is_primary"] and NAMED.search(s.get("label") or "")]
            for s in places:
                path = local(s["file_name"])
                if path:
                    restored.add((path, s["line_start"]))
            # A re-export of what is now pub(crate) names only the item:
            # every pub(crate) definition or re-export of that name.
            # A glob import no longer brings it: "cannot find value `X`".
            # An item a `facade!` glob re-exports is "private" where the
            # glob is (lib.rs): the item itself is what to open.
            if code in ("E0364", "E0365", "E0412", "E0422", "E0425", "E0433", "E0531", "E0532", "E0603"):
                name = re.search(r"`([^`]+)`", m["message"]).group(1).split("::")[-1]
                for path, line in definitions(name):
                    restored.add((path, line))
    changed = 0
    for path, line in sorted(restored):
        lines = open(path).read().split("\n")
        # The item's `pub(crate)` on its line, or on the line it starts
        # (attributes and docs above a name the span points at).
        for l in range(line, max(line - 3, 0), -1):
            t = lines[l - 1]
            i = t.find("pub(crate)")
            if i >= 0 and ITEM.match("pub" + t[i + len("pub(crate)"):]):
                lines[l - 1] = t[:i] + "pub" + t[i + len("pub(crate)"):]
                changed += 1
                break
        else:
            # Already `pub`: the module around it is what hides it.
            changed += open_module(path, line, lines)
        open(path, "w").write("\n".join(lines))
    print(f"api-narrow: round {round_}: {changed} items public again", file=sys.stderr)
    if changed == 0:
        break
subprocess.run(["cargo", "fmt"], check=True)
PY
