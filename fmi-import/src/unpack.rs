//! Unpacking an `.fmu` archive safely.
//!
//! Every entry is checked before anything is written: an archive with one bad entry leaves no
//! files behind. Refused: absolute paths (`/x`, `C:x`), `..` components, backslashes (FMI
//! archives use forward slashes; on Windows a backslash is a separator), NUL, symbolic links
//! and other special files (by the unix mode stored in the entry), and names that appear
//! twice. Entries are then written with `create_new` under a fresh directory, so nothing
//! outside it is ever opened for writing.
//!
//! Zip bombs: the archive is refused before anything is written when it has more entries than
//! [`UnpackLimits::max_entries`] or when the uncompressed sizes its entries declare add up to
//! more than [`UnpackLimits::max_total_bytes`]. Declared sizes can lie, so while extracting,
//! every entry is cut off one byte past its declared size and refused if it reaches it: the
//! bytes written never exceed the declared total, hence never the limit.

use crate::error::ImportError;
use std::collections::{BTreeSet, HashSet};
use std::fs::{self, File};
use std::io::{self, BufReader, Read};
use std::path::{Path, PathBuf};
use zip::ZipArchive;

const S_IFMT: u32 = 0o170_000;
const S_IFLNK: u32 = 0o120_000;
const S_IFREG: u32 = 0o100_000;
const S_IFDIR: u32 = 0o040_000;

/// How much an archive may unpack to. The defaults are far above any real FMU (the largest
/// FMUs with lookup tables or embedded solvers unpack to a few hundred MB, with a few thousand
/// files) and far below what would fill a disk or a memory-backed temporary directory by
/// accident.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UnpackLimits {
    /// The sum of the entries' uncompressed sizes, in bytes (default 4 GiB).
    pub max_total_bytes: u64,
    /// The number of entries, directories included (default 100 000).
    pub max_entries: usize,
    /// The size of `modelDescription.xml`, which is read into memory and parsed into a tree
    /// several times its size (default 256 MiB; descriptions with 100 000 variables are about
    /// 50 MB).
    pub max_model_description_bytes: u64,
}

impl UnpackLimits {
    /// The limits [`Fmu::open`](crate::Fmu::open) applies; as a `const` so callers can
    /// change one field with `..UnpackLimits::DEFAULT`.
    pub const DEFAULT: UnpackLimits = UnpackLimits {
        max_total_bytes: 4 << 30,
        max_entries: 100_000,
        max_model_description_bytes: 256 << 20,
    };
}

impl Default for UnpackLimits {
    fn default() -> UnpackLimits {
        UnpackLimits::DEFAULT
    }
}

/// Bytes in a readable unit for messages ("4 GiB", "1.5 MiB", "12 bytes").
pub(crate) fn bytes(n: u64) -> String {
    const UNITS: [(&str, u64); 3] = [("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)];
    for (name, size) in UNITS {
        if n >= size {
            let x = n as f64 / size as f64;
            return if n.is_multiple_of(size) {
                format!("{} {name}", n / size)
            } else {
                format!("{x:.1} {name} ({n} bytes)")
            };
        }
    }
    format!("{n} bytes")
}

/// What the unpacked archive holds, as far as opening the FMU needs to know.
pub(crate) struct Unpacked {
    /// The folders under `binaries/`, sorted.
    pub platforms: Vec<String>,
}

/// One checked entry: its index and its path relative to the unpack directory.
struct Planned {
    index: usize,
    name: String,
    relative: PathBuf,
    dir: bool,
    /// The uncompressed size the archive declares.
    declared: u64,
}

/// The name shown in errors: the stored name with NUL made visible.
fn shown(raw: &[u8]) -> String {
    String::from_utf8_lossy(raw).replace('\0', "\\0")
}

/// Why an entry name is unsafe, or its normalized components.
fn check_name<'a>(name: &'a str, raw: &[u8]) -> Result<Vec<&'a str>, &'static str> {
    if raw.contains(&0) || name.contains('\0') {
        return Err("contains a NUL character");
    }
    if name.contains('\\') {
        return Err("contains a backslash (FMU archives must use forward slashes)");
    }
    if name.starts_with('/') {
        return Err("is an absolute path");
    }
    let first = name.split('/').next().unwrap_or("");
    if first.contains(':') {
        return Err("starts with a drive or scheme prefix (an absolute path on Windows)");
    }
    let mut parts = Vec::new();
    for part in name.split('/') {
        match part {
            "" | "." => {}
            ".." => return Err("contains a '..' component (it would escape the FMU directory)"),
            p => parts.push(p),
        }
    }
    if parts.is_empty() && !name.ends_with('/') {
        return Err("has an empty name");
    }
    Ok(parts)
}

fn check_mode(mode: Option<u32>) -> Result<(), &'static str> {
    let Some(mode) = mode else { return Ok(()) };
    match mode & S_IFMT {
        0 | S_IFREG | S_IFDIR => Ok(()),
        S_IFLNK => Err("is a symbolic link"),
        _ => Err("is a special file (device, FIFO or socket)"),
    }
}

