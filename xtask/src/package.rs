//! `cargo xtask fmu`: build the FMU crates in release and pack each into `<target>/fmu/<id>.fmu`
//! (the test suite: in the dev profile, into `<target>/fmu-dev/`; [`Profile`]).
//!
//! The archive (FMI 2.0 section 2.3, docs/references.md section 7.4): modelDescription.xml,
//! `binaries/<platform>/<id>.<ext>`, resources/..., documentation/index.html. Deflate, forward
//! slashes, and reproducible: entries sorted by name, every timestamp 1980-01-01 00:00, unix
//! permissions 0644 (0755 for the shared library), no extra fields. The same sources give the
//! same bytes, so the .fmu can be compared or cached by hash.

use crate::fmus::{DESCRIBE, FMUS, FmuSpec};
use crate::workspace::{Profile, cargo, root, run, target_dir};
use anyhow::{Context, Result, bail};
use std::collections::HashSet;
use std::fs;
use std::io::{Cursor, Write};
use std::path::{Path, PathBuf};
use std::process::Command;
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, DateTime, System, ZipWriter};

/// One packaged FMU.
pub struct Packaged {
    pub model_identifier: &'static str,
    pub path: PathBuf,
    pub size: u64,
}

/// The FMI platform directory and shared-library naming of the machine we build on.
struct Platform {
    dir: &'static str,
    prefix: &'static str,
    extension: &'static str,
}

fn platform() -> Result<Platform> {
    match (std::env::consts::OS, std::env::consts::ARCH) {
        ("linux", "x86_64") => Ok(Platform {
            dir: "linux64",
            prefix: "lib",
            extension: "so",
        }),
        ("macos", "x86_64" | "aarch64") => Ok(Platform {
            dir: "darwin64",
            prefix: "lib",
            extension: "dylib",
        }),
        ("windows", "x86_64") => Ok(Platform {
            dir: "win64",
            prefix: "",
            extension: "dll",
        }),
        (os, arch) => bail!("FMI 2.0 defines no binaries/ directory for {os} on {arch}"),
    }
}

/// One file of the archive.
struct Entry {
    name: String,
    data: Vec<u8>,
    mode: u32,
}

/// The cargo command that builds every FMU crate in `profile`, and `fmu-describe` with them
/// (sharing their compiled crates).
pub fn build_command(profile: Profile) -> std::process::Command {
    let mut build = cargo();
    build.arg("build").args(profile.flags());
    for spec in FMUS {
        build.args(["-p", spec.package]);
    }
    build.args(["-p", DESCRIBE]);
    build
}

