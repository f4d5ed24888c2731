//! Input files: every file mcrt reads (scene files and their `<include>`s, meshes, textures,
//! checkpoints, sums files, the images `compare` reads) is read by [`read`] or [`read_text`],
//! once, whole, and only if it is a regular file no larger than [`MAX_FILE_BYTES`] that fits
//! in memory. A FIFO would block the reader forever, `/dev/zero` or `/dev/urandom` never
//! end, and a directory or device is never what the user meant; each is refused with what it
//! is. Also here: [`shorten`], which cuts a user's string short before an error echoes it.

use std::borrow::Cow;
use std::fs::{File, Metadata};
use std::io::Read;
use std::path::Path;

/// The largest file mcrt reads: 16 GiB (a PLY mesh of a few hundred million triangles). The
/// memory check ([`crate::check_allocation`]) usually refuses less.
pub const MAX_FILE_BYTES: u64 = 16 << 30;

/// Why `path` cannot be read as an input file, where that can be said before opening it:
/// "not found", what it is instead of a regular file, or the system's reason. None for a
/// regular file (symbolic links followed).
pub fn file_problem(path: &Path) -> Option<String> {
    match std::fs::metadata(path) {
        Ok(m) => kind_problem(&m),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Some("not found".into()),
        Err(e) => Some(format!("cannot be read: {e}")),
    }
}

/// "is a FIFO (named pipe), not a regular file" and the like; None for a regular file.
fn kind_problem(m: &Metadata) -> Option<String> {
    if m.is_file() {
        return None;
    }
    let what = if m.is_dir() {
        "a directory"
    } else {
        special_kind(m)
    };
    Some(format!("is {what}, not a regular file"))
}

#[cfg(unix)]
fn special_kind(m: &Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = m.file_type();
    if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "a special file"
    }
}

#[cfg(not(unix))]
fn special_kind(_: &Metadata) -> &'static str {
    "a special file"
}

/// Opens without blocking: should the path have become a FIFO since it was looked at, the
/// open returns at once and the check of the opened file refuses it.
fn open(path: &Path) -> std::io::Result<File> {
    let mut o = std::fs::OpenOptions::new();
    o.read(true);
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::OpenOptionsExt;
        o.custom_flags(libc::O_NONBLOCK);
    }
    o.open(path)
}

/// Reads a whole input file once. Err (without the path, which the caller names) when it is
/// missing, not a regular file, larger than [`MAX_FILE_BYTES`] or than the memory left.
pub fn read(path: &Path) -> Result<Vec<u8>, String> {
    if let Some(p) = file_problem(path) {
        return Err(format!("it {p}"));
    }
    let file = open(path).map_err(|e| format!("cannot open it: {e}"))?;
    let meta = file
        .metadata()
        .map_err(|e| format!("cannot read it: {e}"))?;
    if let Some(p) = kind_problem(&meta) {
        return Err(format!("it {p}"));
    }
    let size = meta.len();
    if size > MAX_FILE_BYTES {
        return Err(format!(
            "it is {}, more than the {} mcrt reads",
            crate::bytes_text(size),
            crate::bytes_text(MAX_FILE_BYTES)
        ));
    }
    crate::check_allocation(size).map_err(|e| format!("reading it {e}"))?;
    let mut bytes = Vec::with_capacity(size as usize);
    // One byte more than its size tells a file that grows while it is read.
    file.take(size + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("cannot read it: {e}"))?;
    if bytes.len() as u64 > size {
        return Err("it grew while it was read".into());
    }
    Ok(bytes)
}

/// Reads a whole text file once ([`read`]): UTF-8, without a leading byte-order mark (which
/// would otherwise become part of the first keyword or value).
pub fn read_text(path: &Path) -> Result<String, String> {
    let bytes = read(path)?;
    let bom = bytes.len() - as_text(&bytes)?.len();
    let mut s = String::from_utf8(bytes).map_err(|e| e.to_string())?;
    s.drain(..bom);
    Ok(s)
}

/// The bytes of a text file as a string without its byte-order mark; Err names the first
/// byte that is not UTF-8 by line and column.
pub fn as_text(bytes: &[u8]) -> Result<&str, String> {
    let s = std::str::from_utf8(bytes).map_err(|e| {
        // Valid up to there, so it is a str.
        let before = std::str::from_utf8(&bytes[..e.valid_up_to()]).unwrap_or("");
        let line = before.matches('\n').count() + 1;
        let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        format!("it is not UTF-8 text (an invalid byte at line {line}, column {col})")
    })?;
    Ok(s.strip_prefix('\u{feff}').unwrap_or(s))
}

/// Characters of a user's string an error message shows; the rest is cut.
pub const SHOWN_CHARS: usize = 60;

/// A user's string as an error echoes it: whole when short, else its first [`SHOWN_CHARS`]
/// characters, "…", and how long it was. Control characters are escaped, so that a value
/// cannot rewrite the terminal.
pub fn shorten(s: &str) -> Cow<'_, str> {
    let n = s.chars().count();
    if n <= SHOWN_CHARS && !s.chars().any(char::is_control) {
        return Cow::Borrowed(s);
    }
    let head: String = s
        .chars()
        .take(SHOWN_CHARS)
        .flat_map(|c| {
            if c.is_control() {
                c.escape_default().collect::<Vec<_>>()
            } else {
                vec![c]
            }
        })
        .collect();
    if n <= SHOWN_CHARS {
        Cow::Owned(head)
    } else {
        Cow::Owned(format!("{head}… ({n} characters)"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_files_are_named() {
        assert_eq!(
            read(Path::new("/dev/zero")).unwrap_err(),
            "it is a character device, not a regular file"
        );
        let dir = std::env::temp_dir();
        assert!(read(&dir).unwrap_err().contains("is a directory"));
        assert_eq!(
            file_problem(&dir.join("mcrt-no-such-file")).as_deref(),
            Some("not found")
        );
    }

    #[test]
    fn text_without_bom() {
        assert_eq!(as_text(b"\xef\xbb\xbfv 1 2 3").unwrap(), "v 1 2 3");
        let e = as_text(b"a\nbc\xff").unwrap_err();
        assert!(e.contains("line 2, column 3"), "{e}");
    }

    #[test]
    fn shorten_cuts_and_escapes() {
        assert_eq!(shorten("camera"), "camera");
        let long = "x".repeat(1000);
        let s = shorten(&long);
        assert!(s.starts_with(&"x".repeat(SHOWN_CHARS)));
        assert!(s.ends_with("… (1000 characters)"), "{s}");
        assert!(s.chars().count() < SHOWN_CHARS + 30);
        assert_eq!(shorten("a\nb"), "a\\nb");
    }
}
