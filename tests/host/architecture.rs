//! ARCHITECTURE.md's import rules for the host crates, checked against
//! their code: the tools (`boards/host/tools`), the runner
//! (`boards/host/runner`) and the program (`boards/host`). Each file's
//! code — without comments (an intra-doc link is not an import) and
//! without `#[cfg(test)] mod` blocks (a unit test may drive any protocol) —
//! is read for the paths it names: `crate::` roots give each crate's
//! module graph, `imu_emu_*` the crates it reaches.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// One host crate's code: root module → the code of its files.
struct Crate {
    name: &'static str,
    modules: BTreeMap<String, String>,
}

/// Root module → the other root modules of its crate its code names.
type Graph = BTreeMap<String, BTreeSet<String>>;

#[path = "../common/rs_files.rs"]
mod rs_files;
use rs_files::rs_files;

/// Cuts the `{ … }` block that opens at or after `at` (with what precedes
/// it from `at`).
fn cut_block(code: &mut String, at: usize) {
    let Some(open) = code[at..].find('{').map(|i| at + i) else {
        code.truncate(at);
        return;
    };
    let mut depth = 0usize;
    let mut end = code.len();
    for (i, c) in code[open..].char_indices() {
        if c == '{' {
            depth += 1;
        } else if c == '}' {
            depth -= 1;
            if depth == 0 {
                end = open + i + 1;
                break;
            }
        }
    }
    code.replace_range(at..end, "");
}

/// `text` without comments and `#[cfg(test)] mod` blocks.
fn code_of(text: &str) -> String {
    let mut code: String = text
        .lines()
        .map(|l| match l.find("//") {
            Some(i) if !l[..i].contains('"') => &l[..i],
            _ => l,
        })
        .flat_map(|l| [l, "\n"])
        .collect();
    let mut from = 0;
    while let Some(i) = code[from..].find("#[cfg(test)]") {
        let at = from + i;
        let after = code[at + "#[cfg(test)]".len()..].trim_start();
        if after.starts_with("mod ") || after.starts_with("pub mod ") {
            cut_block(&mut code, at);
        } else {
            from = at + 1;
        }
    }
    code
}

/// The identifiers that follow `prefix` in `code` (`crate::{a, b::c}`
/// gives `a` and `b`).
fn names_after(code: &str, prefix: &str) -> BTreeSet<String> {
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    let mut out = BTreeSet::new();
    for (i, _) in code.match_indices(prefix) {
        let rest = &code[i + prefix.len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 1usize;
            let mut at_item = true;
            for (k, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 1 => break,
                    '}' => depth -= 1,
                    ',' if depth == 1 => at_item = true,
                    c if at_item && depth == 1 && (c.is_ascii_alphabetic() || c == '_') => {
                        out.insert(ident(&group[k..]));
                        at_item = false;
                    }
                    _ => {}
                }
            }
        } else {
            let id = ident(rest);
            if !id.is_empty() && !rest[id.len()..].starts_with('!') {
                out.insert(id);
            }
        }
    }
    out
}

/// The crate at `dir` (relative to `boards/host`): its root modules
/// (`lib.rs` and `main.rs` are the crate's own) and their code.
fn read(name: &'static str, dir: &str) -> Crate {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir).join("src");
    let mut files = Vec::new();
    rs_files(&src, &mut files);
    let mut modules = BTreeMap::<String, String>::new();
    for f in files {
        let rel = f.strip_prefix(&src).unwrap();
        let first = rel.components().next().unwrap().as_os_str();
        let module = first.to_str().unwrap().trim_end_matches(".rs").to_owned();
        let text = std::fs::read_to_string(&f).unwrap();
        modules.entry(module).or_default().push_str(&code_of(&text));
    }
    assert!(modules.len() >= 3, "{name}: {} modules read", modules.len());
    Crate { name, modules }
}

fn crates() -> [Crate; 3] {
    [
        read("imu_emu_tools", "tools"),
        read("imu_emu_runner", "runner"),
        read("imu_emu_host", "."),
    ]
}

