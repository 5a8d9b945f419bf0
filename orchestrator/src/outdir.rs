//! The output directory of a command (`run`, `simulate`): one writer at a time, no stale files
//! from an earlier run beside the new ones, and a manifest that says how the results were made.
//!
//! | concern | rule |
//! |---|---|
//! | two runs into one directory | the first takes an exclusive lock on `DIR/.orchestrator.lock` (an OS file lock: released when the process ends, even by a crash); the second stops with a message naming the directory |
//! | stale outputs | the files the previous run's `manifest.json` lists (plain names inside `DIR`, regular files only) are removed before the new run writes, so no `metrics.json` of another run sits beside a new `results.csv` |
//! | special files | an output path that is a symlink, FIFO, device or directory is refused, never replaced |
//! | a refused or failed run | a directory the run created and wrote no results into is removed again (no empty `--out` left) |
//! | traceability | `DIR/manifest.json`: program and version, command line, every `--set`, each FMU's path, GUID and SHA-256, the time (UTC) and the files written |

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::fs::{File, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};

/// The lock file's name inside the output directory.
pub const LOCK: &str = ".orchestrator.lock";
/// The manifest's name inside the output directory.
pub const MANIFEST: &str = "manifest.json";

/// An output directory held by this process. Dropping it removes the lock file, and the
/// manifest too if no results were written (the run failed before it started): a directory
/// the run could not use is left as it was found.
pub struct OutputDir {
    dir: PathBuf,
    /// Holds the lock until dropped.
    _lock: File,
    /// What [`OutputDir::hold`] wrote: its files are the run's outputs.
    manifest: Option<Manifest>,
    /// The directory did not exist before: a run that wrote nothing removes it again, so a
    /// refused run leaves no empty `--out` behind.
    created: bool,
}

impl Drop for OutputDir {
    fn drop(&mut self) {
        // A directory only opened keeps whatever manifest its user wrote.
        let wrote = self.manifest.as_ref().is_none_or(|m| {
            m.files.iter().any(|f| {
                let f = self.dir.join(f);
                f.exists() || crate::record::partial(&f).exists()
            })
        });
        if !wrote {
            let _ = std::fs::remove_file(self.dir.join(MANIFEST));
        }
        let _ = std::fs::remove_file(self.dir.join(LOCK));
        if self.created && !wrote {
            // Fails, as it should, if anything else is in it.
            let _ = std::fs::remove_dir(&self.dir);
        }
    }
}

/// One FMU a result was made with.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct FmuRecord {
    /// The component the FMU ran as (`fmu` for `simulate`).
    pub component: String,
    /// The FMU file's path as the command was given it (not made absolute).
    pub path: String,
    /// The model description's GUID; empty when it cannot be read.
    pub guid: String,
    /// SHA-256 of the .fmu file, lower-case hex: what tells two builds of an FMU apart.
    pub sha256: String,
}

/// `manifest.json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Manifest {
    /// The writer and its version, e.g. `orchestrator 0.1.0`.
    pub program: String,
    /// This process's command line, program name first.
    pub command: Vec<String>,
    /// The `--set NAME=VALUE` settings, as given.
    pub settings: Vec<String>,
    /// The FMUs the results were made with.
    pub fmus: Vec<FmuRecord>,
    /// When the run started, UTC, RFC 3339.
    pub time_utc: String,
    /// The files this run wrote into the directory (plain names).
    pub files: Vec<String>,
}

