#!/usr/bin/env bash
# The public items of the core crate (src/), counted the way the
# public-API count of ARCHITECTURE.md ("The public API") is: every item
# declared `pub` (not `pub(crate)`, not `pub(super)`) at the start of a
# line, by kind — `fn` (with `const fn`), `const`, `struct`, `enum`,
# `trait`, `type`, `static`, `mod` — outside `#[cfg(test)]` modules;
# `pub` re-exports and struct fields are not counted. With a revision it
# counts that commit's tree (`scripts/api-count.sh 0249634`).
#
# With --public (the working tree only) it also counts the public API:
# those items less the ones rustc's `unreachable_pub` lint finds no path
# to from outside the crate (an item declared `pub` in a crate-private
# module; the `internals` feature, which makes such modules public for the
# crate's own tests, is off), in the default build or, for what only it
# compiles, the fixed-point one; a `data_set!` struct counts as its
# `pub struct X in mod x` line, and an item declared only with
# `#[cfg(feature = "internals")]` is outside the public API. On a tree
# whose modules are all `pub` the two counts are the same.
#
# Usage: scripts/api-count.sh [REV | --public]
set -euo pipefail
cd "$(git rev-parse --show-toplevel)"
exec python3 - "${1:-}" <<'PY'
import json, os, pathlib, re, subprocess, sys
from collections import Counter

public = sys.argv[1] == "--public"
rev = "" if public else sys.argv[1]

def files():
    if rev:
        names = subprocess.run(["git", "ls-tree", "-r", "--name-only", rev, "src"],
                               check=True, capture_output=True, text=True).stdout.split()
        for p in names:
            if p.endswith(".rs"):
                yield subprocess.run(["git", "show", f"{rev}:{p}"], check=True,
                                     capture_output=True, text=True).stdout
    else:
        for p in sorted(pathlib.Path("src").rglob("*.rs")):
            yield p.read_text()

def without_test_modules(text):
    """The text without `#[cfg(test)] mod … { … }` blocks (brace count)."""
    out, skip, depth, pending = [], False, 0, False
    for line in text.split("\n"):
        s = line.strip()
        if skip:
            depth += line.count("{") - line.count("}")
            skip = depth > 0
            continue
        if s.startswith("#[cfg(test)]"):
            pending = True
            continue
        if pending:
            pending = False
            if re.match(r"(pub(\([a-z]+\))? )?mod \w+ *\{", s):
                depth = line.count("{") - line.count("}")
                skip = depth > 0
                continue
            if re.match(r"(pub(\([a-z]+\))? )?mod \w+;", s):
                continue
        out.append(line)
    return "\n".join(out)

ITEM = re.compile(r"^\s*pub ((?:const |unsafe |async )*fn|const|struct|enum|trait|type|static|mod)\b", re.M)
kinds, lines = Counter(), 0
for text in files():
    lines += text.count("\n")
    for m in ITEM.finditer(without_test_modules(text)):
        kinds["fn" if m.group(1).endswith("fn") else m.group(1)] += 1
total = sum(kinds.values())
order = ["fn", "const", "struct", "enum", "trait", "type", "static", "mod"]
print(f"{total} public items ({', '.join(f'{k} {kinds[k]}' for k in order)}); "
      f"{lines} lines, {total * 1000 / lines:.1f} per 1 000 lines")

if public:
    lib = open("src/lib.rs").read()
    anchor = "#![deny(missing_docs)]\n"
    mark = "#![warn(unreachable_pub)] // api-count.sh: removed when it ends\n"
    open("src/lib.rs", "w").write(lib.replace(anchor, anchor + mark, 1))
    try:
        # Both builds: a file only the fixed-point build compiles
        # (`chain/fixed.rs`) is linted only there.
        out = "".join(subprocess.run(["cargo", "check", "-p", "imu-emu", "--lib", "--message-format=json",
                                      "--quiet"] + extra, capture_output=True, text=True).stdout
                      for extra in ([], ["--features", "fixed-point"]))
    finally:
        open("src/lib.rs", "w").write(lib)
    def outermost(sp):
        while sp.get("expansion"):
            sp = sp["expansion"]["span"]
        return sp

    spots = set()  # (file, line) of each `pub` item the public API does not reach
    for line in out.splitlines():
        m = json.loads(line) if line.startswith("{") else {}
        msg = m.get("message") or {}
        if (msg.get("code") or {}).get("code") != "unreachable_pub":
            continue
        for sp in msg["spans"]:
            if not sp["is_primary"]:
                continue
            if not sp.get("expansion"):
                spots.add((sp["file_name"], sp["line_start"], sp["column_start"]))
            elif "pub struct $name" in sp["text"][0]["text"]:
                # A `data_set!` struct: its `pub struct X in mod x` line
                # is the first such line of the invocation.
                call = outermost(sp)
                src = open(call["file_name"]).read().split("\n")
                for i in range(call["line_start"] - 1, len(src)):
                    if re.match(r"\s*pub struct \w+ in mod ", src[i]):
                        spots.add((call["file_name"], i + 1, src[i].index("pub") + 1))
                        break
    # An item that only the `internals` build compiles is outside it too.
    for p in sorted(pathlib.Path("src").rglob("*.rs")):
        src = without_test_modules(p.read_text()).split("\n")
        for i, text in enumerate(src):
            if text.strip() == '#[cfg(feature = "internals")]':
                for j in range(i + 1, min(i + 8, len(src))):
                    if ITEM.match(src[j]):
                        spots.add((str(p), -(j + 1), src[j].index("pub") + 1, src[j]))
                        break
                    if not src[j].strip().startswith(("#[", "///", "//")):
                        break
    hidden = Counter()
    for spot in spots:
        if len(spot) == 4:
            text = spot[3]
        else:
            text = open(spot[0]).read().split("\n")[spot[1] - 1]
        col = spot[2]
        m2 = ITEM.match(text[col - 1:])
        if m2 and text[:col - 1].strip() == "":
            hidden["fn" if m2.group(1).endswith("fn") else m2.group(1)] += 1
    shown = Counter({k: kinds[k] - hidden[k] for k in order})
    n = sum(shown.values())
    print(f"{n} in the public API ({', '.join(f'{k} {shown[k]}' for k in order)}); "
          f"{n * 1000 / lines:.1f} per 1 000 lines; {sum(hidden.values())} pub only "
          "inside the crate (reached by its own tests through `internals`)")
PY
