//! The control grammar (`imu_emu_runner::control`): every line, as the
//! control socket and the web view's `POST /api/command` take it.

use imu_emu_runner::control;

/// Parses each line of `data` (lossy UTF-8, split at newlines, trimmed as
/// the socket does). Invariants: an answer is one line (an error holds no
/// newline); `dev K <command>` gives device K and the same command as
/// `<command>` alone; a line that does not start with `dev` parses as
/// [`control::parse`] does; a command that parses starts with a word
/// `help` lists, whose syntax an error can name.
pub fn control_line(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    for line in text.split('\n') {
        let line = line.trim();
        let addressed = control::parse_addressed(line);
        if let Err(e) = &addressed {
            assert!(!e.contains('\n'), "a two-line error: {e:?}");
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        match (words.first(), &addressed) {
            (Some(&"dev"), Ok((Some(k), c))) => {
                let rest = &line[line.find(words[2]).expect("the command")..];
                assert_eq!(control::parse(rest).as_ref(), Ok(c), "{line:?}");
                assert_eq!(words[1].parse::<usize>().ok(), Some(*k));
            }
            (Some(&"dev"), Ok((None, _))) => panic!("dev without a device: {line:?}"),
            (Some(&"dev"), Err(_)) => {}
            (_, a) => {
                let plain = control::parse(line);
                assert_eq!(plain.as_ref().ok(), a.as_ref().ok().map(|(_, c)| c));
                assert!(a.as_ref().map_or(true, |(k, _)| k.is_none()));
            }
        }
        if let Ok((_, c)) = &addressed {
            let word = line
                .split_whitespace()
                .find(|w| !matches!(*w, "dev") && w.parse::<usize>().is_err())
                .unwrap_or("");
            assert!(
                control::usage(word).is_some(),
                "{word:?} ({c:?}) not in help"
            );
            assert!(control::help().contains(word));
        }
    }
}