/// Builds every FMU crate in `profile` and packages each; prints the path and size of each .fmu.
pub fn build_and_package(profile: Profile) -> Result<Vec<Packaged>> {
    run(&mut build_command(profile))?;
    let target = target_dir()?;
    let platform = platform()?;
    let out_dir = target.join(profile.fmu_dir());
    fs::create_dir_all(&out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let build_dir = target.join(profile.dir());
    let describe = Describe(build_dir.join(format!("{DESCRIBE}{}", std::env::consts::EXE_SUFFIX)));
    let functions = describe.text(&["fmi-functions"])?;
    let mut packaged = Vec::new();
    for spec in FMUS {
        let p = package(spec, &describe, &functions, &build_dir, &platform, &out_dir)
            .with_context(|| format!("packaging {}", spec.model_identifier))?;
        println!("{} ({} bytes)", display_path(&p.path).display(), p.size);
        packaged.push(p);
    }
    Ok(packaged)
}

/// `path` relative to the workspace root when it is inside it (shorter messages).
pub fn display_path(path: &Path) -> PathBuf {
    path.strip_prefix(root())
        .map(Path::to_path_buf)
        .unwrap_or_else(|_| path.to_path_buf())
}

/// The built `fmu-describe` program.
struct Describe(PathBuf);

impl Describe {
    /// What it prints for `args`; fails with its message if it refuses.
    fn text(&self, args: &[&str]) -> Result<String> {
        let out = Command::new(&self.0)
            .args(args)
            .output()
            .with_context(|| format!("could not run {}", self.0.display()))?;
        if !out.status.success() {
            bail!(
                "`{DESCRIBE} {}` failed ({}): {}",
                args.join(" "),
                out.status,
                String::from_utf8_lossy(&out.stderr).trim_end()
            );
        }
        String::from_utf8(out.stdout).with_context(|| format!("`{DESCRIBE}` printed non-UTF-8"))
    }
}

fn package(
    spec: &FmuSpec,
    describe: &Describe,
    functions: &str,
    build_dir: &Path,
    platform: &Platform,
    out_dir: &Path,
) -> Result<Packaged> {
    // Checked against the standard's rules and the identifier by `fmu-describe`.
    let xml = describe.text(&[spec.model_identifier, "model-description"])?;
    let documentation = describe.text(&[spec.model_identifier, "documentation"])?;

    let library = build_dir.join(format!(
        "{}{}.{}",
        platform.prefix, spec.lib_name, platform.extension
    ));
    let binary = fs::read(&library)
        .with_context(|| format!("reading the built library {}", library.display()))?;
    check_exports(&binary, functions).with_context(|| format!("checking {}", library.display()))?;

    let mut entries = vec![
        Entry {
            name: "modelDescription.xml".into(),
            data: xml.into_bytes(),
            mode: 0o644,
        },
        Entry {
            name: format!(
                "binaries/{}/{}.{}",
                platform.dir, spec.model_identifier, platform.extension
            ),
            data: binary,
            mode: 0o755,
        },
        Entry {
            name: "documentation/index.html".into(),
            data: documentation.into_bytes(),
            mode: 0o644,
        },
    ];
    if let Some(dir) = spec.resources {
        let dir = root().join(dir);
        collect_files(&dir, &dir, "resources", &mut entries)?;
    }
    let bytes = zip_entries(entries)?;

    let path = out_dir.join(format!("{}.fmu", spec.model_identifier));
    // Write then rename, so a reader (a test run in another shell) never sees half an archive.
    let tmp = out_dir.join(format!(".{}.fmu.tmp", spec.model_identifier));
    fs::write(&tmp, &bytes).with_context(|| format!("writing {}", tmp.display()))?;
    fs::rename(&tmp, &path)
        .with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))?;
    Ok(Packaged {
        model_identifier: spec.model_identifier,
        path,
        size: bytes.len() as u64,
    })
}

/// A quick guard against shipping a library without the FMI entry points (for example a crate
/// that forgot `fmi_abi::export_fmu!`): every function name must appear as a NUL-terminated
/// string, which the dynamic symbol table (.dynstr) holds. The Python tests check the real
/// exports with the dynamic loader. `functions`: the names, one per line (`fmu-describe
/// fmi-functions`).
fn check_exports(binary: &[u8], functions: &str) -> Result<()> {
    let strings: HashSet<&[u8]> = binary.split(|b| *b == 0).collect();
    let missing: Vec<&str> = functions
        .lines()
        .filter(|name| !strings.contains(name.as_bytes()))
        .collect();
    if !missing.is_empty() {
        bail!(
            "the library does not export {} FMI function(s): {}",
            missing.len(),
            missing.join(", ")
        );
    }
    Ok(())
}

