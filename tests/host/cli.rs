//! The command line itself through the binary: shell completions that
//! complete at every level (the bash script driven as bash drives it), a
//! man page for every page the pages name, the README's Quickstart run as
//! pasted, and the usage errors of options that do not fit.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn imu_emu(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_imu-emu"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("run imu-emu")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// What bash's programmable completion offers for the words `line` (the
/// last one being completed, maybe empty): the generated script sourced,
/// COMP_WORDS / COMP_CWORD set as readline sets them, its function called
/// with the command, the word and the previous word.
fn bash_complete(script: &Path, line: &[&str]) -> Vec<String> {
    let words: Vec<String> = line.iter().map(|w| format!("'{w}'")).collect();
    let program = format!(
        "source '{}'\nCOMP_WORDS=({})\nCOMP_CWORD={}\nCOMP_LINE='{}'\nCOMP_POINT=${{#COMP_LINE}}\n\
         _imu__emu imu-emu \"${{COMP_WORDS[COMP_CWORD]}}\" \"${{COMP_WORDS[COMP_CWORD-1]}}\"\n\
         printf '%s\\n' \"${{COMPREPLY[@]}}\"\n",
        script.display(),
        words.join(" "),
        line.len() - 1,
        line.join(" "),
    );
    let out = Command::new("bash")
        .arg("-c")
        .arg(program)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    text(&out.stdout)
        .lines()
        .filter(|l| !l.is_empty())
        .map(str::to_owned)
        .collect()
}

/// `client re<TAB>`, `client --protocol <TAB>`, `sensor-profile show
/// <TAB>`, `client record --to <TAB>`: each level completes (the
/// generator's states for a hyphenated program name used to match none of
/// its case labels past the first word).
#[test]
fn bash_completion_completes_every_level() {
    let out = imu_emu(&["completions", "bash"]);
    assert!(out.status.success());
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("imu-emu.bash");
    std::fs::write(&script, &out.stdout).unwrap();
    let cases: [(&[&str], &[&str]); 8] = [
        (&["imu-emu", "cl"], &["client"]),
        (&["imu-emu", "client", "re"], &["reset", "record"]),
        (&["imu-emu", "client", "--protocol", ""], &["kernel", "isb"]),
        (&["imu-emu", "--protocol", "i"], &["isb"]),
        (
            &["imu-emu", "client", "record", "--to", ""],
            &["csv", "json"],
        ),
        (&["imu-emu", "client", "record", "--fo"], &["--format"]),
        (&["imu-emu", "sensor-profile", "sh"], &["show"]),
        (&["imu-emu", "completions", "f"], &["fish"]),
    ];
    for (line, want) in cases {
        assert_eq!(bash_complete(&script, line), want, "{line:?}");
    }
    let names = bash_complete(&script, &["imu-emu", "sensor-profile", "show", "K1"]);
    assert_eq!(
        names,
        ["K100", "K102", "K108", "K110", "K110M", "K120"],
        "sensor-profile show K1<TAB>"
    );
}

