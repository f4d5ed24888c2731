//! Running the `mcrt` binary in tests: temporary directories, and the check that a bad input
//! fails cleanly (status 2, file:line:col, no panic, nothing written).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicUsize, Ordering};

pub const BIN: &str = env!("CARGO_BIN_EXE_mcrt");

/// A fresh, empty directory under the system temp dir, removed when dropped.
pub struct TempDir(PathBuf);

impl TempDir {
    pub fn new(tag: &str) -> TempDir {
        static N: AtomicUsize = AtomicUsize::new(0);
        let dir = std::env::temp_dir().join(format!(
            "mcrt-cli-{}-{}-{}",
            std::process::id(),
            tag,
            N.fetch_add(1, Ordering::Relaxed)
        ));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }
    pub fn path(&self) -> &Path {
        &self.0
    }
    pub fn write(&self, name: &str, text: &str) -> PathBuf {
        let p = self.0.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }
    /// Names of the files in the directory, sorted.
    pub fn listing(&self) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(&self.0)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

pub fn run(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(BIN)
        .args(args)
        .output()
        .expect("cannot run the mcrt binary")
}

pub fn stderr_of(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Where an error must point: the line holding `line_text`, at the column where `at` starts in
/// it (`at` = None: any column).
pub struct Loc {
    pub line_text: &'static str,
    pub at: Option<&'static str>,
}

pub fn loc(line_text: &'static str, at: &'static str) -> Option<Loc> {
    Some(Loc {
        line_text,
        at: Some(at),
    })
}

/// 1-based line and column of `l` in `text`.
pub fn line_col(text: &str, l: &Loc) -> (usize, Option<usize>) {
    let (i, line) = text
        .lines()
        .enumerate()
        .find(|(_, s)| s.contains(l.line_text))
        .unwrap_or_else(|| panic!("test bug: no line with {:?}", l.line_text));
    let col = l.at.map(|a| {
        let start = line.find(l.line_text).unwrap();
        let off = line[start..].find(a).expect("test bug: `at` not in line") + start;
        line[..off].chars().count() + 1
    });
    (i + 1, col)
}

/// Runs `mcrt render SCENE -o OUT extra...` and checks the failure: status 2, no panic, no
/// output file and nothing else left in the directory, stderr naming `file` (at `where_` if
/// given, whose line and column are looked up in `file_text`) and containing each of
/// `expect`.
#[allow(clippy::too_many_arguments)]
pub fn check_failure(
    dir: &TempDir,
    scene: &Path,
    out: &Path,
    extra: &[&str],
    file: &Path,
    file_text: Option<&str>,
    where_: Option<Loc>,
    expect: &[&str],
) {
    let before = dir.listing();
    let mut args: Vec<&std::ffi::OsStr> = vec!["render".as_ref(), scene.as_os_str()];
    args.push("-o".as_ref());
    args.push(out.as_os_str());
    for a in ["--spp", "1", "--width", "8", "--height", "8"] {
        args.push(a.as_ref());
    }
    for a in extra {
        args.push(a.as_ref());
    }
    let o = run(&args);
    let err = stderr_of(&o);
    assert!(!err.contains("panicked"), "mcrt panicked:\n{err}");
    assert_eq!(o.status.code(), Some(2), "exit status; stderr:\n{err}");
    let file_s = file.display().to_string();
    match (&where_, file_text) {
        (Some(l), Some(text)) => {
            let (line, col) = line_col(text, l);
            let want = match col {
                Some(c) => format!("{file_s}:{line}:{c}: "),
                None => format!("{file_s}:{line}:"),
            };
            assert!(
                err.contains(&want),
                "stderr should contain {want:?}, got:\n{err}"
            );
        }
        _ => assert!(
            err.contains(&file_s),
            "stderr should name {file_s}, got:\n{err}"
        ),
    }
    for e in expect {
        assert!(err.contains(e), "stderr should contain {e:?}, got:\n{err}");
    }
    assert!(!out.exists(), "{} was written", out.display());
    assert_eq!(
        dir.listing(),
        before,
        "files appeared or vanished in {}",
        dir.path().display()
    );
    assert!(o.stdout.is_empty(), "nothing goes to stdout on failure");
}
