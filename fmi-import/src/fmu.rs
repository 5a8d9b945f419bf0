//! [`Fmu`]: an opened FMU (unpacked, described, loaded, checked).

use crate::error::ImportError;
use crate::instance::Instance;
use crate::library::{self, Functions, platform_binary};
use crate::logging::LogConfig;
use crate::unpack::{UnpackLimits, unpack};
use libloading::Library;
use model_description::{BaseType, ModelDescription, ScalarVariable};
use std::ffi::{CStr, CString, c_char};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use tempfile::TempDir;

/// An FMU unpacked in a temporary directory, with its model description and its loaded
/// library. Cheap to clone (shared); `Send + Sync`. The directory is removed and the library
/// unloaded when the last clone and the last [`Instance`] are gone (instances keep them alive,
/// since an FMU may read its resources at any time).
#[derive(Clone)]
pub struct Fmu {
    pub(crate) inner: Arc<FmuInner>,
}

/// Field order is drop order: the library is closed before its directory is removed.
pub(crate) struct FmuInner {
    pub(crate) functions: Functions,
    pub(crate) library: Arc<Library>,
    pub(crate) md: ModelDescription,
    pub(crate) model_identifier: String,
    pub(crate) path: PathBuf,
    pub(crate) guid: CString,
    pub(crate) resource_uri: CString,
    pub(crate) only_once: bool,
    /// Live instances, and the name of one, for canBeInstantiatedOnlyOncePerProcess.
    pub(crate) live: AtomicUsize,
    pub(crate) last_name: Mutex<String>,
    pub(crate) dir: TempDir,
}

const _: () = {
    const fn send_sync<T: Send + Sync>() {}
    send_sync::<Fmu>();
};

fn valid_identifier(id: &str) -> bool {
    !id.is_empty() && id != "." && id != ".." && !id.contains(['/', '\\', ':', '\0'])
}

