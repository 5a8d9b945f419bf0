//! What each study produces, as a value: a [`Report`] holds the Markdown for the screen, the
//! files to write (Markdown, JSON, CSV, a calibration or a tap bank) and the figures drawn.
//! One function per command builds it ([`cases`], [`variants`], [`calibration`], [`learned`],
//! [`standard`]), so the command line only parses, calls, writes and maps the error to an exit
//! code, and a program or a test can take the report without a process.

pub mod calibration;
pub mod cases;
pub mod envelope;
pub mod fit;
pub mod learned;
pub mod standard;
pub mod variants;
pub mod written;

use crate::Error;
use orchestrator::outfile::{self, Replace};
use std::path::{Path, PathBuf};

/// What a study produces. Nothing is written until [`Report::write`], except the figures,
/// which the plotting library draws straight into their files (listed in `figures`).
#[derive(Debug, Default)]
pub struct Report {
    /// For the screen (stdout).
    pub markdown: String,
    /// The files of the report, each with its contents.
    pub files: Vec<(PathBuf, Vec<u8>)>,
    /// The SVG figures drawn.
    pub figures: Vec<PathBuf>,
    /// The closing lines for stderr: time taken, where the report is, why something is missing.
    pub note: String,
    /// The files given by name on the command line (`--out FILE`, `--doc FILE`), written by
    /// the single-file rule ([`outfile`]): never an input, replaced only when marked as this
    /// command's or with `--force`. The other files are a study's own names in its output
    /// directory ([`Report::study_dir`]).
    pub guarded: Vec<Guard>,
    /// The study's output directory ([`written`]): its files are replaced only where a study
    /// wrote them, and join its record once written.
    pub study_dir: Option<written::StudyDir>,
}

/// A file the command line named, with what may be replaced there.
#[derive(Debug, Clone)]
pub struct Guard {
    /// The file the command writes.
    pub path: PathBuf,
    /// The command's inputs: never replaced.
    pub inputs: Vec<PathBuf>,
    /// Whether an existing file there may be replaced: `--force`, or the mark of a file this
    /// command wrote.
    pub replace: Replace<'static>,
}

impl Guard {
    /// The check the command runs before any work ([`outfile::check`]).
    pub fn check(&self) -> Result<(), Error> {
        let inputs: Vec<&Path> = self.inputs.iter().map(PathBuf::as_path).collect();
        outfile::check(&self.path, &inputs, self.replace).map_err(|e| Error::Io(e.to_string()))
    }
}

impl Report {
    /// Adds a file to write.
    pub fn file(&mut self, path: PathBuf, contents: impl Into<Vec<u8>>) {
        self.files.push((path, contents.into()));
    }

    /// Writes the files (creating their directories, each through a temporary file renamed
    /// into place), prints the Markdown, then the note.
    pub fn write(&self) -> Result<(), Error> {
        for (path, contents) in &self.files {
            if let Some(d) = self.study_dir.as_ref().filter(|d| d.holds(path)) {
                d.check_file(path)?;
            }
            let (inputs, replace) = match self.guarded.iter().find(|g| &g.path == path) {
                Some(g) => (g.inputs.iter().map(PathBuf::as_path).collect(), g.replace),
                None => (
                    vec![],
                    Replace {
                        force: true,
                        mark: None,
                    },
                ),
            };
            outfile::write_bytes(path, &inputs, replace, contents)
                .map_err(|e| Error::Io(e.to_string()))?;
        }
        if let Some(d) = &self.study_dir {
            d.record(self.files.iter().map(|(p, _)| p).chain(&self.figures))?;
        }
        if !self.markdown.is_empty() {
            println!("{}", self.markdown.trim_end());
        }
        if !self.note.is_empty() {
            eprintln!("{}", self.note.trim_end());
        }
        Ok(())
    }
}

/// The held-out evaluation: accuracy is measured on track seeds the estimator was not
/// calibrated on.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// Held-out track seeds.
    pub seeds: Vec<u32>,
    /// The seed the estimator was calibrated on, refused among `seeds`.
    pub calibration_seed: u32,
}

impl Evaluation {
    /// Refuses the calibration seed among the evaluation seeds.
    pub fn held_out(&self) -> Result<(), Error> {
        if self.seeds.contains(&self.calibration_seed) {
            return Err(Error::Input(format!(
                "seed {} is the calibration seed: accuracy must be measured on other tracks",
                self.calibration_seed
            )));
        }
        if self.seeds.is_empty() {
            return Err(Error::Input("no evaluation seed given".into()));
        }
        Ok(())
    }
}

/// Creates the directory a file is to be written in, if it names one.
pub fn create_parent(file: &Path) -> Result<(), Error> {
    match file.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) => create_dir(dir),
        None => Ok(()),
    }
}

/// Creates a directory and its parents.
pub fn create_dir(dir: &Path) -> Result<(), Error> {
    std::fs::create_dir_all(dir)
        .map_err(|e| Error::Io(format!("cannot create {}: {e}", dir.display())))
}
