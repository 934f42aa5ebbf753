//! Finding and loading a vendor library at run time (`libloading`), so that
//! echothigh builds and runs where the SDK is not installed.

use crate::{DeviceError, DeviceKind};
use std::path::PathBuf;

/// Where a backend looks for its library.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LibrarySpec {
    /// The backend.
    pub backend: DeviceKind,
    /// The SDK's name for messages.
    pub sdk: &'static str,
    /// The environment variable that overrides the path.
    pub env_var: &'static str,
    /// The file name the system loader searches for by default.
    pub default_name: String,
}

impl LibrarySpec {
    /// The path to load: the environment variable if set and non-empty, else
    /// the configured path, else the default name (searched by the system loader).
    pub fn resolve(&self, configured: Option<&PathBuf>) -> String {
        match std::env::var(self.env_var) {
            Ok(v) if !v.trim().is_empty() => v,
            _ => configured
                .map(|p| p.display().to_string())
                .unwrap_or_else(|| self.default_name.clone()),
        }
    }

    /// Loads the library at `path`.
    pub fn load(&self, path: &str) -> Result<libloading::Library, DeviceError> {
        // SAFETY: loading runs the library's initialisers; the vendor SDKs
        // (and our emulator) have none with preconditions on the caller.
        unsafe { libloading::Library::new(path) }.map_err(|e| DeviceError::LibraryNotFound {
            backend: self.backend,
            library: path.to_string(),
            sdk: self.sdk,
            env_var: self.env_var,
            detail: e.to_string(),
        })
    }

    /// Copies the function pointer `symbol` (NUL-terminated) out of `lib`.
    ///
    /// # Safety
    /// `T` must be the exact `extern "C"` signature of the symbol, and the
    /// pointer must not be used after `lib` is dropped.
    pub unsafe fn symbol<T: Copy>(
        &self,
        lib: &libloading::Library,
        path: &str,
        symbol: &'static str,
    ) -> Result<T, DeviceError> {
        let name = format!("{symbol}\0");
        // SAFETY: the caller guarantees the signature.
        unsafe { lib.get::<T>(name.as_bytes()) }
            .map(|s| *s)
            .map_err(|e| DeviceError::MissingSymbol {
                backend: self.backend,
                library: path.to_string(),
                sdk: self.sdk,
                symbol,
                detail: e.to_string(),
            })
    }
}