/// The string a version function returned, for the error message.
unsafe fn returned(p: *const c_char) -> Option<String> {
    if p.is_null() {
        None
    } else {
        // SAFETY: the FMU returns a NUL-terminated static string.
        Some(unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
    }
}

/// What identifies an FMU file for [`Fmu::open_shared`]: its canonical path, size and
/// modification time (a file rebuilt in place is another FMU).
type FileKey = (PathBuf, u64, Option<std::time::SystemTime>);

/// The FMUs [`Fmu::open_shared`] opened, while a clone of each is alive.
static SHARED: Mutex<Vec<(FileKey, std::sync::Weak<FmuInner>)>> = Mutex::new(Vec::new());

impl Fmu {
    /// The FMU at `path` as [`open`](Fmu::open) gives it, or a clone of one this process opened
    /// from the same unchanged file through this function and still holds.
    ///
    /// Why: every [`open`](Fmu::open) unpacks and loads a new copy of the library, and a copy
    /// never gives back what its loading took: a Rust FMU's standard library takes thread-local
    /// keys (glibc has 1024 per process). A study that ran a few thousand co-simulations of the
    /// same two FMUs, each opening them anew, aborted with "out of TLS keys". Instances of one
    /// library are independent (FMI 2.0 requires it unless
    /// `canBeInstantiatedOnlyOncePerProcess`, which then holds across the clones too, as it
    /// should: the flag is about the process).
    pub fn open_shared(path: &Path) -> Result<Fmu, ImportError> {
        let key = std::fs::canonicalize(path).ok().and_then(|p| {
            let m = std::fs::metadata(&p).ok()?;
            Some((p, m.len(), m.modified().ok()))
        });
        let Some(key) = key else {
            // Opening reports why the file cannot be read.
            return Fmu::open(path);
        };
        let mut shared = SHARED.lock().unwrap_or_else(|e| e.into_inner());
        shared.retain(|(_, w)| w.strong_count() > 0);
        if let Some(inner) = shared
            .iter()
            .find(|(k, _)| *k == key)
            .and_then(|(_, w)| w.upgrade())
        {
            return Ok(Fmu { inner });
        }
        let fmu = Fmu::open(path)?;
        shared.push((key, Arc::downgrade(&fmu.inner)));
        Ok(fmu)
    }

    /// Unpacks `path` into a fresh temporary directory (in the system's temp dir), reads the
    /// model description, loads this platform's binary and checks it is an FMI 2.0
    /// co-simulation library. The archive may unpack to at most [`UnpackLimits::DEFAULT`].
    pub fn open(path: &Path) -> Result<Fmu, ImportError> {
        Fmu::open_with_limits(path, &UnpackLimits::DEFAULT)
    }

    /// Like [`open`](Fmu::open), with other limits on what the archive may unpack to.
    pub fn open_with_limits(path: &Path, limits: &UnpackLimits) -> Result<Fmu, ImportError> {
        let dir = tempfile::Builder::new()
            .prefix("fmi-import-")
            .tempdir()
            .map_err(|source| ImportError::Io {
                path: path.to_path_buf(),
                action: "cannot create a temporary directory to unpack into".into(),
                source,
            })?;
        Fmu::open_into(path, dir, limits)
    }

    /// Like [`open`](Fmu::open), with the temporary directory created inside `parent`.
    pub fn open_in(path: &Path, parent: &Path) -> Result<Fmu, ImportError> {
        Fmu::open_with_limits_in(path, parent, &UnpackLimits::DEFAULT)
    }

    /// [`open_in`](Fmu::open_in) and [`open_with_limits`](Fmu::open_with_limits) together.
    pub fn open_with_limits_in(
        path: &Path,
        parent: &Path,
        limits: &UnpackLimits,
    ) -> Result<Fmu, ImportError> {
        let dir = tempfile::Builder::new()
            .prefix("fmi-import-")
            .tempdir_in(parent)
            .map_err(|source| ImportError::Io {
                path: path.to_path_buf(),
                action: format!(
                    "cannot create a temporary directory in {}",
                    parent.display()
                ),
                source,
            })?;
        Fmu::open_into(path, dir, limits)
    }

    fn open_into(path: &Path, dir: TempDir, limits: &UnpackLimits) -> Result<Fmu, ImportError> {
        let fmu = path.to_path_buf();
        let unpacked = unpack(path, dir.path(), limits)?;

        let md_path = dir.path().join("modelDescription.xml");
        let io = |action: &str, source| ImportError::Io {
            path: fmu.clone(),
            action: action.to_string(),
            source,
        };
        let bytes =
            std::fs::read(&md_path).map_err(|e| io("cannot read modelDescription.xml", e))?;
        // Invalid UTF-8 is reported with its line and column, like any parse error.
        let md = ModelDescription::from_bytes(&bytes).map_err(|source| {
            ImportError::ModelDescription {
                path: fmu.clone(),
                source,
            }
        })?;
        if !md.fmi_version.trim().starts_with("2.") {
            return Err(ImportError::UnsupportedFmiVersion {
                path: fmu,
                version: md.fmi_version.clone(),
            });
        }
        let Some(cs) = &md.co_simulation else {
            return Err(ImportError::NotCoSimulation {
                path: fmu,
                model_exchange: md.model_exchange_identifier.is_some(),
            });
        };
        let model_identifier = cs.model_identifier.clone();
        if !valid_identifier(&model_identifier) {
            return Err(ImportError::InvalidModelIdentifier {
                path: fmu,
                identifier: model_identifier,
            });
        }
        let Some(relative) = platform_binary(&model_identifier) else {
            return Err(ImportError::UnsupportedPlatform {
                path: fmu,
                os: std::env::consts::OS,
                arch: std::env::consts::ARCH,
            });
        };
        let library_path = dir.path().join(&relative);
        if !library_path.is_file() {
            return Err(ImportError::MissingBinary {
                path: fmu,
                expected: relative,
                available: unpacked.platforms,
            });
        }
        let library = library::load(&library_path).map_err(|message| ImportError::Load {
            path: fmu.clone(),
            library: relative.clone(),
            message,
        })?;
        let functions =
            Functions::resolve(&library).map_err(|missing| ImportError::MissingFunctions {
                path: fmu.clone(),
                library: relative.clone(),
                missing,
            })?;
        // SAFETY: both functions take no arguments and return a static string (FMI 2.0).
        let version = unsafe { returned((functions.get_version)()) };
        if version.as_deref() != Some("2.0") {
            return Err(ImportError::Incompatible {
                path: fmu,
                function: "fmi2GetVersion",
                expected: "2.0",
                found: version.map_or("NULL".into(), |v| format!("{v:?}")),
            });
        }
        // SAFETY: as for fmi2GetVersion above: no arguments, a static string or NULL back.
        let types = unsafe { returned((functions.get_types_platform)()) };
        if types.as_deref() != Some("default") {
            return Err(ImportError::Incompatible {
                path: fmu,
                function: "fmi2GetTypesPlatform",
                expected: "default",
                found: types.map_or("NULL".into(), |v| format!("{v:?}")),
            });
        }

        let guid = CString::new(md.guid.clone()).map_err(|_| ImportError::Io {
            path: fmu.clone(),
            action: "the guid in modelDescription.xml contains a NUL character".into(),
            source: std::io::Error::from(std::io::ErrorKind::InvalidData),
        })?;
        let resource_uri = resource_uri(dir.path()).map_err(|source| ImportError::Io {
            path: fmu.clone(),
            action: "cannot express the resources directory as a file:// URI".into(),
            source,
        })?;
        let only_once = cs.can_be_instantiated_only_once_per_process;
        Ok(Fmu {
            inner: Arc::new(FmuInner {
                functions,
                library: Arc::new(library),
                model_identifier,
                guid,
                resource_uri,
                only_once,
                live: AtomicUsize::new(0),
                last_name: Mutex::new(String::new()),
                path: fmu,
                md,
                dir,
            }),
        })
    }

    /// The `.fmu` file this was opened from (as given to [`open`](Fmu::open)).
    pub fn path(&self) -> &Path {
        &self.inner.path
    }

    /// The temporary directory the archive was unpacked into.
    pub fn unpacked_dir(&self) -> &Path {
        self.inner.dir.path()
    }

    /// The `fmuResourceLocation` passed to fmi2Instantiate: the `file://` URI of
    /// `<unpacked>/resources`, percent-encoded, without a trailing slash.
    pub fn resource_uri(&self) -> &str {
        self.inner.resource_uri.to_str().unwrap_or("")
    }

    /// The parsed `modelDescription.xml`, checked at [`open`](Fmu::open) to be FMI 2.0
    /// co-simulation; the variables' value references and causalities come from here.
    pub fn model_description(&self) -> &ModelDescription {
        &self.inner.md
    }

    /// The co-simulation `modelIdentifier` (the library's file stem).
    pub fn model_identifier(&self) -> &str {
        &self.inner.model_identifier
    }

    /// The variable called `name`, or an error naming the FMU and the variable.
    pub fn variable(&self, name: &str) -> Result<&ScalarVariable, ImportError> {
        self.inner
            .md
            .variable(name)
            .ok_or_else(|| ImportError::UnknownVariable {
                path: self.inner.path.clone(),
                name: name.to_string(),
            })
    }

    /// The base type and value reference of the variable called `name`.
    pub fn value_reference(&self, name: &str) -> Result<(BaseType, u32), ImportError> {
        let v = self.variable(name)?;
        Ok((v.kind.base_type(), v.value_reference))
    }

    /// Creates a co-simulation instance (fmi2Instantiate) logging through `logging`.
    pub fn instantiate(
        &self,
        instance_name: &str,
        logging: LogConfig,
    ) -> Result<Instance, ImportError> {
        let inner = &self.inner;
        let name = CString::new(instance_name).map_err(|_| ImportError::InvalidInstanceName {
            path: inner.path.clone(),
            name: instance_name.to_string(),
        })?;
        if inner.only_once {
            let previous = inner.live.fetch_add(1, Ordering::AcqRel);
            if previous > 0 {
                inner.live.fetch_sub(1, Ordering::AcqRel);
                let existing = inner
                    .last_name
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .clone();
                return Err(ImportError::InstantiatedOnlyOnce {
                    path: inner.path.clone(),
                    existing,
                });
            }
        } else {
            inner.live.fetch_add(1, Ordering::AcqRel);
        }
        *inner.last_name.lock().unwrap_or_else(|e| e.into_inner()) = instance_name.to_string();
        Instance::new(Arc::clone(inner), name, instance_name, logging)
    }
}

impl std::fmt::Debug for Fmu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Fmu")
            .field("path", &self.inner.path)
            .field("model_identifier", &self.inner.model_identifier)
            .field("unpacked_dir", &self.inner.dir.path())
            .finish()
    }
}

/// `file://` URI of `<dir>/resources`, percent-encoded by the url crate, no trailing slash.
fn resource_uri(dir: &Path) -> std::io::Result<CString> {
    let resources = std::path::absolute(dir.join("resources"))?;
    let url = url::Url::from_file_path(&resources).map_err(|()| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{} is not an absolute path", resources.display()),
        )
    })?;
    let text = url.as_str().trim_end_matches('/').to_string();
    CString::new(text).map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifiers() {
        assert!(valid_identifier("AlignmentEstimator"));
        assert!(valid_identifier("my-model_2"));
        for bad in ["", ".", "..", "../x", "a/b", "a\\b", "c:x", "a\0"] {
            assert!(!valid_identifier(bad), "{bad:?}");
        }
    }

    #[test]
    fn resource_uris_are_percent_encoded_without_trailing_slash() {
        let uri = resource_uri(Path::new("/tmp/a b%c/x")).unwrap();
        assert_eq!(uri.to_str().unwrap(), "file:///tmp/a%20b%25c/x/resources");
    }
}