impl OutputDir {
    /// Creates `dir` if needed, takes its lock and removes the outputs of the run that wrote its
    /// manifest before. Errors name the directory and what is wrong.
    pub fn open(dir: &Path) -> io::Result<OutputDir> {
        let named = |what: &str, e: io::Error| {
            io::Error::new(e.kind(), format!("cannot {what} {}: {e}", dir.display()))
        };
        if let Ok(m) = std::fs::metadata(dir)
            && !m.is_dir()
        {
            return Err(io::Error::new(
                io::ErrorKind::AlreadyExists,
                format!(
                    "cannot create the directory {}: a file of that name exists",
                    dir.display()
                ),
            ));
        }
        let created = !dir.exists();
        std::fs::create_dir_all(dir).map_err(|e| named("create the directory", e))?;
        let lock_path = dir.join(LOCK);
        refuse_special(&lock_path)?;
        let lock = OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&lock_path)
            .map_err(|e| named("create the lock file in", e))?;
        match lock.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                return Err(io::Error::new(
                    io::ErrorKind::WouldBlock,
                    format!(
                        "output directory {} is being written by another run (it holds {}): wait for it to finish or give another --out",
                        dir.display(),
                        lock_path.display()
                    ),
                ));
            }
            Err(std::fs::TryLockError::Error(e)) => return Err(named("lock", e)),
        }
        let out = OutputDir {
            dir: dir.to_path_buf(),
            _lock: lock,
            manifest: None,
            created,
        };
        out.remove_stale()?;
        Ok(out)
    }

    /// The directory, as given to [`OutputDir::open`].
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// The manifest [`OutputDir::hold`] wrote (none for a directory only opened).
    pub fn manifest(&self) -> Option<&Manifest> {
        self.manifest.as_ref()
    }

    /// Opens `dir` for a run ([`OutputDir::open`]), checks its output `files` (no symlink, FIFO
    /// or device is replaced, [`refuse_special`]) and writes the manifest before the run, so
    /// that even a failed run's partial results can be traced. `program` names the writer; the
    /// command line is this process's.
    pub fn hold(
        dir: &Path,
        program: &str,
        files: &[&str],
        fmus: &[(&str, &Path)],
        settings: &[String],
    ) -> io::Result<OutputDir> {
        let mut out = OutputDir::open(dir)?;
        for f in files {
            let path = out.path().join(f);
            refuse_special(&path)?;
            // What an earlier run here wrote is gone (`open` removed what its manifest lists):
            // a file still there is someone else's, and is neither replaced nor, through this
            // run's manifest, handed to the next run to remove.
            if path.exists() {
                return Err(io::Error::new(
                    io::ErrorKind::AlreadyExists,
                    format!(
                        "{} exists and no manifest of an earlier run here lists it: it is not replaced; move it or write elsewhere",
                        path.display()
                    ),
                ));
            }
        }
        let manifest = Manifest {
            program: program.into(),
            command: std::env::args().collect(),
            settings: settings.to_vec(),
            fmus: fmus
                .iter()
                .map(|(c, p)| fmu_record(c, p))
                .collect::<Result<_, _>>()?,
            time_utc: rfc3339(std::time::SystemTime::now()),
            files: files.iter().map(|f| f.to_string()).collect(),
        };
        out.write_manifest(&manifest)?;
        out.manifest = Some(manifest);
        Ok(out)
    }

    /// Removes what the previous manifest lists, and the manifest.
    fn remove_stale(&self) -> io::Result<()> {
        let manifest = self.dir.join(MANIFEST);
        let Ok(text) = std::fs::read_to_string(&manifest) else {
            return Ok(());
        };
        // A manifest we cannot read lists nothing we may delete; it is replaced at the end.
        let files: Vec<String> = serde_json::from_str::<Manifest>(&text)
            .map(|m| m.files)
            .unwrap_or_default();
        for name in files.iter().chain([&MANIFEST.to_string()]) {
            let plain = Path::new(name)
                .file_name()
                .is_some_and(|f| f == name.as_str());
            if !plain || name.starts_with('.') {
                continue;
            }
            let path = self.dir.join(name);
            // The file, and what a run stopped by a failed write left of it.
            for path in [crate::record::partial(&path), path] {
                if std::fs::symlink_metadata(&path).is_ok_and(|m| m.is_file()) {
                    std::fs::remove_file(&path).map_err(|e| {
                        io::Error::new(
                            e.kind(),
                            format!("cannot remove {} of the previous run: {e}", path.display()),
                        )
                    })?;
                }
            }
        }
        Ok(())
    }

    /// Writes `manifest.json` (through a temporary file, renamed into place).
    pub fn write_manifest(&self, manifest: &Manifest) -> io::Result<PathBuf> {
        let path = self.dir.join(MANIFEST);
        refuse_special(&path)?;
        let tmp = self
            .dir
            .join(format!(".{MANIFEST}.{}.tmp", std::process::id()));
        let text = serde_json::to_string_pretty(manifest).expect("a manifest serializes");
        std::fs::write(&tmp, text + "\n")
            .and_then(|()| std::fs::rename(&tmp, &path))
            .map_err(|e| {
                let _ = std::fs::remove_file(&tmp);
                io::Error::new(e.kind(), format!("cannot write {}: {e}", path.display()))
            })?;
        Ok(path)
    }
}

/// An error if `path` exists and is not a regular file (a symlink, FIFO, device, socket or
/// directory): an output must never replace one.
pub fn refuse_special(path: &Path) -> io::Result<()> {
    let Ok(m) = std::fs::symlink_metadata(path) else {
        return Ok(());
    };
    let what = if m.file_type().is_symlink() {
        "a symbolic link"
    } else if m.is_dir() {
        "a directory"
    } else if m.is_file() {
        return Ok(());
    } else {
        "a FIFO, device or socket"
    };
    Err(io::Error::new(
        io::ErrorKind::AlreadyExists,
        format!(
            "{} is {what}: an output is written only as a regular file, so it is not replaced; remove it or write elsewhere",
            path.display()
        ),
    ))
}

