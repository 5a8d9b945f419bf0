//! Hostile archives: random bytes, mutated zips, random entry names (traversal, absolute paths,
//! drive letters, backslashes, NUL), and zip bombs (too many entries, too large declared sizes,
//! entries that decompress to more than they declare). The properties: `Fmu::open` never
//! panics; every error names the .fmu file; nothing is ever written outside the unpack
//! directory, which is gone once the call returns an error.
//!
//! Case counts are small by default (CI); `PROPTEST_CASES=100000 cargo test -p fmi-import --test
//! archive_fuzz` runs a larger campaign.

#![allow(clippy::result_large_err)]

mod common;

use common::*;
use fmi_import::{Fmu, ImportError, UnpackLimits};
use proptest::prelude::*;
use proptest::test_runner::Config;
use std::io::Write;
use std::path::{Path, PathBuf};

fn config(default_cases: u32) -> Config {
    let mut c = Config::default();
    if std::env::var_os("PROPTEST_CASES").is_none() {
        c.cases = default_cases;
    }
    c
}

/// A small archive that unpacks cleanly; its "binary" is not a library, so even a mutation that
/// keeps it intact ends in a load error, never in running foreign code.
fn seed_entries() -> Vec<Entry> {
    vec![
        file("modelDescription.xml", test_model_description(TEST_GUID)),
        Entry::Dir("resources/".into()),
        file(
            "resources/data.bin",
            (0..2000u32)
                .map(|i| (i * 7 % 251) as u8)
                .collect::<Vec<_>>(),
        ),
        Entry::Mode(
            format!("binaries/{PLATFORM}/TestFmu.{EXT}"),
            b"not a shared library".to_vec(),
            0o755,
        ),
    ]
}

/// Opens `fmu` with the unpack directory created in a fresh `parent`; checks the error names
/// the file and that nothing is left in `parent` or written beside the archive.
fn open_and_check(dir: &Path, fmu: &Path, limits: &UnpackLimits) -> Result<(), TestCaseError> {
    let parent = dir.join("unpack");
    std::fs::create_dir_all(&parent).unwrap();
    let before = listing(dir);
    let result = std::panic::catch_unwind(|| Fmu::open_with_limits_in(fmu, &parent, limits));
    let result = result.map_err(|_| TestCaseError::fail("Fmu::open panicked"))?;
    if let Err(e) = &result {
        let text = e.to_string();
        prop_assert!(
            text.contains(&fmu.display().to_string()),
            "error does not name the file: {}",
            text
        );
        prop_assert_eq!(e.fmu_path(), fmu);
    }
    drop(result);
    prop_assert_eq!(listing(dir), before, "files appeared beside the archive");
    prop_assert_eq!(
        std::fs::read_dir(&parent).unwrap().count(),
        0,
        "the unpack directory was left behind"
    );
    Ok(())
}

fn listing(dir: &Path) -> Vec<PathBuf> {
    let mut out = vec![];
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p.clone());
            }
            out.push(p);
        }
    }
    out.sort();
    out
}

/// Entry names built from the pieces that make names dangerous.
fn entry_name() -> impl Strategy<Value = String> {
    let part = prop_oneof![
        Just("..".to_string()),
        Just(".".to_string()),
        Just(String::new()),
        Just("resources".to_string()),
        Just("binaries".to_string()),
        Just("C:".to_string()),
        Just("c:evil".to_string()),
        Just("a\\..\\..\\b".to_string()),
        Just("a\0b".to_string()),
        Just("é\u{202e}txt".to_string()),
        Just("modelDescription.xml".to_string()),
        Just("~".to_string()),
        "[a-z]{1,6}",
    ];
    (
        any::<bool>(),
        prop::collection::vec(part, 1..5),
        any::<bool>(),
    )
        .prop_map(|(absolute, parts, dir)| {
            let mut name = parts.join("/");
            if absolute {
                name.insert(0, '/');
            }
            if dir {
                name.push('/');
            }
            name
        })
}

#[derive(Debug, Clone)]
enum Mutation {
    Truncate(prop::sample::Index),
    Flip(prop::sample::Index, u8),
    Delete(prop::sample::Index, usize),
    Duplicate(prop::sample::Index, usize),
    Insert(prop::sample::Index, Vec<u8>),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    use prop::sample::Index;
    prop_oneof![
        any::<Index>().prop_map(Mutation::Truncate),
        (any::<Index>(), 1u8..=255).prop_map(|(i, x)| Mutation::Flip(i, x)),
        (any::<Index>(), 1usize..64).prop_map(|(i, n)| Mutation::Delete(i, n)),
        (any::<Index>(), 1usize..256).prop_map(|(i, n)| Mutation::Duplicate(i, n)),
        (any::<Index>(), prop::collection::vec(any::<u8>(), 1..16))
            .prop_map(|(i, b)| Mutation::Insert(i, b)),
    ]
}