/// fish, driven as it completes a command line (`complete -C`, Debian's
/// `fish`; `.ci/run` installs it): every level completes, the positional
/// values included (clap_complete's fish script has none; the binary adds
/// them). zsh: the value lists of the nested levels are in its
/// `_arguments` specs (driving zsh's completion needs a terminal; it was
/// checked by hand at these levels, docs/tools.md).
#[test]
fn fish_completes_every_level_and_zsh_has_the_nested_values() {
    let out = imu_emu(&["completions", "fish"]);
    assert!(out.status.success());
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("imu-emu.fish");
    std::fs::write(&script, &out.stdout).unwrap();
    let fish = |line: &str| -> Vec<String> {
        let out = Command::new("fish")
            .arg("--no-config")
            .arg("-c")
            .arg(format!(
                "source '{}'; complete -C '{line}'",
                script.display()
            ))
            .output()
            .expect("fish (apt-get install fish)");
        assert!(out.status.success(), "{}", text(&out.stderr));
        text(&out.stdout)
            .lines()
            .map(|l| l.split('\t').next().unwrap().to_owned())
            .collect()
    };
    assert_eq!(fish("imu-emu client re"), ["record", "reset"]);
    assert_eq!(fish("imu-emu client --protocol "), ["isb", "kernel"]);
    assert_eq!(fish("imu-emu client record --to "), ["csv", "json"]);
    assert_eq!(
        fish("imu-emu sensor-profile show "),
        [
            "IMX-5",
            "IMX-5-2022",
            "K100",
            "K102",
            "K108",
            "K110",
            "K110M",
            "K120",
            "K201",
            "K210",
            "K220"
        ]
    );
    assert_eq!(
        fish("imu-emu completions "),
        ["bash", "elvish", "fish", "powershell", "zsh"]
    );
    let zsh = text(&imu_emu(&["completions", "zsh"]).stdout);
    for spec in [
        "':name -- Model name:(K100 K102 K108 K110 K110M K120 K201 K210 K220 IMX-5 IMX-5-2022)'",
        "--protocol=[The unit",
        ":PROTOCOL:((kernel\\:",
        "'reset:IMX-5 (ISB)\\: software reset",
    ] {
        assert!(zsh.contains(spec), "no {spec} in the zsh script");
    }
}

