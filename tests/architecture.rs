//! ARCHITECTURE.md's import rules for the core, checked against the code:
//! every `crate::` path of `src/` (in `use` lines and in place, outside
//! comments and `#[cfg(test)] mod` blocks) names the root module it
//! reaches, and the rules below are read off that graph. Unit tests may
//! drive a real personality (the schedule's tests run a KERNEL), so test
//! modules are not part of the graph.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Root module → the other root modules its code names.
type Graph = BTreeMap<String, BTreeSet<String>>;

/// The personalities: a module of their own each, above the shell.
const PERSONALITIES: &[&str] = &["kernel", "isb"];

#[path = "common/rs_files.rs"]
mod rs_files;
use rs_files::rs_files;

/// The source without line comments (doc comments included: an intra-doc
/// link is not an import) and without `#[cfg(test)] mod … { … }` blocks.
fn code_of(text: &str) -> String {
    let mut code = String::new();
    for line in text.lines() {
        let line = match line.find("//") {
            Some(i) if !line[..i].contains('"') => &line[..i],
            _ => line,
        };
        code.push_str(line);
        code.push('\n');
    }
    while let Some(at) = code.find("#[cfg(test)]") {
        let rest = code[at + "#[cfg(test)]".len()..].trim_start();
        let open = if rest.starts_with("mod ") || rest.starts_with("pub mod ") {
            code[at..].find('{').map(|i| at + i)
        } else {
            None
        };
        let Some(open) = open else {
            // An attribute on one item: drop the attribute only.
            code.replace_range(at..at + "#[cfg(test)]".len(), "");
            continue;
        };
        let mut depth = 0usize;
        let mut end = code.len();
        for (i, c) in code[open..].char_indices() {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = open + i + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        code.replace_range(at..end, "");
    }
    code
}

fn ident_at(s: &str) -> &str {
    let end = s
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(s.len());
    &s[..end]
}

/// The root modules `code` names through `crate::` paths, grouped ones
/// (`use crate::{a::b, c}`) too; a macro (`crate::data_set!`) is not a
/// module.
fn named_roots(code: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut rest = code;
    while let Some(i) = rest.find("crate::") {
        rest = &rest[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 1usize;
            let mut at_item = true;
            let mut chars = group.char_indices();
            while let Some((k, c)) = chars.next() {
                match c {
                    '{' => depth += 1,
                    '}' => {
                        depth -= 1;
                        if depth == 0 {
                            break;
                        }
                    }
                    ',' if depth == 1 => at_item = true,
                    c if depth == 1 && at_item && (c.is_ascii_alphabetic() || c == '_') => {
                        let id = ident_at(&group[k..]);
                        out.insert(id.to_string());
                        at_item = false;
                        for _ in 1..id.len() {
                            chars.next();
                        }
                    }
                    _ => {}
                }
            }
        } else {
            let id = ident_at(rest);
            if !id.is_empty() && !rest[id.len()..].starts_with('!') {
                out.insert(id.to_string());
            }
        }
    }
    out
}

/// The root modules `lib.rs` declares.
fn root_modules(src: &Path) -> BTreeSet<String> {
    let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
    lib.lines()
        .filter_map(|l| {
            let l = l.trim_start();
            let l = l.strip_prefix("pub ").unwrap_or(l);
            l.strip_prefix("mod ")
                .map(|m| m.trim_end_matches(';').trim().to_string())
        })
        .collect()
}

fn graph() -> (BTreeSet<String>, Graph) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let roots = root_modules(&src);
    let mut files = Vec::new();
    rs_files(&src, &mut files);
    assert!(files.len() > 50, "src/ read: {} files", files.len());
    let mut g = Graph::new();
    for f in files {
        let rel = f.strip_prefix(&src).unwrap();
        let first = rel.components().next().unwrap().as_os_str();
        let module = first.to_str().unwrap().trim_end_matches(".rs").to_string();
        if module == "lib" {
            continue;
        }
        assert!(
            roots.contains(&module),
            "{} is in no root module",
            rel.display()
        );
        let text = std::fs::read_to_string(&f).unwrap();
        let names = named_roots(&code_of(&text));
        let edges = g.entry(module.clone()).or_default();
        for n in names {
            assert!(
                roots.contains(&n),
                "{}: crate::{n} is no root module",
                rel.display()
            );
            if n != module {
                edges.insert(n);
            }
        }
    }
    (roots, g)
}

