//! The single-file outputs of every command (`export-ssp`, `alignment-studies smooth`, `learn`,
//! `taps`, `calibrate`, a study's `--doc` and report files): the rule [`crate::outdir`] applies to
//! output directories, for one file.
//!
//! | case | outcome |
//! |---|---|
//! | the output is one of the command's inputs (same device and inode) | refused, even with `--force` |
//! | a symlink, FIFO, device, socket or directory | refused, even with `--force` ([`refuse_special`](crate::outdir::refuse_special)) |
//! | an existing regular file that starts with the writer's mark (a file this command wrote, e.g. the shipped tap bank) | replaced |
//! | any other existing regular file | refused, unless `--force` |
//! | the write itself | into a temporary file in the same directory, renamed into place: a failed write (a full disk) leaves the old file as it was and no temporary behind |
//!
//! The check runs before the command's work ([`check`]) and again just before the rename
//! ([`write()`]), so hours of fitting are never lost to an `--out` that could not be used.

use std::io::{self, Read};
use std::path::{Path, PathBuf};

/// What the command may replace at an output path.
#[derive(Debug, Clone, Copy, Default)]
pub struct Replace<'a> {
    /// `--force`: replace any existing regular file that is not an input.
    pub force: bool,
    /// The first bytes of every file this writer makes: an existing file that starts with them
    /// was written by it, and is replaced without `--force`.
    pub mark: Option<&'a [u8]>,
}

/// Whether `a` and `b` name the same existing file (same device and inode on Unix; the same
/// canonical path elsewhere). Hard links and `./x` against `x` are caught alike.
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (std::fs::metadata(a), std::fs::metadata(b)) {
            (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        match (a.canonicalize(), b.canonicalize()) {
            (Ok(x), Ok(y)) => x == y,
            _ => false,
        }
    }
}

/// An error unless `out` may be written by the rules of this module: not an input, not a
/// special file, and absent, or marked as this writer's, or `force`d. Its directory must exist
/// or be creatable later; nothing is created here.
pub fn check(out: &Path, inputs: &[&Path], replace: Replace) -> io::Result<()> {
    let refused = |why: String| io::Error::new(io::ErrorKind::AlreadyExists, why);
    if let Some(input) = inputs.iter().find(|i| same_file(out, i)) {
        return Err(refused(format!(
            "--out {} is the input {}: a command never replaces its input; write elsewhere",
            out.display(),
            input.display()
        )));
    }
    crate::outdir::refuse_special(out)?;
    if out.exists() && !replace.force && !starts_with(out, replace.mark) {
        return Err(refused(format!(
            "{} exists and was not written by this command: it is not replaced; give --force to replace it, or write elsewhere",
            out.display()
        )));
    }
    Ok(())
}

/// Whether the file starts with `mark`.
fn starts_with(path: &Path, mark: Option<&[u8]>) -> bool {
    let Some(mark) = mark.filter(|m| !m.is_empty()) else {
        return false;
    };
    let mut head = Vec::with_capacity(mark.len());
    std::fs::File::open(path)
        .and_then(|f| f.take(mark.len() as u64).read_to_end(&mut head))
        .is_ok_and(|_| head == mark)
}

/// The temporary file `out` is written through: hidden, in `out`'s directory (so the rename
/// is atomic), per process (two writers never share one).
pub fn temporary(out: &Path) -> PathBuf {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    out.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Checks `out` ([`check`]), creates its directory, lets `fill` write the temporary file
/// ([`temporary`]) and renames it into place. On any error the temporary file is removed and
/// whatever was at `out` is left as it was.
pub fn write(
    out: &Path,
    inputs: &[&Path],
    replace: Replace,
    fill: impl FnOnce(&Path) -> io::Result<()>,
) -> io::Result<()> {
    check(out, inputs, replace)?;
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| {
            io::Error::new(
                e.kind(),
                format!("cannot create the directory {}: {e}", dir.display()),
            )
        })?;
    }
    let tmp = temporary(out);
    crate::outdir::refuse_special(&tmp)?;
    let done = fill(&tmp).and_then(|()| {
        // Checked again: the file may have appeared while the command worked.
        check(out, inputs, replace)?;
        std::fs::rename(&tmp, out)
    });
    done.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io::Error::new(
            e.kind(),
            format!("cannot write {} (left as it was): {e}", out.display()),
        )
    })
}

/// [`write()`] with the contents in memory.
pub fn write_bytes(
    out: &Path,
    inputs: &[&Path],
    replace: Replace,
    contents: &[u8],
) -> io::Result<()> {
    write(out, inputs, replace, |tmp| std::fs::write(tmp, contents))
}

#[cfg(test)]
mod tests {
    use super::*;

    const MARK: Replace = Replace {
        force: false,
        mark: Some(b"mine v1"),
    };

    #[test]
    fn an_input_is_never_replaced_even_forced_or_through_another_name() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("rec.csv");
        std::fs::write(&input, "data").unwrap();
        let other_name = dir.path().join(".").join("rec.csv");
        let force = Replace {
            force: true,
            mark: None,
        };
        let e = write_bytes(&other_name, &[&input], force, b"x").unwrap_err();
        assert!(e.to_string().contains("is the input"), "{e}");
        #[cfg(unix)]
        {
            let hard = dir.path().join("hard.csv");
            std::fs::hard_link(&input, &hard).unwrap();
            let e = write_bytes(&hard, &[&input], force, b"x").unwrap_err();
            assert!(e.to_string().contains("is the input"), "{e}");
        }
        assert_eq!(std::fs::read_to_string(&input).unwrap(), "data");
    }

    #[test]
    fn an_unmarked_file_needs_force_and_a_marked_one_does_not() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.txt");
        std::fs::write(&out, "someone's notes").unwrap();
        let e = write_bytes(&out, &[], MARK, b"mine v1 new").unwrap_err();
        assert!(
            e.to_string().contains("not written by this command")
                && e.to_string().contains("--force"),
            "{e}"
        );
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "someone's notes");
        std::fs::write(&out, "mine v1 old").unwrap();
        write_bytes(&out, &[], MARK, b"mine v1 new").unwrap();
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "mine v1 new");
        let forced = Replace {
            force: true,
            ..MARK
        };
        std::fs::write(&out, "other").unwrap();
        write_bytes(&out, &[], forced, b"forced").unwrap();
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "forced");
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            1,
            "no temporary left"
        );
    }

    #[cfg(unix)]
    #[test]
    fn special_files_are_refused_even_forced() {
        let dir = tempfile::tempdir().unwrap();
        let forced = Replace {
            force: true,
            mark: None,
        };
        let link = dir.path().join("link");
        std::os::unix::fs::symlink("/dev/full", &link).unwrap();
        let e = write_bytes(&link, &[], forced, b"x").unwrap_err();
        assert!(e.to_string().contains("symbolic link"), "{e}");
        let e = write_bytes(dir.path(), &[], forced, b"x").unwrap_err();
        assert!(e.to_string().contains("directory"), "{e}");
    }

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.txt");
        std::fs::write(&out, "mine v1 old").unwrap();
        let e = write(&out, &[], MARK, |tmp| {
            std::fs::write(tmp, "mine v1 half")?;
            Err(io::Error::new(
                io::ErrorKind::StorageFull,
                "No space left on device",
            ))
        })
        .unwrap_err();
        assert!(
            e.to_string().contains("left as it was") && e.to_string().contains("No space"),
            "{e}"
        );
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "mine v1 old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