/// Checks every entry of `fmu`, then extracts all of them into `dir`.
pub(crate) fn unpack(
    fmu: &Path,
    dir: &Path,
    limits: &UnpackLimits,
) -> Result<Unpacked, ImportError> {
    let file = File::open(fmu).map_err(|source| ImportError::Io {
        path: fmu.to_path_buf(),
        action: "cannot open the FMU file".into(),
        source,
    })?;
    let archive_error = |source| ImportError::Archive {
        path: fmu.to_path_buf(),
        source,
    };
    let mut zip = ZipArchive::new(BufReader::new(file)).map_err(archive_error)?;
    let too_large = |entry: Option<String>, what: String| ImportError::TooLarge {
        path: fmu.to_path_buf(),
        entry,
        what,
    };
    if zip.len() > limits.max_entries {
        return Err(too_large(
            None,
            format!(
                "the archive has {} entries, more than the limit of {}",
                zip.len(),
                limits.max_entries
            ),
        ));
    }

    // Pass 1: check everything, extract nothing.
    let mut plan = Vec::with_capacity(zip.len());
    let mut declared_total: u64 = 0;
    let mut seen = HashSet::new();
    let mut platforms = BTreeSet::new();
    let mut has_model_description = false;
    for index in 0..zip.len() {
        let entry = zip.by_index_data(index).map_err(archive_error)?;
        let raw = entry.name_raw();
        let unsafe_entry = |reason| ImportError::UnsafeEntry {
            path: fmu.to_path_buf(),
            entry: shown(raw),
            reason,
        };
        let name = entry.name().map_err(archive_error)?.into_owned();
        let parts = check_name(&name, raw).map_err(unsafe_entry)?;
        check_mode(entry.unix_mode()).map_err(unsafe_entry)?;
        declared_total = declared_total.saturating_add(entry.size());
        if declared_total > limits.max_total_bytes {
            return Err(too_large(
                Some(shown(raw)),
                format!(
                    "entry '{}' declares {}, which brings the uncompressed total to {}, more than the limit of {}",
                    shown(raw),
                    bytes(entry.size()),
                    bytes(declared_total),
                    bytes(limits.max_total_bytes)
                ),
            ));
        }
        let dir = name.ends_with('/') || entry.unix_mode().is_some_and(|m| m & S_IFMT == S_IFDIR);
        if parts.is_empty() {
            continue; // "./": the unpack directory itself
        }
        let normalized = parts.join("/");
        if !seen.insert(normalized.clone()) && !dir {
            return Err(unsafe_entry("appears twice in the archive"));
        }
        if normalized == "modelDescription.xml" && !dir {
            has_model_description = true;
            if entry.size() > limits.max_model_description_bytes {
                return Err(too_large(
                    Some(shown(raw)),
                    format!(
                        "modelDescription.xml declares {}, more than the limit of {}",
                        bytes(entry.size()),
                        bytes(limits.max_model_description_bytes)
                    ),
                ));
            }
        }
        if let ["binaries", platform, ..] = parts.as_slice()
            && (parts.len() > 2 || dir)
        {
            platforms.insert(platform.to_string());
        }
        plan.push(Planned {
            index,
            name: shown(raw),
            relative: parts.iter().collect(),
            dir,
            declared: entry.size(),
        });
    }
    if zip.has_duplicate_names() {
        return Err(archive_error(zip::result::ZipError::InvalidArchive(
            "the central directory lists the same entry name more than once".into(),
        )));
    }
    if !has_model_description {
        return Err(ImportError::MissingModelDescription {
            path: fmu.to_path_buf(),
        });
    }

    // Pass 2: extract.
    for p in plan {
        let extract_error = |source| ImportError::Extract {
            path: fmu.to_path_buf(),
            entry: p.name.clone(),
            source,
        };
        let target = dir.join(&p.relative);
        if p.dir {
            fs::create_dir_all(&target).map_err(extract_error)?;
            continue;
        }
        if let Some(parent) = target.parent() {
            fs::create_dir_all(parent).map_err(extract_error)?;
        }
        let mut entry = zip.by_index(p.index).map_err(archive_error)?;
        let mut out = File::create_new(&target).map_err(extract_error)?;
        // One byte more than declared tells a lying size from an honest one.
        let written =
            io::copy(&mut (&mut entry).take(p.declared + 1), &mut out).map_err(extract_error)?;
        if written > p.declared {
            return Err(too_large(
                Some(p.name.clone()),
                format!(
                    "entry '{}' decompresses to more than the {} it declares (a corrupt or crafted archive)",
                    p.name,
                    bytes(p.declared)
                ),
            ));
        }
    }
    Ok(Unpacked {
        platforms: platforms.into_iter().collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names() {
        fn ok(n: &str) -> Result<Vec<&str>, &'static str> {
            check_name(n, n.as_bytes())
        }
        assert_eq!(
            ok("binaries/linux64/a.so").unwrap(),
            ["binaries", "linux64", "a.so"]
        );
        assert_eq!(
            ok("./modelDescription.xml").unwrap(),
            ["modelDescription.xml"]
        );
        assert_eq!(ok("resources/").unwrap(), ["resources"]);
        assert!(ok("../evil").unwrap_err().contains(".."));
        assert!(ok("a/../../evil").unwrap_err().contains(".."));
        assert!(ok("/etc/passwd").unwrap_err().contains("absolute"));
        assert!(ok("C:/x").unwrap_err().contains("Windows"));
        assert!(ok("a\\b").unwrap_err().contains("backslash"));
        assert!(ok("a\0b").unwrap_err().contains("NUL"));
        assert!(ok("").is_err());
    }

    #[test]
    fn modes() {
        assert!(check_mode(None).is_ok());
        assert!(check_mode(Some(0o100_644)).is_ok());
        assert!(check_mode(Some(0o040_755)).is_ok());
        assert!(check_mode(Some(0o644)).is_ok());
        assert_eq!(check_mode(Some(0o120_777)), Err("is a symbolic link"));
        assert!(check_mode(Some(0o140_777)).unwrap_err().contains("special"));
    }
}