fn imports<'g>(g: &'g Graph, module: &str) -> &'g BTreeSet<String> {
    g.get(module)
        .unwrap_or_else(|| panic!("no module {module} in src/"))
}

/// Fails with every edge of `module` outside `allowed`.
fn only(g: &Graph, module: &str, allowed: &[&str]) {
    let bad: Vec<_> = imports(g, module)
        .iter()
        .filter(|m| !allowed.contains(&m.as_str()))
        .collect();
    assert!(
        bad.is_empty(),
        "{module} imports {bad:?}; allowed {allowed:?}"
    );
}

#[test]
fn the_reader_sees_the_imports_there_are() {
    // The graph is not empty by accident: edges the code has for certain.
    let (_, g) = graph();
    assert!(imports(&g, "kernel").contains("device"));
    assert!(imports(&g, "isb").contains("personality"));
    assert!(imports(&g, "chain").contains("sensor"));
    assert!(imports(&g, "schedule").contains("device"));
    let grouped = named_roots("use crate::{a::b, c::{d, e}, f};\ncrate::g!(x);");
    assert_eq!(grouped, ["a", "c", "f"].map(String::from).into());
    let code = code_of("use crate::a; // crate::b\n#[cfg(test)]\nmod tests { use crate::c; }\n");
    assert_eq!(named_roots(&code), ["a"].map(String::from).into());
}

#[test]
fn the_core_names_no_personality() {
    // The shell, the line, the schedule, the chain and its stages, the
    // vehicle, the Earth, the store, the seam: none names kernel/ or isb/.
    let (roots, g) = graph();
    for m in roots
        .iter()
        .filter(|m| !PERSONALITIES.contains(&m.as_str()))
    {
        for p in PERSONALITIES {
            assert!(!imports(&g, m).contains(*p), "{m} imports {p}");
        }
    }
}

#[test]
fn the_personalities_do_not_import_each_other() {
    let (_, g) = graph();
    assert!(!imports(&g, "kernel").contains("isb"));
    assert!(!imports(&g, "isb").contains("kernel"));
}

#[test]
fn the_seam_points_one_way() {
    // personality.rs and io.rs are below the shell and the personalities.
    let (_, g) = graph();
    for m in ["personality", "io"] {
        assert!(!imports(&g, m).contains("device"), "{m} imports device");
        assert!(!imports(&g, m).contains("schedule"), "{m} imports schedule");
    }
}

#[test]
fn the_stages_meet_only_in_the_chain() {
    let (_, g) = graph();
    only(&g, "math", &[]);
    only(&g, "earth", &[]);
    for stage in ["sensor", "dsp", "ahrs"] {
        only(&g, stage, &["math", "time"]);
    }
    only(&g, "vehicle", &["math", "sensor"]);
    only(&g, "model", &["sensor"]);
}

#[test]
fn no_import_circle_among_the_root_modules() {
    let (roots, g) = graph();
    // Depth-first search with colours: grey on the path, black done.
    fn visit<'a>(
        m: &'a str,
        g: &'a Graph,
        colour: &mut BTreeMap<&'a str, u8>,
        path: &mut Vec<&'a str>,
    ) {
        match colour.get(m) {
            Some(2) => return,
            Some(1) => {
                let from = path.iter().position(|p| *p == m).unwrap();
                panic!("import circle: {:?} → {m}", &path[from..]);
            }
            _ => {}
        }
        colour.insert(m, 1);
        path.push(m);
        for n in g.get(m).into_iter().flatten() {
            visit(n, g, colour, path);
        }
        path.pop();
        colour.insert(m, 2);
    }
    let mut colour = BTreeMap::new();
    for m in &roots {
        visit(m, &g, &mut colour, &mut Vec::new());
    }
}
