//! fmuResourceLocation, as importers actually send it (docs/references.md section 7.5).
//!
//! fmpy sends `file:///tmp/x/resources` percent-encoded without a trailing slash, the FMI
//! Library `file://` + an absolute path, fmusim adds a trailing slash, and some tools send
//! `file:/abs/path`, four slashes, or `file://localhost/...`. A plain absolute path is accepted
//! too. Anything else gives `None` and the caller logs what it got.

use std::io::Read;
use std::path::{Path, PathBuf};

/// Reads a text file a user named in a parameter, refusing what would hang or exhaust the
/// importer: anything but a regular file (a FIFO blocks on open, `/dev/zero` never ends) and
/// files above `limit` bytes. Messages start with the file, then say what it was meant to be
/// (`what`: "track file", "calibration file").
pub fn read_text(path: &Path, what: &str, limit: u64) -> Result<String, String> {
    let bytes = read_bytes(path, what, limit)?;
    String::from_utf8(bytes).map_err(|e| {
        format!(
            "{}: cannot read the {what}: stream did not contain valid UTF-8 (byte {})",
            path.display(),
            e.utf8_error().valid_up_to()
        )
    })
}

/// [`read_text`] for binary files: the same refusals, the bytes as they are.
pub fn read_bytes(path: &Path, what: &str, limit: u64) -> Result<Vec<u8>, String> {
    let shown = path.display();
    let cannot = |e: std::io::Error| format!("{shown}: cannot read the {what}: {e}");
    let meta = std::fs::metadata(path).map_err(cannot)?;
    if !meta.is_file() {
        return Err(format!("{shown}: the {what} is not a regular file"));
    }
    if meta.len() > limit {
        return Err(format!(
            "{shown}: the {what} has {} bytes, more than the limit of {limit}",
            meta.len()
        ));
    }
    let file = std::fs::File::open(path).map_err(cannot)?;
    // The length can change after the check (a growing file).
    let mut bytes = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(cannot)?;
    if bytes.len() as u64 > limit {
        return Err(format!(
            "{shown}: the {what} grew beyond {limit} bytes while being read"
        ));
    }
    Ok(bytes)
}

/// Reads `reader` to its end as UTF-8 text, but never more than `limit` bytes: `Ok(None)` when
/// there is more. For anything whose size is not known beforehand, or not to be trusted (a zip
/// entry's declared size, a file that grows, a device).
pub fn read_limited(reader: impl Read, limit: u64) -> std::io::Result<Option<String>> {
    let mut text = String::new();
    reader.take(limit + 1).read_to_string(&mut text)?;
    Ok((text.len() as u64 <= limit).then_some(text))
}

/// The resources directory the URI names, or `None` when it is not a local file location.
pub fn resource_dir(location: &str) -> Option<PathBuf> {
    let location = location.trim();
    if location.is_empty() {
        return None;
    }
    if location.starts_with('/') {
        return Some(PathBuf::from(location));
    }
    let scheme_ok = location
        .get(..5)
        .is_some_and(|s| s.eq_ignore_ascii_case("file:"));
    if !scheme_ok || location.len() == 5 {
        return None;
    }
    // `file:////abs` (four slashes) parses as a UNC-like host-less path; fold it to `file:///abs`.
    let mut normalized = location.to_string();
    while normalized.len() > 8 && normalized[5..].starts_with("////") {
        normalized.remove(5);
    }
    let url = url::Url::parse(&normalized).ok()?;
    let host_ok = matches!(url.host_str(), None | Some("") | Some("localhost"));
    if !host_ok {
        return None;
    }
    let mut path = url.to_file_path().ok()?;
    // A trailing slash parses to the same directory already; strip a stray empty component.
    if path.as_os_str().len() > 1 && path.to_string_lossy().ends_with('/') {
        path = PathBuf::from(path.to_string_lossy().trim_end_matches('/'));
    }
    Some(path)
}

#[cfg(test)]
mod tests {
    use super::{read_limited, read_text, resource_dir};
    use std::path::Path;
    use std::path::PathBuf;

    #[test]
    fn every_form_importers_send_is_understood() {
        let want = Some(PathBuf::from("/tmp/my fmu/resources"));
        for uri in [
            "file:///tmp/my%20fmu/resources",
            "file:///tmp/my%20fmu/resources/",
            "file://localhost/tmp/my%20fmu/resources",
            "file:/tmp/my%20fmu/resources",
            "file:////tmp/my%20fmu/resources",
            "FILE:///tmp/my%20fmu/resources",
            "/tmp/my fmu/resources",
        ] {
            assert_eq!(resource_dir(uri), want, "{uri}");
        }
    }

    #[test]
    fn non_local_locations_are_refused() {
        for uri in [
            "",
            "http://example.com/resources",
            "file://otherhost/tmp/x",
            "resources",
            "file:",
        ] {
            assert_eq!(resource_dir(uri), None, "{uri}");
        }
    }

    #[test]
    fn read_text_refuses_devices_directories_and_large_files() {
        let dir = tempfile::tempdir().unwrap();
        let ok = dir.path().join("a.csv");
        std::fs::write(&ok, "distance\n1\n").unwrap();
        assert_eq!(read_text(&ok, "track file", 100).unwrap(), "distance\n1\n");
        let e = read_text(&ok, "track file", 5).unwrap_err();
        assert!(
            e.ends_with("a.csv: the track file has 11 bytes, more than the limit of 5"),
            "{e}"
        );
        let e = read_text(dir.path(), "track file", 100).unwrap_err();
        assert!(e.ends_with(": the track file is not a regular file"), "{e}");
        let e = read_text(Path::new("/dev/zero"), "calibration file", 100).unwrap_err();
        assert_eq!(e, "/dev/zero: the calibration file is not a regular file");
        let e = read_text(&dir.path().join("missing"), "track file", 100).unwrap_err();
        assert!(e.contains("missing: cannot read the track file: "), "{e}");
        let bad = dir.path().join("bad.csv");
        std::fs::write(&bad, [0xff, 0xfe]).unwrap();
        assert!(
            read_text(&bad, "track file", 100)
                .unwrap_err()
                .contains("bad.csv")
        );
    }

    #[test]
    fn read_limited_stops_one_byte_past_the_limit() {
        assert_eq!(
            read_limited(&b"abcde"[..], 5).unwrap().as_deref(),
            Some("abcde")
        );
        assert_eq!(read_limited(&b"abcdef"[..], 5).unwrap(), None);
        // An endless reader ends too.
        assert_eq!(read_limited(std::io::repeat(b'a'), 1000).unwrap(), None);
        assert!(read_limited(&[0xffu8, 0xfe][..], 5).is_err());
    }
}
