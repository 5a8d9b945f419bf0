//! The fingerprint of an FMU build that its serialized FMU states carry
//! (`fmi_abi::Model::STATE_LAYOUT`), made by the FMU crate's build script.
//!
//! A serialized state is the instance's memory layout written out; a state saved by another
//! build, whose structs may differ, must be refused with a message rather than decoded into
//! wrong values. The layout follows from the sources (and any resources built into the
//! library), so the fingerprint is a hash of them:
//!
//! | part | hashed as |
//! |---|---|
//! | every `src/**/*.rs` but test-only `*_tests.rs` | its path relative to the crate (with `/`), then its text with CRLF as LF |
//! | each extra part (e.g. a built-in tap bank) | its name, then its bytes (text files: CRLF as LF) |
//!
//! The same commit gives the same fingerprint on every machine (a Windows checkout's CRLF line
//! ends are read as LF). Any edit of a hashed source, a comment included, gives a new one: a
//! saved state of the old build is then refused, which errs on the safe side. An untracked
//! scratch `.rs` file in `src/` counts too.
//!
//! The same fingerprint, extended by what else shapes the modelDescription.xml (the resources
//! that set parameter defaults, the crates that write the XML), gives the FMU its GUID
//! ([`Fingerprint::guid`]): a new one whenever the FMU changes.
//!
//! 64-bit FNV-1a, each part followed by its length so that parts cannot run into each other.
//! Not a cryptographic hash: it tells builds apart, it does not authenticate them.
//!
//! ```no_run
//! // build.rs of an FMU crate
//! let layout = state_layout::Fingerprint::of_fmu_crate();
//! println!("cargo::rustc-env=MY_STATE_LAYOUT={}", layout.hex());
//! println!("cargo::rustc-env=MY_GUID={}", layout.fmu_guid(&[]));
//! ```

use std::path::{Path, PathBuf};

/// A running 64-bit FNV-1a over length-delimited parts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fingerprint(u64);

impl Default for Fingerprint {
    fn default() -> Fingerprint {
        Fingerprint(0xcbf2_9ce4_8422_2325)
    }
}

