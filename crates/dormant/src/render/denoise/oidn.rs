//! The only `unsafe` code of denoising: an owned OIDN CPU device and `RT` filters over
//! caller-owned pixel buffers, every call checked with `oidnGetDeviceError`.
//!
//! A filter is made and committed once per kind of run (its inputs, size and flags) and kept
//! for the next frames: committing a new filter sets its network up again, which OIDN skips
//! when only the image pointers change (measured:
//! docs/lab/reuse.md#2026-12-06-the-stores-passes-in-one-trace-the-denoisers-filter-kept---denoise-quality).

use std::cell::RefCell;
use std::ffi::{c_void, CStr};
use std::ptr;

use oidn_sys as sys;

use super::{DenoiseError, DenoiseQuality};

/// OIDN's name for an error code.
fn code_name(code: sys::OIDNError) -> &'static str {
    match code {
        sys::OIDN_ERROR_NONE => "OIDN_ERROR_NONE",
        sys::OIDN_ERROR_UNKNOWN => "OIDN_ERROR_UNKNOWN",
        sys::OIDN_ERROR_INVALID_ARGUMENT => "OIDN_ERROR_INVALID_ARGUMENT",
        sys::OIDN_ERROR_INVALID_OPERATION => "OIDN_ERROR_INVALID_OPERATION",
        sys::OIDN_ERROR_OUT_OF_MEMORY => "OIDN_ERROR_OUT_OF_MEMORY",
        sys::OIDN_ERROR_UNSUPPORTED_HARDWARE => "OIDN_ERROR_UNSUPPORTED_HARDWARE",
        sys::OIDN_ERROR_CANCELLED => "OIDN_ERROR_CANCELLED",
        _ => "unknown OIDN error code",
    }
}

/// The first unqueried error of `device` on this thread (a null device: the thread's global
/// error, e.g. why a device could not be created), cleared by the query.
fn take_error(device: sys::OIDNDevice) -> Option<(sys::OIDNError, String)> {
    let mut message = ptr::null();
    // SAFETY: `device` is null or a live device; `message` is a valid out pointer.
    let code = unsafe { sys::oidnGetDeviceError(device, &mut message) };
    if code == sys::OIDN_ERROR_NONE {
        return None;
    }
    let text = if message.is_null() {
        String::new()
    } else {
        // SAFETY: a non-null message is a NUL-terminated string owned by the library, valid
        // until the next OIDN call on this thread; it is copied before any.
        unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned()
    };
    Some((code, text))
}

/// An OIDN CPU device and the filters made on it; released on drop. Raw pointers keep it
/// `!Send` and `!Sync`, which suits OIDN's per-thread error reporting.
pub(super) struct OidnDevice {
    raw: sys::OIDNDevice,
    filters: RefCell<Vec<(FilterKey, Filter)>>,
}

/// An `RT` filter's parameters: `hdr` says the color image is HDR, `clean_aux` that the guides
/// are noise-free; `quality` picks the network.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) struct FilterOptions {
    pub hdr: bool,
    pub clean_aux: bool,
    pub quality: DenoiseQuality,
}

/// What a committed filter was set up for: its input names, image size and options.
#[derive(Clone, PartialEq, Eq)]
struct FilterKey {
    inputs: Vec<&'static CStr>,
    size: (usize, usize),
    options: FilterOptions,
}

impl Drop for OidnDevice {
    fn drop(&mut self) {
        // Filters first: each holds a reference to the device.
        self.filters.get_mut().clear();
        // SAFETY: `raw` is a live device this struct holds the only reference to; every filter
        // made from it is released above.
        unsafe { sys::oidnReleaseDevice(self.raw) };
    }
}

impl OidnDevice {
    /// Creates and commits a CPU device with `threads` worker threads (0: all cores) and no
    /// thread pinning (the renderer's own threads share the cores).
    pub(super) fn new(threads: Option<usize>) -> Result<Self, DenoiseError> {
        // SAFETY: plain call; a null result is handled below.
        let raw = unsafe { sys::oidnNewDevice(sys::OIDN_DEVICE_TYPE_CPU) };
        if raw.is_null() {
            let message = take_error(ptr::null_mut()).map(|(_, m)| m).unwrap_or_default();
            return Err(DenoiseError::NoDevice { message, lib_dir: sys::LIB_DIR.to_string() });
        }
        let device = OidnDevice { raw, filters: RefCell::new(Vec::new()) };
        let threads = threads.map_or(0, |n| i32::try_from(n).unwrap_or(i32::MAX));
        // SAFETY: `raw` is a live, not yet committed device; the names are NUL-terminated.
        unsafe {
            sys::oidnSetDeviceInt(raw, c"numThreads".as_ptr(), threads);
            sys::oidnSetDeviceBool(raw, c"setAffinity".as_ptr(), false);
            sys::oidnCommitDevice(raw);
        }
        device.check("oidnCommitDevice")?;
        // SAFETY: `raw` is a live, committed device; the name is NUL-terminated.
        let major = unsafe { sys::oidnGetDeviceInt(raw, c"versionMajor".as_ptr()) };
        if major != 2 {
            return Err(DenoiseError::Version { found: device.version() });
        }
        Ok(device)
    }