/// An FMU's record for the manifest: its GUID (from the model description) and SHA-256.
pub fn fmu_record(component: &str, path: &Path) -> io::Result<FmuRecord> {
    let mut file = File::open(path)
        .map_err(|e| io::Error::new(e.kind(), format!("cannot read {}: {e}", path.display())))?;
    let mut hasher = Sha256::new();
    io::copy(&mut file, &mut hasher)
        .map_err(|e| io::Error::new(e.kind(), format!("cannot read {}: {e}", path.display())))?;
    let sha256 = hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    let guid = crate::info::read_archive(path)
        .map(|a| a.model_description.guid)
        .unwrap_or_default();
    Ok(FmuRecord {
        component: component.to_string(),
        path: path.display().to_string(),
        guid,
        sha256,
    })
}

/// `t` as RFC 3339 in UTC, to the second (civil date from days since 1970-01-01: H. Hinnant's
/// algorithm).
pub fn rfc3339(t: std::time::SystemTime) -> String {
    let secs = t
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_writer_is_refused_and_the_lock_dies_with_the_first() {
        let dir = tempfile::tempdir().unwrap();
        let first = OutputDir::open(dir.path()).unwrap();
        let e = OutputDir::open(dir.path()).err().unwrap();
        assert!(
            e.to_string().contains("being written by another run"),
            "{e}"
        );
        drop(first);
        OutputDir::open(dir.path()).unwrap();
    }

    #[test]
    fn the_previous_runs_outputs_are_removed_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        for f in [
            "results.csv",
            "results.csv.partial",
            "metrics.json",
            "notes.txt",
        ] {
            std::fs::write(d.join(f), "old").unwrap();
        }
        let m = Manifest {
            program: "x".into(),
            command: vec![],
            settings: vec![],
            fmus: vec![],
            time_utc: String::new(),
            files: vec![
                "results.csv".into(),
                "metrics.json".into(),
                "../escape".into(),
                "/etc/passwd".into(),
            ],
        };
        OutputDir::open(d).unwrap().write_manifest(&m).unwrap();
        drop(OutputDir::open(d).unwrap());
        assert!(!d.join("results.csv").exists() && !d.join("metrics.json").exists());
        assert!(
            !d.join("results.csv.partial").exists(),
            "what a failed write left of a listed file goes too"
        );
        assert!(!d.join(MANIFEST).exists());
        assert!(d.join("notes.txt").exists(), "files no manifest lists stay");
    }

    #[test]
    fn a_file_no_manifest_lists_is_neither_replaced_nor_listed() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("data.csv"), "mine").unwrap();
        let e = OutputDir::hold(d, "test", &["data.csv"], &[], &[])
            .err()
            .unwrap();
        assert!(
            e.to_string().contains("data.csv exists and no manifest"),
            "{e}"
        );
        assert_eq!(std::fs::read_to_string(d.join("data.csv")).unwrap(), "mine");
        assert!(!d.join(MANIFEST).exists());
        // Written by a run here (listed in its manifest): the next run replaces it.
        std::fs::remove_file(d.join("data.csv")).unwrap();
        let out = OutputDir::hold(d, "test", &["data.csv"], &[], &[]).unwrap();
        std::fs::write(d.join("data.csv"), "run 1").unwrap();
        drop(out);
        OutputDir::hold(d, "test", &["data.csv"], &[], &[]).unwrap();
        assert!(!d.join("data.csv").exists());
    }

    #[cfg(unix)]
    #[test]
    fn symlinks_and_devices_are_refused_by_name() {
        let dir = tempfile::tempdir().unwrap();
        let link = dir.path().join("link.csv");
        std::os::unix::fs::symlink("/dev/null", &link).unwrap();
        let e = refuse_special(&link).unwrap_err().to_string();
        assert!(e.contains("link.csv") && e.contains("symbolic link"), "{e}");
        let e = refuse_special(Path::new("/dev/null"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("FIFO, device"), "{e}");
        refuse_special(&dir.path().join("absent.csv")).unwrap();
    }

    #[test]
    fn rfc3339_matches_known_instants() {
        use std::time::{Duration, UNIX_EPOCH};
        assert_eq!(rfc3339(UNIX_EPOCH), "1970-01-01T00:00:00Z");
        // 2000-02-29T12:34:56Z (a leap day) and 2026-11-23T23:02:37Z.
        assert_eq!(
            rfc3339(UNIX_EPOCH + Duration::from_secs(951_827_696)),
            "2000-02-29T12:34:56Z"
        );
        assert_eq!(
            rfc3339(UNIX_EPOCH + Duration::from_secs(1_795_474_957)),
            "2026-11-23T23:02:37Z"
        );
    }
}
