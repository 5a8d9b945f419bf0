//! The files an SSP description reads: text files (UTF-8, size-limited), paths made absolute
//! and normal, and .ssp archives extracted under the zip-bomb limits.

use std::fs;
use std::io;
use std::path::{Component as PathPart, Path, PathBuf};

use model_description::xml::line_column;

use super::super::error::SspError;

pub(super) fn in_file(path: PathBuf, e: SspError) -> SspError {
    SspError::InFile {
        path,
        source: Box::new(e),
    }
}

pub(super) fn read_text(path: &Path, shown: &Path) -> Result<String, SspError> {
    let bytes =
        crate::input::read_bytes(path, crate::input::XML_LIMIT).map_err(|source| SspError::Io {
            path: shown.to_path_buf(),
            source,
        })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        // Where the first bad byte is, as a line and column of the valid text before it.
        let valid = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let before = std::str::from_utf8(&bytes[..valid]).unwrap_or_default();
        let (line, column) = line_column(before, valid);
        in_file(
            shown.to_path_buf(),
            SspError::Xml {
                line,
                column,
                message: format!(
                    "byte 0x{:02X} (offset {valid}) is not UTF-8; SSP files must be UTF-8",
                    bytes[valid]
                ),
            },
        )
    })?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

pub(super) fn absolute(p: &Path) -> Result<PathBuf, SspError> {
    std::path::absolute(p)
        .map(|p| normalize(&p))
        .map_err(|source| SspError::Io {
            path: p.to_path_buf(),
            source,
        })
}

/// Removes `.` and resolves `..` lexically.
pub(super) fn normalize(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for part in p.components() {
        match part {
            PathPart::CurDir => {}
            PathPart::ParentDir => {
                if !out.pop() {
                    out.push("..");
                }
            }
            other => out.push(other.as_os_str()),
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Archives

pub(super) fn is_archive(path: &Path) -> Result<bool, SspError> {
    crate::input::regular_file(path).map_err(|source| SspError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ssp"))
    {
        return Ok(true);
    }
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ssd"))
    {
        return Ok(false);
    }
    let mut magic = [0u8; 4];
    let mut file = fs::File::open(path).map_err(|source| SspError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    use std::io::Read;
    let n = file.read(&mut magic).map_err(|source| SspError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(n == 4 && magic == *b"PK\x03\x04")
}

/// Extracts every entry of the archive into `dir`, refusing the whole archive if any entry's
/// name is absolute or climbs out with `..`, or if it is a zip bomb: more entries or more
/// declared uncompressed bytes than fmi-import's [`UnpackLimits::DEFAULT`] (the FMUs inside
/// are unpacked under the same limits later), or an entry that decompresses to more than it
/// declares (cut off one byte past its declared size).
///
/// [`UnpackLimits::DEFAULT`]: fmi_import::UnpackLimits::DEFAULT
pub(super) fn extract(archive: &Path, dir: &Path) -> Result<(), SspError> {
    let limits = fmi_import::UnpackLimits::DEFAULT;
    let bad = |message: String| SspError::Archive {
        path: archive.to_path_buf(),
        message,
    };
    let file = fs::File::open(archive).map_err(|source| SspError::Io {
        path: archive.to_path_buf(),
        source,
    })?;
    let mut zip = zip::ZipArchive::new(io::BufReader::new(file)).map_err(|e| bad(e.to_string()))?;
    if zip.len() > limits.max_entries {
        return Err(bad(format!(
            "it has {} entries, more than the limit of {}",
            zip.len(),
            limits.max_entries
        )));
    }
    // Check every name (and the declared sizes) before writing anything.
    let mut entries = Vec::with_capacity(zip.len());
    let mut declared_total: u64 = 0;
    for i in 0..zip.len() {
        let entry = zip
            .by_index_raw(i)
            .map_err(|e| bad(format!("entry {i}: {e}")))?;
        let name = entry
            .name()
            .map_err(|e| bad(format!("entry {i}: {e}")))?
            .into_owned();
        declared_total = declared_total.saturating_add(entry.size());
        if declared_total > limits.max_total_bytes {
            return Err(bad(format!(
                "entry '{name}' declares {} bytes, which brings the uncompressed total to {declared_total} bytes, more than the limit of {} bytes",
                entry.size(),
                limits.max_total_bytes
            )));
        }
        let declared = entry.size();
        let absolute_name = name.starts_with('/')
            || name.starts_with('\\')
            || name.as_bytes().get(1) == Some(&b':');
        match entry.enclosed_name() {
            Some(rel) if !absolute_name && !name.contains('\\') => {
                entries.push((rel, entry.is_dir(), declared))
            }
            _ => {
                return Err(SspError::UnsafeEntry {
                    path: archive.to_path_buf(),
                    entry: name,
                });
            }
        }
    }
    for (i, (rel, is_dir, declared)) in entries.into_iter().enumerate() {
        let target = dir.join(&rel);
        let io_err = |source| SspError::Io {
            path: archive.join(&rel),
            source,
        };
        if is_dir {
            fs::create_dir_all(&target).map_err(io_err)?;
            continue;
        }
        if let Some(parent) = target.parent() {
            fs::create_dir_all(parent).map_err(io_err)?;
        }
        let mut entry = zip
            .by_index(i)
            .map_err(|e| bad(format!("entry '{}': {e}", rel.display())))?;
        let mut out = fs::File::create(&target).map_err(io_err)?;
        let written = io::copy(&mut io::Read::take(&mut entry, declared + 1), &mut out)
            .map_err(|e| bad(format!("cannot extract entry '{}': {e}", rel.display())))?;
        if written > declared {
            return Err(bad(format!(
                "entry '{}' decompresses to more than the {declared} bytes it declares (a corrupt or crafted archive)",
                rel.display()
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalization_is_lexical() {
        assert_eq!(normalize(Path::new("/a/./b/../c")), PathBuf::from("/a/c"));
    }
}
