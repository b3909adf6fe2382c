//! Raw bindings to the few functions of Intel Open Image Denoise 2.x's C API
//! (`OpenImageDenoise/oidn.h`) that dormant uses, declared by hand: the API passes only opaque
//! handles, scalars, strings and pointers to caller-owned pixels, so there are no struct
//! layouts to get wrong. No safe API here: dormant's wrapper is `dormant::render::denoise`.
//!
//! C enums are passed as `c_int` (what the C compiler uses for these enums on the supported
//! targets), with their values as constants, so a code the list does not name cannot be
//! undefined behaviour. C's `bool` is Rust's `bool`.
#![allow(non_camel_case_types)]

use std::ffi::{c_char, c_int, c_void};

/// Opaque device object (`struct OIDNDeviceImpl`).
#[repr(C)]
pub struct OIDNDeviceImpl {
    _private: [u8; 0],
}
/// Opaque filter object (`struct OIDNFilterImpl`).
#[repr(C)]
pub struct OIDNFilterImpl {
    _private: [u8; 0],
}
/// `OIDNDevice`: a reference-counted device handle; null when creation failed.
pub type OIDNDevice = *mut OIDNDeviceImpl;
/// `OIDNFilter`: a reference-counted filter handle; null when creation failed.
pub type OIDNFilter = *mut OIDNFilterImpl;

/// `OIDNDeviceType`.
pub type OIDNDeviceType = c_int;
pub const OIDN_DEVICE_TYPE_DEFAULT: OIDNDeviceType = 0;
pub const OIDN_DEVICE_TYPE_CPU: OIDNDeviceType = 1;

/// `OIDNError`.
pub type OIDNError = c_int;
pub const OIDN_ERROR_NONE: OIDNError = 0;
pub const OIDN_ERROR_UNKNOWN: OIDNError = 1;
pub const OIDN_ERROR_INVALID_ARGUMENT: OIDNError = 2;
pub const OIDN_ERROR_INVALID_OPERATION: OIDNError = 3;
pub const OIDN_ERROR_OUT_OF_MEMORY: OIDNError = 4;
pub const OIDN_ERROR_UNSUPPORTED_HARDWARE: OIDNError = 5;
pub const OIDN_ERROR_CANCELLED: OIDNError = 6;

/// `OIDNFormat` (the ones used: 32-bit float channels).
pub type OIDNFormat = c_int;
pub const OIDN_FORMAT_FLOAT: OIDNFormat = 1;
pub const OIDN_FORMAT_FLOAT3: OIDNFormat = 3;

/// `OIDNQuality`, for the filter's `quality` parameter.
pub type OIDNQuality = c_int;
pub const OIDN_QUALITY_DEFAULT: OIDNQuality = 0;
pub const OIDN_QUALITY_FAST: OIDNQuality = 4;
pub const OIDN_QUALITY_BALANCED: OIDNQuality = 5;
pub const OIDN_QUALITY_HIGH: OIDNQuality = 6;

extern "C" {
    /// Creates a device of the given type (not yet committed); null on failure, with the
    /// error queryable through `oidnGetDeviceError(null, ..)`.
    pub fn oidnNewDevice(device_type: OIDNDeviceType) -> OIDNDevice;
    /// Releases a device (decrements its reference count).
    pub fn oidnReleaseDevice(device: OIDNDevice);
    /// Sets an integer device parameter (e.g. `numThreads`), before the commit.
    pub fn oidnSetDeviceInt(device: OIDNDevice, name: *const c_char, value: c_int);
    /// Sets a boolean device parameter (e.g. `setAffinity`), before the commit.
    pub fn oidnSetDeviceBool(device: OIDNDevice, name: *const c_char, value: bool);
    /// Reads an integer device parameter (e.g. `version`, `versionMajor`).
    pub fn oidnGetDeviceInt(device: OIDNDevice, name: *const c_char) -> c_int;
    /// Returns and clears the first unqueried error of `device` (or, for a null device, the
    /// thread's global error) for the calling thread; `out_message` (if not null) receives a
    /// string owned by the library, valid until the next call on this thread.
    pub fn oidnGetDeviceError(device: OIDNDevice, out_message: *mut *const c_char) -> OIDNError;
    /// Commits the device's parameters; required before creating filters.
    pub fn oidnCommitDevice(device: OIDNDevice);

    /// Creates a filter of the given type (`"RT"`) on a committed device; null on failure.
    pub fn oidnNewFilter(device: OIDNDevice, filter_type: *const c_char) -> OIDNFilter;
    /// Releases a filter (decrements its reference count).
    pub fn oidnReleaseFilter(filter: OIDNFilter);
    /// Sets an image parameter to memory owned by the caller, which must stay valid (and, for
    /// inputs, unchanged) until the filter executes or the image is unset. Zero strides are
    /// computed from the format and width.
    pub fn oidnSetSharedFilterImage(
        filter: OIDNFilter,
        name: *const c_char,
        dev_ptr: *mut c_void,
        format: OIDNFormat,
        width: usize,
        height: usize,
        byte_offset: usize,
        pixel_byte_stride: usize,
        row_byte_stride: usize,
    );
    /// Unsets an image parameter set before.
    pub fn oidnUnsetFilterImage(filter: OIDNFilter, name: *const c_char);
    /// Sets a boolean filter parameter (`hdr`, `srgb`, `cleanAux`).
    pub fn oidnSetFilterBool(filter: OIDNFilter, name: *const c_char, value: bool);
    /// Sets an integer filter parameter (`quality`, `maxMemoryMB`).
    pub fn oidnSetFilterInt(filter: OIDNFilter, name: *const c_char, value: c_int);
    /// Commits the filter's parameters (loads and plans the network for the image size).
    pub fn oidnCommitFilter(filter: OIDNFilter);
    /// Runs the filter synchronously.
    pub fn oidnExecuteFilter(filter: OIDNFilter);
}

/// Directory of the library this crate was linked against (see `build.rs`).
pub const LIB_DIR: &str = env!("OIDN_SYS_LIB_DIR");

/// How the build found the library: `OIDN_DIR`, the project-local prefix, pkg-config or the
/// system paths.
pub const ORIGIN: &str = env!("OIDN_SYS_ORIGIN");