fn graph(c: &Crate) -> Graph {
    let mut g = Graph::new();
    for (m, code) in &c.modules {
        let edges = g.entry(m.clone()).or_default();
        for n in names_after(code, "crate::") {
            assert!(
                c.modules.contains_key(&n),
                "{}::{m}: crate::{n} is no root module",
                c.name
            );
            if n != *m {
                edges.insert(n);
            }
        }
    }
    g
}

/// The first import circle of `g`, if any.
fn circle(g: &Graph) -> Option<Vec<String>> {
    fn visit(m: &str, g: &Graph, done: &mut BTreeSet<String>, path: &mut Vec<String>) -> bool {
        if let Some(from) = path.iter().position(|p| p == m) {
            path.drain(..from);
            path.push(m.to_owned());
            return true;
        }
        if done.contains(m) {
            return false;
        }
        path.push(m.to_owned());
        for n in g.get(m).into_iter().flatten() {
            if visit(n, g, done, path) {
                return true;
            }
        }
        path.pop();
        done.insert(m.to_owned());
        false
    }
    let mut done = BTreeSet::new();
    for m in g.keys() {
        let mut path = Vec::new();
        if visit(m, g, &mut done, &mut path) {
            return Some(path);
        }
    }
    None
}

/// The modules of `c` whose code contains `needle`.
fn naming(c: &Crate, needle: &str) -> BTreeSet<String> {
    c.modules
        .iter()
        .filter(|(_, code)| code.contains(needle))
        .map(|(m, _)| m.clone())
        .collect()
}

fn set(names: &[&str]) -> BTreeSet<String> {
    names.iter().map(|s| (*s).to_owned()).collect()
}

#[test]
fn the_reader_sees_the_imports_there_are() {
    let grouped = names_after("use crate::{a::b, c::{d, e}, f};\ncrate::g!(x);", "crate::");
    assert_eq!(grouped, set(&["a", "c", "f"]));
    let code = code_of("use crate::a; // crate::b\n#[cfg(test)]\nmod tests { use crate::c; }\n");
    assert_eq!(names_after(&code, "crate::"), set(&["a"]));
    // Edges the code has for certain.
    let [tools, runner, host] = crates();
    assert!(graph(&tools)["client"].contains("protocol"));
    assert!(graph(&runner)["runner"].contains("protocol"));
    assert!(graph(&runner)["fleet"].contains("runner"));
    assert!(names_after(&host.modules["cli"], "imu_emu_runner::").contains("fleet"));
}

/// The tools build on the core only; the runner on the core and the
/// tools; the program on all three.
#[test]
fn the_crates_point_one_way() {
    let [tools, runner, host] = crates();
    for (c, may_not) in [
        (&tools, &["imu_emu_runner", "imu_emu_host"][..]),
        (&runner, &["imu_emu_host"][..]),
    ] {
        for other in may_not {
            let bad = naming(c, &format!("{other}::"));
            assert!(bad.is_empty(), "{} names {other} in {bad:?}", c.name);
        }
    }
    assert!(!naming(&host, "imu_emu_tools::").is_empty());
    for (dir, may_not) in [
        ("tools", &["imu-emu-runner", "imu-emu-host"][..]),
        ("runner", &["imu-emu-host"][..]),
    ] {
        let toml = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(dir)
            .join("Cargo.toml");
        let toml = std::fs::read_to_string(toml).unwrap();
        for other in may_not {
            let dep = toml
                .lines()
                .any(|l| l.trim_start().starts_with(&format!("{other} ")));
            assert!(!dep, "{dir}/Cargo.toml depends on {other}");
        }
    }
}