fn mutate(bytes: &mut Vec<u8>, m: &Mutation) {
    if bytes.is_empty() {
        return;
    }
    match m {
        Mutation::Truncate(i) => bytes.truncate(i.index(bytes.len())),
        Mutation::Flip(i, x) => {
            let i = i.index(bytes.len());
            bytes[i] ^= x;
        }
        Mutation::Delete(i, n) => {
            let i = i.index(bytes.len());
            bytes.drain(i..(i + n).min(bytes.len()));
        }
        Mutation::Duplicate(i, n) => {
            let i = i.index(bytes.len());
            let end = (i + n).min(bytes.len());
            let copy = bytes[i..end].to_vec();
            bytes.splice(end..end, copy);
        }
        Mutation::Insert(i, b) => {
            let i = i.index(bytes.len() + 1);
            bytes.splice(i..i, b.iter().copied());
        }
    }
}

proptest! {
    #![proptest_config(config(64))]

    #[test]
    fn random_bytes_are_refused_by_name(bytes in prop::collection::vec(any::<u8>(), 0..4096), zip_magic in any::<bool>()) {
        let dir = scratch();
        let path = dir.path().join("random.fmu");
        let mut bytes = bytes;
        if zip_magic {
            bytes.splice(0..0, *b"PK\x03\x04");
        }
        std::fs::write(&path, &bytes).unwrap();
        open_and_check(dir.path(), &path, &UnpackLimits::DEFAULT)?;
    }

    #[test]
    fn mutated_archives_never_panic(mutations in prop::collection::vec(mutation(), 1..4)) {
        let dir = scratch();
        let path = dir.path().join("mutated.fmu");
        write_zip(&path, &seed_entries());
        let mut bytes = std::fs::read(&path).unwrap();
        for m in &mutations {
            mutate(&mut bytes, m);
        }
        std::fs::write(&path, &bytes).unwrap();
        open_and_check(dir.path(), &path, &UnpackLimits::DEFAULT)?;
    }

    /// Whatever the names, nothing lands outside the unpack directory, and an unsafe name is
    /// refused naming the entry.
    #[test]
    fn entry_names_never_escape(names in prop::collection::vec(entry_name(), 1..4)) {
        let dir = scratch();
        let path = dir.path().join("names.fmu");
        let mut entries = seed_entries();
        for n in &names {
            entries.push(if n.ends_with('/') { Entry::Dir(n.clone()) } else { file(n, "x") });
        }
        // The zip writer refuses some names (e.g. duplicates); such archives cannot be built.
        let built = std::panic::catch_unwind(|| write_zip(&path, &entries)).is_ok();
        prop_assume!(built);
        open_and_check(dir.path(), &path, &UnpackLimits::DEFAULT)?;
        let result = Fmu::open(&path);
        let unsafe_name = names.iter().any(|n| {
            n.starts_with('/')
                || n.contains('\\')
                || n.contains('\0')
                || n.split('/').next().is_some_and(|first| first.contains(':'))
                || n.split('/').any(|p| p == "..")
        });
        if unsafe_name {
            match result {
                Err(ImportError::UnsafeEntry { entry, .. }) => {
                    prop_assert!(names.iter().any(|n| *n == entry.replace("\\0", "\0")), "{}", entry)
                }
                other => prop_assert!(false, "expected UnsafeEntry for {:?}, got {:?}", names, other.err()),
            }
        }
    }
}

// ---- zip bombs -------------------------------------------------------------------------------

/// Rewrites the uncompressed size that `entry` declares, in its local header and its
/// central-directory record.
fn set_declared_size(path: &Path, entry: &str, size: u32) {
    let mut bytes = std::fs::read(path).unwrap();
    let mut patched = 0;
    let mut i = 0;
    while i + 46 <= bytes.len() {
        let sig = &bytes[i..i + 4];
        let (name_at, size_at) = if sig == [0x50, 0x4b, 0x03, 0x04] {
            (30, 22)
        } else if sig == [0x50, 0x4b, 0x01, 0x02] {
            (46, 24)
        } else {
            i += 1;
            continue;
        };
        let len_at = if name_at == 30 { 26 } else { 28 };
        let name_len = u16::from_le_bytes([bytes[i + len_at], bytes[i + len_at + 1]]) as usize;
        if bytes.get(i + name_at..i + name_at + name_len) == Some(entry.as_bytes()) {
            bytes[i + size_at..i + size_at + 4].copy_from_slice(&size.to_le_bytes());
            patched += 1;
        }
        i += 1;
    }
    assert_eq!(patched, 2, "local and central records of {entry}");
    std::fs::write(path, bytes).unwrap();
}