/// Adds every regular file under `dir` as `<prefix>/<relative path>` (forward slashes). Hidden
/// files (a leading '.', e.g. editor swap files or .gitkeep) are left out.
fn collect_files(base: &Path, dir: &Path, prefix: &str, entries: &mut Vec<Entry>) -> Result<()> {
    let listing = fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))?;
    for item in listing {
        let item = item?;
        let path = item.path();
        let name = item.file_name();
        let Some(name) = name.to_str() else {
            bail!("{}: file names in an FMU must be UTF-8", path.display());
        };
        if name.starts_with('.') {
            continue;
        }
        let meta = fs::metadata(&path).with_context(|| format!("reading {}", path.display()))?;
        if meta.is_dir() {
            collect_files(base, &path, prefix, entries)?;
        } else if meta.is_file() {
            let relative = path.strip_prefix(base).expect("walked from base");
            let parts: Vec<&str> = relative
                .iter()
                .map(|p| p.to_str().expect("checked UTF-8"))
                .collect();
            let data = fs::read(&path).with_context(|| format!("reading {}", path.display()))?;
            entries.push(Entry {
                name: format!("{prefix}/{}", parts.join("/")),
                data,
                mode: 0o644,
            });
        }
    }
    Ok(())
}

/// The archive bytes: entries sorted by name, deflated, with fixed timestamps and permissions.
fn zip_entries(mut entries: Vec<Entry>) -> Result<Vec<u8>> {
    entries.sort_by(|a, b| a.name.cmp(&b.name));
    if let Some(w) = entries.windows(2).find(|w| w[0].name == w[1].name) {
        bail!("two files would be stored as {}", w[0].name);
    }
    let mut zip = ZipWriter::new(Cursor::new(Vec::new()));
    for e in &entries {
        let options = SimpleFileOptions::default()
            .compression_method(CompressionMethod::Deflated)
            .last_modified_time(DateTime::default()) // 1980-01-01 00:00:00, the earliest DOS time
            .system(System::Unix)
            .unix_permissions(e.mode);
        zip.start_file(e.name.as_str(), options)
            .with_context(|| format!("adding {}", e.name))?;
        zip.write_all(&e.data)?;
    }
    Ok(zip.finish()?.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<Entry> {
        vec![
            Entry {
                name: "resources/b.toml".into(),
                data: b"x = 1\n".to_vec(),
                mode: 0o644,
            },
            Entry {
                name: "binaries/linux64/M.so".into(),
                data: vec![0x7f; 1000],
                mode: 0o755,
            },
            Entry {
                name: "modelDescription.xml".into(),
                data: b"<a/>".to_vec(),
                mode: 0o644,
            },
        ]
    }

    #[test]
    fn archive_is_reproducible_sorted_and_deflated() {
        let a = zip_entries(sample()).unwrap();
        let mut reversed = sample();
        reversed.reverse();
        assert_eq!(
            a,
            zip_entries(reversed).unwrap(),
            "input order or time must not change the bytes"
        );

        let mut archive = zip::ZipArchive::new(Cursor::new(a)).unwrap();
        let names: Vec<String> = archive
            .file_names()
            .map(|n| n.unwrap().into_owned())
            .collect();
        let mut sorted = names.clone();
        sorted.sort();
        assert_eq!(names, sorted);
        for i in 0..archive.len() {
            let f = archive.by_index(i).unwrap();
            assert_eq!(f.compression(), CompressionMethod::Deflated);
            assert_eq!(f.last_modified(), Some(DateTime::default()));
            let name = f.name().unwrap().into_owned();
            let expected = if name.ends_with(".so") { 0o755 } else { 0o644 };
            assert_eq!(f.unix_mode().map(|m| m & 0o777), Some(expected), "{name}");
        }
    }

    #[test]
    fn duplicate_names_are_refused() {
        let mut e = sample();
        e.push(Entry {
            name: "modelDescription.xml".into(),
            data: vec![],
            mode: 0o644,
        });
        assert!(zip_entries(e).is_err());
    }

    #[test]
    fn export_check_names_missing_functions() {
        let functions = "fmi2Instantiate\nfmi2DoStep\nfmi2Terminate\n";
        let mut fake = b"junk\0fmi2Instantiate\0fmi2Terminate\0".to_vec();
        let err = check_exports(&fake, functions).unwrap_err().to_string();
        assert!(
            err.contains("fmi2DoStep") && err.contains("1 FMI function"),
            "{err}"
        );
        fake.extend_from_slice(b"fmi2DoStep\0");
        check_exports(&fake, functions).unwrap();
    }
}