#[test]
fn no_import_circle_in_a_host_crate() {
    for c in crates() {
        if let Some(path) = circle(&graph(&c)) {
            panic!("{}: import circle {path:?}", c.name);
        }
    }
    let mut g = Graph::new();
    g.entry("a".into()).or_default().insert("b".into());
    g.entry("b".into()).or_default().insert("a".into());
    assert_eq!(circle(&g), Some(vec!["a".into(), "b".into(), "a".into()]));
}

/// The protocol choice and the usage error are the lowest modules of the
/// tools, below everything that uses them.
#[test]
fn the_protocol_choice_and_the_usage_error_import_nothing() {
    let [tools, ..] = crates();
    let g = graph(&tools);
    for m in ["protocol", "error"] {
        assert!(g[m].is_empty(), "tools::{m} imports {:?}", g[m]);
    }
    let [_, runner, _] = crates();
    assert!(graph(&runner)["error"].is_empty());
}

/// What differs between the protocols is `runner::protocol::HostProtocol`:
/// the rest of the runner matches on no protocol and names none of the
/// core's — only the protocols' own pieces do (the KERNEL's monitor, the
/// live decoders), the in-process virtual KERNEL and the units `allan`
/// runs in process; the program turns the choice into a type in `cli` only.
#[test]
fn one_trait_holds_what_differs_between_the_protocols() {
    let [_, runner, host] = crates();
    assert_eq!(naming(&runner, "Protocol::"), set(&["protocol"]));
    assert_eq!(naming(&host, "Protocol::"), set(&["cli"]));
    let per_protocol = set(&["protocol", "monitor", "web", "virtual_device", "unit"]);
    for needle in ["imu_emu::kernel", "imu_emu::isb"] {
        let named = naming(&runner, needle);
        let bad: Vec<_> = named.difference(&per_protocol).collect();
        assert!(bad.is_empty(), "{bad:?} name {needle}");
    }
    // In `web`, only its live decoders name a protocol.
    let web =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("runner/src/web.rs"))
            .unwrap();
    let web = code_of(&web);
    assert!(!web.contains("imu_emu::kernel") && !web.contains("imu_emu::isb"));
}

/// The code of each file of the crate at `dir` (relative to
/// `boards/host`), by its path below `src/`.
fn files(dir: &str) -> BTreeMap<String, String> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir).join("src");
    let mut paths = Vec::new();
    rs_files(&src, &mut paths);
    paths
        .iter()
        .map(|f| {
            let rel = f.strip_prefix(&src).unwrap().to_str().unwrap();
            let text = std::fs::read_to_string(f).unwrap();
            (rel.replace('\\', "/"), code_of(&text))
        })
        .collect()
}

/// Expands the use tree at the start of `rest` under `prefix` into `out`
/// (`a::{b, c::{self, D}}` gives `a::b`, `a::c` and `a::c::D`).
fn use_tree(rest: &str, prefix: &str, out: &mut BTreeSet<String>) {
    let rest = rest.trim_start();
    if let Some(group) = rest.strip_prefix('{') {
        let mut depth = 0usize;
        let mut start = 0;
        for (k, c) in group.char_indices() {
            let end = match c {
                '{' => {
                    depth += 1;
                    false
                }
                '}' if depth == 0 => true,
                '}' => {
                    depth -= 1;
                    false
                }
                ',' => depth == 0,
                _ => false,
            };
            if end {
                let item = &group[start..k];
                if !item.trim().is_empty() {
                    use_tree(item, prefix, out);
                }
                start = k + 1;
                if c == '}' {
                    return;
                }
            }
        }
        return;
    }
    let id: String = rest
        .chars()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
        .collect();
    if id == "self" || id.is_empty() {
        // `x::{self}`, or `x::<T>` (turbofish): the path so far.
        if !prefix.is_empty() {
            out.insert(prefix.to_owned());
        }
        return;
    }
    let path = if prefix.is_empty() {
        id.clone()
    } else {
        format!("{prefix}::{id}")
    };
    match rest[id.len()..].strip_prefix("::") {
        Some(next) => use_tree(next, &path, out),
        None => {
            out.insert(path);
        }
    }
}

