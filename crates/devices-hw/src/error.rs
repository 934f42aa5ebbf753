//! Typed errors of the device backends: each names what is missing and how to fix it.

use crate::DeviceKind;
use echothigh_device::ConfigError;

/// Why a device backend could not start or stopped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DeviceError {
    /// The vendor's shared library could not be loaded.
    #[error("{backend}: cannot load the {sdk} library `{library}` ({detail}); install the {sdk} or set {env_var} to the full path of the library")]
    LibraryNotFound {
        /// The backend.
        backend: DeviceKind,
        /// The file looked for.
        library: String,
        /// The SDK's name.
        sdk: &'static str,
        /// The environment variable that overrides the path.
        env_var: &'static str,
        /// The loader's message.
        detail: String,
    },
    /// The library lacks a function the backend calls.
    #[error("{backend}: `{library}` has no function `{symbol}`: it is not a compatible {sdk} library ({detail})")]
    MissingSymbol {
        /// The backend.
        backend: DeviceKind,
        /// The file loaded.
        library: String,
        /// The SDK's name.
        sdk: &'static str,
        /// The missing function.
        symbol: &'static str,
        /// The loader's message.
        detail: String,
    },
    /// The library loaded but found no device.
    #[error("{backend}: no device found: {detail}")]
    NoDevice {
        /// The backend.
        backend: DeviceKind,
        /// The SDK's explanation.
        detail: String,
    },
    /// An SDK call failed.
    #[error("{backend}: {call} failed: {detail}")]
    Sdk {
        /// The backend.
        backend: DeviceKind,
        /// The SDK function.
        call: &'static str,
        /// The SDK's error text.
        detail: String,
    },
    /// A device service (Haply's Inverse Service) did not answer.
    #[error("{backend}: cannot reach the {service} at {url} ({detail}); start it, or set {env_var} to its WebSocket address (ws://HOST:PORT)")]
    ServiceUnreachable {
        /// The backend.
        backend: DeviceKind,
        /// The service's name.
        service: &'static str,
        /// The address tried.
        url: String,
        /// The environment variable that overrides the address.
        env_var: &'static str,
        /// Why it failed.
        detail: String,
    },
    /// This build left the backend out (a cargo feature).
    #[error("{backend}: this echothigh was built without the `{feature}` cargo feature; rebuild with `--features {feature}` (it is on by default)")]
    NotBuilt {
        /// The backend.
        backend: DeviceKind,
        /// The cargo feature that builds it.
        feature: &'static str,
    },
    /// A configuration value is out of range.
    #[error(transparent)]
    Config(#[from] ConfigError),
}