/// Every page a man page names (`imu-emu-client(1)`, …) is produced by
/// `imu-emu man` with the subcommand's path, and `--dir` writes them all.
#[test]
fn every_man_page_named_can_be_produced() {
    let mut todo = vec![Vec::<String>::new()];
    let mut seen = Vec::new();
    while let Some(path) = todo.pop() {
        let mut args = vec!["man".to_owned()];
        args.extend(path.iter().cloned());
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = imu_emu(&args);
        assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
        let page = text(&out.stdout);
        let name = std::iter::once("imu-emu")
            .chain(path.iter().map(String::as_str))
            .collect::<Vec<_>>()
            .join("-");
        assert!(
            page.starts_with(&format!(
                ".ie \\n(.g .ds Aq \\(aq\n.el .ds Aq '\n.TH {name} 1"
            )),
            "{args:?}: {}",
            &page[..page.len().min(200)]
        );
        seen.push(name.clone());
        // The pages it names: `imu\-emu\-client(1)`.
        let named = page.replace("\\-", "-");
        for w in named.split(|c: char| c.is_whitespace() || c == '\\' || c == '"') {
            if let Some(sub) = w
                .strip_prefix(&format!("{name}-"))
                .and_then(|s| s.strip_suffix("(1)"))
            {
                let mut p = path.clone();
                p.push(sub.to_owned());
                todo.push(p);
            }
        }
    }
    seen.sort();
    for want in [
        "imu-emu",
        "imu-emu-client",
        "imu-emu-client-record",
        "imu-emu-client-reset",
        "imu-emu-sensor-profile-show",
        "imu-emu-allan",
        "imu-emu-man",
    ] {
        assert!(
            seen.iter().any(|s| s == want),
            "{want} not reached: {seen:?}"
        );
    }
    assert!(!seen.iter().any(|s| s.ends_with("-help")), "{seen:?}");
    let dir = tempfile::tempdir().unwrap();
    let out = imu_emu(&["man", "--dir", dir.path().to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let mut files: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| {
            e.unwrap()
                .file_name()
                .to_string_lossy()
                .trim_end_matches(".1")
                .to_owned()
        })
        .collect();
    files.sort();
    assert_eq!(files, seen);
    let out = imu_emu(&["man", "client", "nothing"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).starts_with("imu-emu: man: `imu-emu client` has no subcommand nothing;"),
        "{}",
        text(&out.stderr)
    );
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// The README's Quickstart block, run by bash as pasted, with `cargo emu`
/// as the binary under test (its `cargo build` line dropped: the test
/// harness built it) and free ports instead of 7000 and 8080 (other
/// tests run beside it): it records two seconds at 200 Hz and plots them.
#[test]
fn the_readme_quickstart_runs_as_pasted() {
    let readme = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../README.md");
    let readme = std::fs::read_to_string(readme).unwrap();
    let section = &readme[readme.find("## Quickstart").expect("a Quickstart")..];
    let start = section.find("```sh\n").expect("a sh block") + "```sh\n".len();
    let block = &section[start..start + section[start..].find("```").unwrap()];
    let (uart, web) = (free_port(), free_port());
    let script: String = block
        .lines()
        .filter(|l| !l.starts_with("cargo build"))
        .map(|l| {
            l.replace("cargo emu", env!("CARGO_BIN_EXE_imu-emu"))
                .replace("127.0.0.1:7000", &format!("127.0.0.1:{uart}"))
                .replace("127.0.0.1:8080", &format!("127.0.0.1:{web}"))
                + "\n"
        })
        .collect();
    assert!(script.contains("until grep -q '^listening'"), "{script}");
    let out = Command::new("bash")
        .arg("-c")
        .arg(format!("{script}echo \"$work\"\n"))
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", text(&out.stderr));
    assert!(stdout.starts_with("serial: 10000000\n"), "{stdout}");
    assert!(stdout.contains("Data_Rate saved = 200\n"), "{stdout}");
    let work = PathBuf::from(stdout.lines().last().unwrap());
    let csv = std::fs::read_to_string(work.join("ga.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 400);
    assert!(rows[399].starts_with("399,GA,1.995000,"), "{}", rows[399]);
    let png = std::fs::read(work.join("ga.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    assert!(stdout.contains("ga.png: 400 rows plotted\n"), "{stdout}");
    let _ = std::fs::remove_dir_all(&work);
}

/// Options that do not fit: each a usage error (exit status 2), one line,
/// nothing listens: a motion file that does not load, as a sensor profile
/// that does not; `--gps-time` for a KERNEL (it keeps no GPS time).
#[test]
fn options_that_do_not_fit_are_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let motion = dir.path().join("m.csv");
    std::fs::write(
        &motion,
        "time,lat,lon,height,vn,ve,vd,roll,pitch,yaw\n0,45,7,0,0,0,0,0,0,0\n1,95,7,0,0,0,0,0,0,0\n",
    )
    .unwrap();
    let profile = dir.path().join("p.toml");
    std::fs::write(&profile, "[gyro]\nrange = -1\n").unwrap();
    let m = motion.to_str().unwrap();
    let p = profile.to_str().unwrap();
    let cases: [(&[&str], String); 5] = [
        (
            &["--motion", m],
            format!(
                "imu-emu: --motion {m}: in {m}: line 3, column lat (value 2): value out of range: \
                 \"1,95,7,0,0,0,0,0,0,0\"\n"
            ),
        ),
        (
            &["--motion", "/nonexistent/m.csv"],
            "imu-emu: --motion /nonexistent/m.csv: reading motion /nonexistent/m.csv: No such \
             file or directory (os error 2)\n"
                .to_owned(),
        ),
        (&["--sensor-profile", p], String::new()),
        (&["--sensor-profile", "/nonexistent/p.toml"], String::new()),
        (
            &["--gps-time", "2026-03-01"],
            "imu-emu: --gps-time sets an IMX-5's GPS time (--protocol isb); a KERNEL keeps no \
             GPS time\n"
                .to_owned(),
        ),
    ];
    for (args, want) in cases {
        let mut all = vec!["--tcp", "127.0.0.1:0"];
        all.extend_from_slice(args);
        let out = imu_emu(&all);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{args:?}: {}",
            text(&out.stderr)
        );
        assert!(out.stdout.is_empty(), "{args:?} listened");
        let err = text(&out.stderr);
        assert_eq!(err.lines().count(), 1, "{err}");
        if !want.is_empty() {
            assert_eq!(err, want);
        }
    }
    // With --protocol isb, --gps-time is the IMX's GPS time: accepted.
    let help = text(&imu_emu(&["--help"]).stdout);
    assert!(!help.contains("IMU mode"), "{help}");
    assert!(
        help.contains("an Inertial Sense IMX-5 speaking ISB: its IMU,"),
        "{help}"
    );
}