fn too_large(path: &Path, limits: &UnpackLimits) -> (Option<String>, String) {
    let dir = path.parent().unwrap();
    let parent = dir.join("unpack");
    std::fs::create_dir_all(&parent).unwrap();
    let err = Fmu::open_with_limits_in(path, &parent, limits).unwrap_err();
    assert_eq!(
        std::fs::read_dir(&parent).unwrap().count(),
        0,
        "left files behind"
    );
    let text = err.to_string();
    assert!(text.contains(&path.display().to_string()), "{text}");
    match err {
        ImportError::TooLarge { entry, .. } => (entry, text),
        other => panic!("expected TooLarge, got {other:?}"),
    }
}

#[test]
fn declared_sizes_over_the_limit_are_refused_before_writing() {
    let dir = scratch();
    let path = dir.path().join("Big.fmu");
    write_zip(
        &path,
        &[
            file("modelDescription.xml", test_model_description(TEST_GUID)),
            file("resources/a.bin", vec![0u8; 600]),
            file("resources/b.bin", vec![0u8; 600]),
        ],
    );
    let md = test_model_description(TEST_GUID).len() as u64;
    let limits = UnpackLimits {
        max_total_bytes: md + 1000,
        ..UnpackLimits::DEFAULT
    };
    let (entry, text) = too_large(&path, &limits);
    assert_eq!(entry.as_deref(), Some("resources/b.bin"));
    assert!(
        text.contains(&format!(
            "entry 'resources/b.bin' declares 600 bytes, which brings the uncompressed total to {}, more than the limit of {}",
            fmt_bytes(md + 1200),
            fmt_bytes(md + 1000)
        )),
        "{text}"
    );
    // At exactly the total it unpacks (and fails later, for want of a binary).
    let exact = UnpackLimits {
        max_total_bytes: md + 1200,
        max_entries: 3,
        ..UnpackLimits::DEFAULT
    };
    let err = Fmu::open_with_limits(&path, &exact).unwrap_err();
    assert!(matches!(err, ImportError::MissingBinary { .. }), "{err:?}");
}

#[test]
fn a_model_description_over_its_limit_is_refused() {
    let dir = scratch();
    let path = dir.path().join("BigXml.fmu");
    let md = test_model_description(TEST_GUID);
    write_zip(&path, &[file("modelDescription.xml", md.clone())]);
    let limits = UnpackLimits {
        max_model_description_bytes: md.len() as u64 - 1,
        ..UnpackLimits::DEFAULT
    };
    let (entry, text) = too_large(&path, &limits);
    assert_eq!(entry.as_deref(), Some("modelDescription.xml"));
    assert!(
        text.contains(&format!(
            "modelDescription.xml declares {}, more than the limit of {}",
            fmt_bytes(md.len() as u64),
            fmt_bytes(md.len() as u64 - 1)
        )),
        "{text}"
    );
}

/// As the error messages write sizes.
fn fmt_bytes(n: u64) -> String {
    if n >= 1024 {
        format!("{:.1} KiB ({n} bytes)", n as f64 / 1024.0)
    } else {
        format!("{n} bytes")
    }
}

#[test]
fn too_many_entries_are_refused() {
    let dir = scratch();
    let path = dir.path().join("Many.fmu");
    let mut entries = vec![file(
        "modelDescription.xml",
        test_model_description(TEST_GUID),
    )];
    for i in 0..20 {
        entries.push(file(&format!("resources/{i}"), ""));
    }
    write_zip(&path, &entries);
    let limits = UnpackLimits {
        max_entries: 20,
        ..UnpackLimits::DEFAULT
    };
    let (entry, text) = too_large(&path, &limits);
    assert_eq!(entry, None);
    assert!(
        text.contains("the archive has 21 entries, more than the limit of 20"),
        "{text}"
    );
}