    /// The pending error of the last calls, as a [`DenoiseError`] naming `call`.
    fn check(&self, call: &'static str) -> Result<(), DenoiseError> {
        match take_error(self.raw) {
            None => Ok(()),
            Some((code, message)) => Err(DenoiseError::Oidn { call, code: code_name(code), message }),
        }
    }

    /// The library's version, `major.minor.patch`.
    pub(super) fn version(&self) -> String {
        // SAFETY: `raw` is a live, committed device; `version` is a constant parameter.
        let v = unsafe { sys::oidnGetDeviceInt(self.raw, c"version".as_ptr()) };
        format!("{}.{}.{}", v / 10000, v / 100 % 100, v % 100)
    }

    /// Runs the `RT` filter with `options` on `width` x `height` images of packed RGB floats:
    /// `inputs` names each (`color`, `albedo`, `normal`; a guide alone is prefiltered).
    /// Returns the output image.
    pub(super) fn filter_rt(
        &self,
        (width, height): (usize, usize),
        inputs: &[(&'static CStr, &[f32])],
        options: FilterOptions,
    ) -> Result<Vec<f32>, DenoiseError> {
        let len = width * height * 3;
        assert!(inputs.iter().all(|(_, data)| data.len() == len), "images of {width}x{height} RGB");
        let key = FilterKey {
            inputs: inputs.iter().map(|(name, _)| *name).collect(),
            size: (width, height),
            options,
        };
        let mut filters = self.filters.borrow_mut();
        let filter = match filters.iter().position(|(k, _)| *k == key) {
            Some(at) => &filters[at].1,
            None => {
                let filter = self.new_rt_filter(options)?;
                filters.push((key, filter));
                &filters.last().expect("just pushed").1
            }
        };
        let mut output = vec![0.0f32; len];
        // Inputs are only read by OIDN; the pointer type of the C API is not const.
        let images = inputs
            .iter()
            .map(|(name, data)| (*name, data.as_ptr() as *mut c_void))
            .chain([(c"output", output.as_mut_ptr() as *mut c_void)]);
        // SAFETY: `filter.raw` is a live filter; every image it reads or writes is set here,
        // each pointer addressing `len` floats (width * height packed FLOAT3 pixels, strides
        // computed by OIDN) that outlive the execution below; only `output` is written, and
        // nothing else reads or writes it meanwhile. The pointers left in the filter after
        // this call are never used: the next call sets every image again before executing.
        unsafe {
            for (name, data) in images {
                sys::oidnSetSharedFilterImage(
                    filter.raw,
                    name.as_ptr(),
                    data,
                    sys::OIDN_FORMAT_FLOAT3,
                    width,
                    height,
                    0,
                    0,
                    0,
                );
            }
            sys::oidnCommitFilter(filter.raw);
        }
        self.check("oidnCommitFilter")?;
        // SAFETY: a committed filter whose images are valid (above).
        unsafe { sys::oidnExecuteFilter(filter.raw) };
        self.check("oidnExecuteFilter")?;
        Ok(output)
    }

    /// A new `RT` filter with `options` set, its images not yet.
    fn new_rt_filter(&self, options: FilterOptions) -> Result<Filter, DenoiseError> {
        // SAFETY: `raw` is a live, committed device.
        let filter = Filter { raw: unsafe { sys::oidnNewFilter(self.raw, c"RT".as_ptr()) } };
        self.check("oidnNewFilter")?;
        if filter.raw.is_null() {
            return Err(DenoiseError::Oidn {
                call: "oidnNewFilter",
                code: "null filter",
                message: String::new(),
            });
        }
        // SAFETY: `filter.raw` is a live filter; the names are NUL-terminated.
        unsafe {
            sys::oidnSetFilterBool(filter.raw, c"hdr".as_ptr(), options.hdr);
            sys::oidnSetFilterBool(filter.raw, c"cleanAux".as_ptr(), options.clean_aux);
            sys::oidnSetFilterInt(filter.raw, c"quality".as_ptr(), quality_code(options.quality));
        }
        Ok(filter)
    }
}

/// OIDN's code for `quality`.
fn quality_code(quality: DenoiseQuality) -> sys::OIDNQuality {
    match quality {
        DenoiseQuality::High => sys::OIDN_QUALITY_HIGH,
        DenoiseQuality::Balanced => sys::OIDN_QUALITY_BALANCED,
        DenoiseQuality::Fast => sys::OIDN_QUALITY_FAST,
    }
}

/// An OIDN filter; released on drop.
struct Filter {
    raw: sys::OIDNFilter,
}

impl Drop for Filter {
    fn drop(&mut self) {
        if !self.raw.is_null() {
            // SAFETY: `raw` is a live filter this struct holds the only reference to.
            unsafe { sys::oidnReleaseFilter(self.raw) };
        }
    }
}