/// Every path below the crate `krate` that `code` names (in `use` lines
/// and in place), without the crate's name.
fn paths_of(code: &str, krate: &str) -> BTreeSet<String> {
    let root = format!("{krate}::");
    let mut out = BTreeSet::new();
    for (i, _) in code.match_indices(&root) {
        let before = code[..i].chars().next_back();
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_') {
            continue;
        }
        use_tree(&code[i + root.len()..], "", &mut out);
    }
    out
}

/// What of the core the tools may name: each protocol's codec façade
/// (framing, commands, parameters, decoding, its units), the scanner both
/// decoders implement, the unit model a codec's scales come from, the
/// sensor profile declaration a profile file reads, and g. Not the
/// device, the personalities, the chain, the clock or the flash: a unit
/// run in process is the runner's.
const TOOLS_FACADE: &[&str] = &[
    "kernel::command",
    "kernel::decode",
    "kernel::formats",
    "kernel::frame",
    "kernel::model",
    "kernel::params",
    "kernel::rate",
    "kernel::Field",
    "kernel::Scales",
    "kernel::Value",
    "kernel::Capability",
    "kernel::ProductError",
    "kernel::MODELS",
    "isb::did",
    "isb::layout",
    "isb::message",
    "isb::nmea",
    "isb::packet",
    "isb::sets",
    "isb::IMX5",
    "framing",
    "model::Product",
    "model::Model",
    "sensor::profile",
    "sensor::profiles",
    "G",
];

/// The paths of `paths` under none of `allowed`.
fn outside<'a>(paths: &'a BTreeSet<String>, allowed: &[&str]) -> Vec<&'a String> {
    paths
        .iter()
        .filter(|p| {
            !allowed
                .iter()
                .any(|a| p.as_str() == *a || p.starts_with(&format!("{a}::")))
        })
        .collect()
}

/// The tools name only the core's codec façades ([`TOOLS_FACADE`]).
#[test]
fn the_tools_name_only_the_cores_codec_facades() {
    let got = paths_of(
        "use imu_emu::isb::{did, layout::{self, Kind},\n sets};\nlet d = \
         imu_emu::kernel::frame::Decoder::<9>::new(); use imu_emu_tools::x;",
        "imu_emu",
    );
    assert_eq!(
        got,
        set(&[
            "isb::did",
            "isb::layout",
            "isb::layout::Kind",
            "isb::sets",
            "kernel::frame::Decoder"
        ])
    );
    let bad = set(&[
        "device::Device",
        "kernel::Kernel",
        "time::Instant",
        "SignalChain",
    ]);
    assert_eq!(outside(&bad, TOOLS_FACADE).len(), 4);
    let mut seen = BTreeSet::new();
    for (file, code) in files("tools") {
        let paths = paths_of(&code, "imu_emu");
        let bad = outside(&paths, TOOLS_FACADE);
        assert!(bad.is_empty(), "tools/src/{file} names imu_emu::{bad:?}");
        seen.extend(paths);
    }
    // Paths the tools name for certain (the reader reads them).
    for p in [
        "kernel::frame::Decoder",
        "isb::packet",
        "sensor::profile::SensorProfile",
    ] {
        assert!(seen.contains(p), "{p} not seen in {seen:?}");
    }
}

/// What differs between the protocols on the tools' side is
/// `client::tool_protocol::ToolProtocol`: only the choice itself
/// (`protocol.rs`) and the one place that turns it into a protocol's tools
/// (`client/tool_protocol.rs`) name a protocol's value.
#[test]
fn the_tools_name_a_protocol_only_where_it_is_chosen() {
    let mut naming = BTreeSet::new();
    for (file, code) in files("tools") {
        if ["Protocol::Kernel", "Protocol::Isb"]
            .iter()
            .any(|v| code.contains(v))
        {
            naming.insert(file);
        }
    }
    assert_eq!(naming, set(&["client/tool_protocol.rs", "protocol.rs"]));
}