impl Fingerprint {
    /// Adds one part.
    pub fn add(&mut self, bytes: &[u8]) {
        for b in bytes.iter().chain(&(bytes.len() as u64).to_le_bytes()) {
            self.0 = (self.0 ^ *b as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }

    /// Adds every `.rs` file under `crate_dir/src` (sorted by path) but the test-only
    /// `*_tests.rs`: its relative path, then its text with CRLF as LF.
    pub fn add_sources(&mut self, crate_dir: &Path) {
        let mut files = vec![];
        sources(&crate_dir.join("src"), &mut files);
        files.sort();
        for f in &files {
            let rel = f.strip_prefix(crate_dir).expect("under the crate");
            self.add(rel.to_string_lossy().replace('\\', "/").as_bytes());
            let bytes =
                std::fs::read(f).unwrap_or_else(|e| panic!("cannot read {}: {e}", f.display()));
            self.add(&lf(bytes));
        }
    }

    /// Adds another crate's sources (a path dependency that shapes the FMU, e.g. the one that
    /// writes its modelDescription.xml), telling cargo to run the build script again when they
    /// change.
    pub fn add_crate(&mut self, crate_dir: &Path) {
        println!(
            "cargo::rerun-if-changed={}",
            crate_dir.join("src").display()
        );
        self.add_sources(crate_dir);
    }

    /// Adds a text file (its name, then its text with CRLF as LF; an absent file as empty),
    /// telling cargo to run the build script again when it changes.
    pub fn add_text_file(&mut self, path: &Path) {
        println!("cargo::rerun-if-changed={}", path.display());
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
        self.add(name.unwrap_or_default().as_bytes());
        self.add(&lf(std::fs::read(path).unwrap_or_default()));
    }

    /// The fingerprint of the calling build script's crate sources (`CARGO_MANIFEST_DIR`),
    /// telling cargo to run the script again when they change.
    pub fn of_sources() -> Fingerprint {
        let mut f = Fingerprint::default();
        f.add_crate(&manifest_dir());
        f
    }

    /// The fingerprint of an FMU crate's serialized state, for its build script: its sources
    /// and the workspace's Cargo.lock (the encoding follows serde and postcard). Parts the
    /// crate builds into its library (tap banks) are added by the caller.
    pub fn of_fmu_crate() -> Fingerprint {
        let mut f = Fingerprint::of_sources();
        f.add_text_file(&workspace_dir().join("Cargo.lock"));
        f
    }

    /// The FMU's GUID: this fingerprint extended by what else reaches its modelDescription.xml:
    /// the package version, `resources` (text files that set parameter defaults) and the
    /// workspace crates that write the XML (`fmi-abi`, `modelDescription`).
    pub fn fmu_guid(mut self, resources: &[PathBuf]) -> String {
        self.add(
            std::env::var("CARGO_PKG_VERSION")
                .unwrap_or_default()
                .as_bytes(),
        );
        for r in resources {
            self.add_text_file(r);
        }
        for dep in ["fmi-abi", "modelDescription"] {
            self.add_crate(&workspace_dir().join(dep));
        }
        self.guid()
    }

    /// 16 lowercase hex digits.
    pub fn hex(&self) -> String {
        format!("{:016x}", self.0)
    }

    /// A GUID for the FMU this fingerprint describes, in the UUID form (RFC 9562, version 8:
    /// custom bits): the fingerprint's 64 bits and those of it continued by one more part
    /// (`"guid"`), with the version and variant bits set, no braces (libcosim #533). An FMU whose
    /// build inputs change gets a new GUID, as FMI 2.0 intends for a new modelDescription.xml.
    pub fn guid(&self) -> String {
        let mut more = *self;
        more.add(b"guid");
        let hi = (self.0 & !0xf000) | 0x8000; // version 8 in bits 48-51 of the UUID
        let lo = (more.0 & !(0b11 << 62)) | (0b10 << 62); // variant 10
        format!(
            "{:08x}-{:04x}-{:04x}-{:04x}-{:012x}",
            hi >> 32,
            (hi >> 16) & 0xffff,
            hi & 0xffff,
            lo >> 48,
            lo & 0xffff_ffff_ffff
        )
    }
}

/// The build script's crate (`CARGO_MANIFEST_DIR`).
fn manifest_dir() -> PathBuf {
    PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it"))
}

/// The workspace: the nearest directory above the crate that holds a Cargo.lock (the crate's
/// own parent when none does).
fn workspace_dir() -> PathBuf {
    let dir = manifest_dir();
    dir.ancestors()
        .skip(1)
        .find(|d| d.join("Cargo.lock").is_file())
        .unwrap_or_else(|| dir.parent().unwrap_or(&dir))
        .to_path_buf()
}

/// `bytes` with every CRLF as LF.
fn lf(bytes: Vec<u8>) -> Vec<u8> {
    if !bytes.windows(2).any(|w| w == b"\r\n") {
        return bytes;
    }
    let mut out = Vec::with_capacity(bytes.len());
    for (i, b) in bytes.iter().enumerate() {
        if !(*b == b'\r' && bytes.get(i + 1) == Some(&b'\n')) {
            out.push(*b);
        }
    }
    out
}

/// Every `.rs` file under `dir` but the test-only `*_tests.rs` (compiled only into tests).
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries =
        std::fs::read_dir(dir).unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()));
    for e in entries {
        let p = e.expect("a directory entry").path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs")
            && !p.to_string_lossy().ends_with("_tests.rs")
        {
            out.push(p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_published_fnv1a_values() {
        // FNV-1a 64 of "" and "a" (Fowler, Noll, Vo: the reference test vectors), before the
        // length suffix this crate adds; checked here through the raw state.
        let raw = |s: &[u8]| {
            let mut h: u64 = 0xcbf2_9ce4_8422_2325;
            for b in s {
                h = (h ^ *b as u64).wrapping_mul(0x0100_0000_01b3);
            }
            h
        };
        assert_eq!(raw(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(raw(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(raw(b"foobar"), 0x8594_4171_f739_67e8);
        // The crate's hash is the same function over the part and its length.
        let mut f = Fingerprint::default();
        f.add(b"a");
        let mut bytes = b"a".to_vec();
        bytes.extend(1u64.to_le_bytes());
        assert_eq!(f.0, raw(&bytes));
    }

    #[test]
    fn parts_do_not_run_into_each_other_and_order_matters() {
        let of = |parts: &[&[u8]]| {
            let mut f = Fingerprint::default();
            for p in parts {
                f.add(p);
            }
            f
        };
        assert_ne!(of(&[b"ab", b"c"]), of(&[b"a", b"bc"]));
        assert_ne!(of(&[b"a", b"b"]), of(&[b"b", b"a"]));
        assert_eq!(of(&[b"a", b"b"]), of(&[b"a", b"b"]));
        assert_eq!(of(&[b"x"]).hex().len(), 16);
    }

    #[test]
    fn the_guid_is_a_version_8_uuid_that_follows_the_fingerprint() {
        let of = |part: &[u8]| {
            let mut f = Fingerprint::default();
            f.add(part);
            f.guid()
        };
        let g = of(b"sources");
        let groups: Vec<&str> = g.split('-').collect();
        assert_eq!(
            groups.iter().map(|x| x.len()).collect::<Vec<_>>(),
            [8, 4, 4, 4, 12],
            "{g}"
        );
        assert!(
            g.chars()
                .all(|c| c == '-' || c.is_ascii_hexdigit() && !c.is_ascii_uppercase())
        );
        assert!(groups[2].starts_with('8'), "version 8: {g}");
        assert!("89ab".contains(&groups[3][..1]), "variant 10: {g}");
        assert_eq!(of(b"sources"), g);
        assert_ne!(of(b"sources, changed"), g);
    }

    #[test]
    fn a_changed_source_changes_the_fingerprint() {
        let dir = std::env::temp_dir().join(format!("state-layout-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("src/sub")).unwrap();
        std::fs::write(dir.join("src/lib.rs"), "pub struct A(u8);").unwrap();
        std::fs::write(dir.join("src/sub/b.rs"), "pub struct B;").unwrap();
        std::fs::write(dir.join("src/notes.txt"), "not a source").unwrap();
        let of = |d: &Path| {
            let mut f = Fingerprint::default();
            f.add_sources(d);
            f
        };
        let before = of(&dir);
        std::fs::write(dir.join("src/notes.txt"), "changed, still not a source").unwrap();
        std::fs::write(dir.join("src/sub/b_tests.rs"), "#[test] fn t() {}").unwrap();
        assert_eq!(
            of(&dir),
            before,
            "a text file and a test-only file do not count"
        );
        std::fs::write(dir.join("src/lib.rs"), "pub struct A(u8);\r\n").unwrap();
        let crlf = of(&dir);
        std::fs::write(dir.join("src/lib.rs"), "pub struct A(u8);\n").unwrap();
        assert_eq!(of(&dir), crlf, "CRLF and LF checkouts agree");
        std::fs::write(dir.join("src/lib.rs"), "pub struct A(u8);").unwrap();
        assert_eq!(of(&dir), before);
        std::fs::write(dir.join("src/sub/b.rs"), "pub struct B(u16);").unwrap();
        assert_ne!(of(&dir), before);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
