//! Reading the files a user hands the orchestrator (signal CSVs, results.csv, SSP documents)
//! without trusting them: a device or FIFO named by mistake (`/dev/zero`) would otherwise be
//! read until memory runs out, and a file is never read past its limit even if it grows while
//! being read.

use std::fs::File;
use std::io::{Error, ErrorKind, Read};
use std::path::Path;

/// Limit for CSV inputs: 4 GiB, far above an hour of 1 kHz signals in a dozen columns (~1 GB).
pub const CSV_LIMIT: u64 = 1 << 32;

/// Limit for an SSP document (XML): 256 MiB.
pub const XML_LIMIT: u64 = 1 << 28;

/// The metadata of `path`, refused unless it is a regular file: checked before anything opens
/// it (a FIFO would block, a device never end).
pub fn regular_file(path: &Path) -> std::io::Result<std::fs::Metadata> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(Error::new(ErrorKind::InvalidInput, "not a regular file"));
    }
    Ok(meta)
}

/// The bytes of the regular file `path`, refused when it is not a regular file or holds more
/// than `limit` bytes.
pub fn read_bytes(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    let meta = regular_file(path)?;
    let too_big = |len: u64| {
        Error::new(
            ErrorKind::InvalidData,
            format!("{len} bytes, more than the limit of {limit}"),
        )
    };
    if meta.len() > limit {
        return Err(too_big(meta.len()));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    File::open(path)?.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_big(bytes.len() as u64));
    }
    Ok(bytes)
}

/// [`read_bytes`] as UTF-8 text.
pub fn read_text(path: &Path, limit: u64) -> std::io::Result<String> {
    String::from_utf8(read_bytes(path, limit)?).map_err(|e| {
        Error::new(
            ErrorKind::InvalidData,
            format!("stream did not contain valid UTF-8 ({})", e.utf8_error()),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_directories_and_oversized_files_are_refused() {
        let e = read_bytes(Path::new("/dev/zero"), 10).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let e = read_bytes(dir.path(), 10).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
        let path = dir.path().join("big.csv");
        std::fs::write(&path, [b'x'; 11]).unwrap();
        let e = read_bytes(&path, 10).unwrap_err();
        assert!(
            e.to_string()
                .contains("11 bytes, more than the limit of 10"),
            "{e}"
        );
        assert_eq!(read_bytes(&path, 11).unwrap().len(), 11);
        std::fs::write(&path, b"a,\xff\n").unwrap();
        let e = read_text(&path, 11).unwrap_err();
        assert!(e.to_string().contains("valid UTF-8"), "{e}");
    }
}