/// A bomb that lies: it declares 1000 bytes and decompresses to 50 MB. Only one byte more
/// than declared is ever written.
#[test]
fn an_entry_larger_than_declared_is_cut_off() {
    let dir = scratch();
    let path = dir.path().join("Liar.fmu");
    write_zip(
        &path,
        &[
            file("modelDescription.xml", test_model_description(TEST_GUID)),
            file("resources/bomb.bin", vec![0u8; 50 << 20]),
        ],
    );
    assert!(
        std::fs::metadata(&path).unwrap().len() < 200_000,
        "deflate packs zeros"
    );
    set_declared_size(&path, "resources/bomb.bin", 1000);
    let started = std::time::Instant::now();
    let parent = dir.path().join("unpack");
    std::fs::create_dir_all(&parent).unwrap();
    let err = Fmu::open_with_limits_in(&path, &parent, &UnpackLimits::DEFAULT).unwrap_err();
    assert!(started.elapsed().as_secs_f64() < 5.0);
    assert_eq!(std::fs::read_dir(&parent).unwrap().count(), 0);
    // The zip crate's reader stops at the declared size itself; unpack's own cut-off (one
    // byte past the declared size, ImportError::TooLarge) stands behind it.
    match &err {
        ImportError::Extract { entry, source, .. } => {
            assert_eq!(entry, "resources/bomb.bin");
            assert_eq!(
                source.to_string(),
                "File is larger than its declared uncompressed size"
            );
        }
        other => panic!("{other:?}"),
    }
    assert!(
        err.to_string().starts_with(&format!(
            "{}: cannot extract entry 'resources/bomb.bin': File is larger than its declared uncompressed size",
            path.display()
        )),
        "{err}"
    );
}

/// The default limit: entries declaring 1 GiB each (the data itself is tiny) are refused before
/// a byte is written.
#[test]
fn the_default_limit_refuses_five_declared_gigabytes() {
    let dir = scratch();
    let path = dir.path().join("Bomb.fmu");
    let mut entries = vec![file(
        "modelDescription.xml",
        test_model_description(TEST_GUID),
    )];
    for i in 0..5 {
        entries.push(file(&format!("resources/{i}.bin"), vec![0u8; 10]));
    }
    write_zip(&path, &entries);
    for i in 0..5 {
        set_declared_size(&path, &format!("resources/{i}.bin"), 1 << 30);
    }
    let (entry, text) = too_large(&path, &UnpackLimits::DEFAULT);
    // modelDescription.xml and four times 1 GiB are just over 4 GiB.
    assert_eq!(entry.as_deref(), Some("resources/3.bin"), "{text}");
    assert!(
        text.contains("entry 'resources/3.bin' declares 1 GiB, which brings the uncompressed total to 4.0 GiB (")
            && text.contains("bytes), more than the limit of 4 GiB"),
        "{text}"
    );
}

/// An honest archive of exactly the declared sizes unpacks.
#[test]
fn honest_sizes_unpack() {
    let dir = scratch();
    let path = dir.path().join("Honest.fmu");
    let mut zip = zip::ZipWriter::new(std::fs::File::create(&path).unwrap());
    let opts = zip::write::SimpleFileOptions::default();
    zip.start_file("modelDescription.xml", opts).unwrap();
    zip.write_all(test_model_description(TEST_GUID).as_bytes())
        .unwrap();
    zip.start_file("resources/empty", opts).unwrap();
    zip.finish().unwrap();
    let err = Fmu::open(&path).unwrap_err();
    assert!(matches!(err, ImportError::MissingBinary { .. }), "{err:?}");
}

/// A modelDescription.xml that is not UTF-8: the position of the first bad byte.
#[test]
fn a_model_description_not_in_utf8_names_the_position() {
    let dir = scratch();
    let path = dir.path().join("Latin1.fmu");
    let md = test_model_description(TEST_GUID)
        .replace("modelName=\"TestFmu\"", "modelName=\"T\u{e9}st\"");
    let latin1: Vec<u8> = md.chars().map(|c| c as u32 as u8).collect();
    write_zip(&path, &[file("modelDescription.xml", latin1)]);
    let err = Fmu::open(&path).unwrap_err();
    assert!(
        matches!(err, ImportError::ModelDescription { .. }),
        "{err:?}"
    );
    assert_eq!(
        err.to_string(),
        format!(
            "{}: modelDescription.xml: malformed XML at line 2, column 51: byte 0xE9 (offset 89) is not UTF-8; modelDescription.xml must be UTF-8",
            path.display()
        )
    );
}
