//! fmuResourceLocation, as importers actually send it (fmi.md section 5).
//!
//! fmpy sends `file:///tmp/x/resources` percent-encoded without a trailing slash, the FMI
//! Library `file://` + an absolute path, fmusim adds a trailing slash, and some tools send
//! `file:/abs/path`, four slashes, or `file://localhost/...`. A plain absolute path is accepted
//! too. Anything else gives `None` and the caller logs what it got.

use std::path::PathBuf;

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
    use super::resource_dir;
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
}
