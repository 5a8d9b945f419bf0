//! A study's output directory (`standard`, `robustness`, `resonance`, `all`, `variants`,
//! `calibrate --plots`) and what may be replaced in it: the directories' rule of the output
//! policy (docs/studies.md), as [`orchestrator::outfile`] is the single files'.
//!
//! Several studies share one directory (the demo writes `all` and `variants` into one), so
//! unlike a run's `--out` ([`orchestrator::outdir`]) a study neither locks the directory nor
//! removes another study's files: it replaces only what a study wrote there.
//!
//! | case | outcome |
//! |---|---|
//! | a name the study writes, absent | written |
//! | present, and listed in the directory's record [`RECORD`] (a study wrote it) | replaced |
//! | present, not listed (someone's own `report.md`) | refused before any work, unless `--force` |
//! | a symlink, FIFO, device or directory | refused, even with `--force` |
//! | `--out` itself a file, symlink or device | refused |
//!
//! After the files are written their names join the record (written through a temporary file
//! renamed into place).

use crate::Error;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The record of the names the studies wrote into a directory, one per line.
pub const RECORD: &str = ".alignment-studies-written";

/// A study's output directory, checked before the work.
#[derive(Debug, Clone)]
pub struct StudyDir {
    dir: PathBuf,
    force: bool,
}

impl StudyDir {
    /// Checks `dir` and the `names` the study will write there before any work (see the module
    /// docs); nothing is created.
    pub fn check(dir: &Path, names: &[String], force: bool) -> Result<StudyDir, Error> {
        match std::fs::symlink_metadata(dir) {
            Ok(m) if !m.is_dir() => {
                return Err(Error::Io(format!(
                    "--out {}: exists and is not a directory; give a directory",
                    dir.display()
                )));
            }
            _ => {}
        }
        let d = StudyDir {
            dir: dir.to_path_buf(),
            force,
        };
        let written = d.written();
        for name in names {
            d.may_write(&dir.join(name), &written)?;
        }
        Ok(d)
    }

    /// The directory, as given.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Whether `path` is in this directory (a file the rule applies to).
    pub fn holds(&self, path: &Path) -> bool {
        path.parent() == Some(self.dir.as_path())
    }

    /// The check of one file, again at write time (a file may have appeared meanwhile).
    pub fn check_file(&self, path: &Path) -> Result<(), Error> {
        self.may_write(path, &self.written())
    }

    fn may_write(&self, path: &Path, written: &BTreeSet<String>) -> Result<(), Error> {
        orchestrator::outdir::refuse_special(path).map_err(|e| Error::Io(e.to_string()))?;
        let listed = path
            .file_name()
            .is_some_and(|n| written.contains(n.to_string_lossy().as_ref()));
        if path.exists() && !listed && !self.force {
            return Err(Error::Io(format!(
                "{} exists and no study wrote it (it is not in {}): it is not replaced; give --force to replace it, or another --out",
                path.display(),
                self.dir.join(RECORD).display()
            )));
        }
        Ok(())
    }

    /// The names the record lists (none when it is absent or unreadable).
    fn written(&self) -> BTreeSet<String> {
        std::fs::read_to_string(self.dir.join(RECORD))
            .map(|t| t.lines().map(str::to_string).collect())
            .unwrap_or_default()
    }

    /// Adds the names of `paths` (files of this directory) to the record.
    pub fn record<'a>(&self, paths: impl IntoIterator<Item = &'a PathBuf>) -> Result<(), Error> {
        let mut names = self.written();
        names.extend(
            paths
                .into_iter()
                .filter(|p| self.holds(p))
                .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned())),
        );
        let text: String = names.iter().map(|n| format!("{n}\n")).collect();
        let record = self.dir.join(RECORD);
        orchestrator::outfile::write_bytes(
            &record,
            &[],
            orchestrator::outfile::Replace {
                force: true,
                mark: None,
            },
            text.as_bytes(),
        )
        .map_err(|e| Error::Io(e.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(n: &[&str]) -> Vec<String> {
        n.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn only_what_a_study_wrote_is_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("report.md"), "mine").unwrap();
        let e = StudyDir::check(d, &names(&["report.md", "a.json"]), false).unwrap_err();
        assert!(e.to_string().contains("no study wrote it"), "{e}");
        // Forced, it may; once a study wrote it, the next study may without --force.
        let s = StudyDir::check(d, &names(&["report.md", "a.json"]), true).unwrap();
        s.record([&d.join("report.md"), &d.join("a.json")]).unwrap();
        StudyDir::check(d, &names(&["report.md", "a.json"]), false).unwrap();
        // Another study's names join the record; the first study's stay.
        let s = StudyDir::check(d, &names(&["variants.md"]), false).unwrap();
        s.record([&d.join("variants.md")]).unwrap();
        let record = std::fs::read_to_string(d.join(RECORD)).unwrap();
        assert_eq!(record, "a.json\nreport.md\nvariants.md\n");
    }

    #[cfg(unix)]
    #[test]
    fn special_files_are_refused_even_forced() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::os::unix::fs::symlink("/dev/null", d.join("report.md")).unwrap();
        let e = StudyDir::check(d, &names(&["report.md"]), true).unwrap_err();
        assert!(e.to_string().contains("symbolic link"), "{e}");
        let file = d.join("file");
        std::fs::write(&file, "x").unwrap();
        let e = StudyDir::check(&file, &[], false).unwrap_err();
        assert!(e.to_string().contains("not a directory"), "{e}");
    }
}
