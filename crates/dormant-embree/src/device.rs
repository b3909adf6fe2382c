//! [`Device`]: an Embree device with its error callback (errors come back as
//! [`EmbreeError`]s) and thread count, and the library [`Version`] check against the headers.

use std::ffi::{c_char, c_void, CStr, CString};
use std::fmt;
use std::ptr;
use std::sync::{Arc, Mutex};

use embree4_sys as sys;

use super::error::{code_name, EmbreeError};

/// An Embree version as `major.minor.patch`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
pub struct Version {
    pub major: u32,
    pub minor: u32,
    pub patch: u32,
}

impl Version {
    /// Decodes Embree's `RTC_VERSION` encoding (`40303` is 4.3.3).
    pub(crate) fn from_encoded(v: u32) -> Self {
        Self { major: v / 10000, minor: v / 100 % 100, patch: v % 100 }
    }

    /// The version of the headers the bindings were generated from.
    pub fn header() -> Self {
        Self::from_encoded(sys::RTC_VERSION)
    }
}

impl fmt::Display for Version {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{}.{}", self.major, self.minor, self.patch)
    }
}

/// Where Embree's error callback leaves the last message for [`Device::check`].
#[derive(Default)]
struct ErrorSlot {
    last: Mutex<Option<(sys::RTCError::Type, String)>>,
}

/// Embree's error callback. Runs on the thread whose API call failed.
unsafe extern "C" fn record_error(user_ptr: *mut c_void, code: sys::RTCError::Type, msg: *const c_char) {
    // SAFETY: `user_ptr` is the `ErrorSlot` inside the `DeviceInner` that registered this
    // callback; every Embree object holds an `Arc<DeviceInner>`, so the slot outlives them all.
    let slot = unsafe { &*(user_ptr as *const ErrorSlot) };
    let message = if msg.is_null() {
        String::new()
    } else {
        // SAFETY: Embree passes a NUL-terminated string valid for the duration of the call.
        unsafe { CStr::from_ptr(msg) }.to_string_lossy().into_owned()
    };
    // Never unwind across the FFI boundary: a poisoned lock still holds a usable slot.
    let mut last = slot.last.lock().unwrap_or_else(|e| e.into_inner());
    *last = Some((code, message));
}

pub(crate) struct DeviceInner {
    pub(crate) raw: sys::RTCDevice,
    // Boxed so its address is stable for the callback's user pointer.
    errors: Box<ErrorSlot>,
    library: Version,
}

impl Drop for DeviceInner {
    fn drop(&mut self) {
        // SAFETY: `raw` is a valid device we hold one reference to; every scene and geometry
        // keeps this `DeviceInner` alive through an `Arc`, so none outlives the release.
        unsafe { sys::rtcReleaseDevice(self.raw) };
    }
}

/// An Embree device: the factory for scenes and geometries and the owner of Embree's thread
/// pool. Cheap to clone (shared).
#[derive(Clone)]
pub struct Device {
    pub(crate) inner: Arc<DeviceInner>,
}

// SAFETY: Embree objects are not bound to the thread that made them, and the device-level calls
// the wrapper makes through `&Device` (creating scenes and geometries, reading properties and
// the error code, which Embree keeps per thread: rtcGetDeviceError(3)) are thread-safe; the
// error slot is behind a Mutex. Only modifying one object from two threads at once is
// forbidden (Embree API docs, rtcCommitScene(3)), and the wrapper needs `&mut` for that.
unsafe impl Send for DeviceInner {}
// SAFETY: see `Send` above.
unsafe impl Sync for DeviceInner {}

impl Device {
    /// Creates a device. `threads` sets the size of Embree's worker pool (`threads=N` in the
    /// config string); `None` uses every core.
    pub fn new(threads: Option<usize>) -> Result<Self, EmbreeError> {
        let config = match threads {
            Some(n) => format!("threads={n}"),
            None => String::new(),
        };
        Self::with_config(&config)
    }

    /// Creates a device from an Embree configuration string (rtcNewDevice(3)).
    pub fn with_config(config: &str) -> Result<Self, EmbreeError> {
        let config = CString::new(config).map_err(|_| EmbreeError::DeviceCreation {
            code: "RTC_ERROR_INVALID_ARGUMENT",
            message: ": configuration string contains a NUL byte".into(),
        })?;
        // SAFETY: `config` is a valid NUL-terminated string for the duration of the call.
        let raw = unsafe { sys::rtcNewDevice(config.as_ptr()) };
        if raw.is_null() {
            // SAFETY: a null device asks for the error of the failed device creation.
            let code = unsafe { sys::rtcGetDeviceError(ptr::null_mut()) };
            return Err(EmbreeError::DeviceCreation { code: code_name(code), message: String::new() });
        }
        let errors = Box::<ErrorSlot>::default();
        // SAFETY: `raw` is valid; the slot pointer stays valid while `DeviceInner` lives, and
        // `DeviceInner` releases the device in its `Drop`.
        unsafe {
            sys::rtcSetDeviceErrorFunction(
                raw,
                Some(record_error),
                &*errors as *const ErrorSlot as *mut c_void,
            )
        };
        // SAFETY: `raw` is a valid device.
        let encoded =
            unsafe { sys::rtcGetDeviceProperty(raw, sys::RTCDeviceProperty::RTC_DEVICE_PROPERTY_VERSION) };
        let library = Version::from_encoded(u32::try_from(encoded).unwrap_or(0));
        let device = Device { inner: Arc::new(DeviceInner { raw, errors, library }) };
        device.check()?;
        check_version(library, Version::header())?;
        Ok(device)
    }

    /// The version of the Embree library actually loaded.
    pub fn library_version(&self) -> Version {
        self.inner.library
    }

    /// Returns the error Embree recorded on this thread since the last check, if any.
    pub(crate) fn check(&self) -> Result<(), EmbreeError> {
        // SAFETY: the device is valid while `self` lives.
        let code = unsafe { sys::rtcGetDeviceError(self.inner.raw) };
        let recorded = self.inner.errors.last.lock().unwrap_or_else(|e| e.into_inner()).take();
        match (code, recorded) {
            (sys::RTCError::RTC_ERROR_NONE, None) => Ok(()),
            (sys::RTCError::RTC_ERROR_NONE, Some((code, message))) | (code, Some((_, message))) => {
                Err(EmbreeError::Api { code: code_name(code), message })
            }
            (code, None) => Err(EmbreeError::Api { code: code_name(code), message: String::new() }),
        }
    }
}

/// The library must have the header's major version and be at least as new: newer minor
/// versions only add functions, older ones may lack what the bindings call.
pub(crate) fn check_version(library: Version, header: Version) -> Result<(), EmbreeError> {
    if library.major == header.major && library >= header {
        Ok(())
    } else {
        Err(EmbreeError::VersionMismatch { library: library.to_string(), header: header.to_string() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn version_rule() {
        let v = |s: &str| {
            let p: Vec<u32> = s.split('.').map(|x| x.parse().unwrap()).collect();
            Version { major: p[0], minor: p[1], patch: p[2] }
        };
        assert!(check_version(v("4.4.0"), v("4.3.3")).is_ok());
        assert!(check_version(v("4.3.3"), v("4.3.3")).is_ok());
        assert!(check_version(v("4.2.0"), v("4.3.3")).is_err());
        assert!(check_version(v("5.0.0"), v("4.3.3")).is_err());
        assert!(check_version(v("3.13.5"), v("4.3.3")).is_err());
        assert_eq!(Version::from_encoded(40303).to_string(), "4.3.3");
    }
}
