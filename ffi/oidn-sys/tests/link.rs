//! The declarations against the linked library: a CPU device reports major version 2, and the
//! `RT` filter denoises a small constant HDR image through shared caller-owned memory into
//! about the same constant (mean within 2%, every pixel within 10%), without an error.

use std::ffi::{c_void, CStr};
use std::ptr;

use oidn_sys::*;

/// The device's pending error, or `None`.
fn error(device: OIDNDevice) -> Option<String> {
    let mut message = ptr::null();
    // SAFETY: `message` is a valid out pointer; the string it receives is read before the
    // next OIDN call on this thread.
    let code = unsafe { oidnGetDeviceError(device, &mut message) };
    (code != OIDN_ERROR_NONE).then(|| {
        // SAFETY: a non-null message is a NUL-terminated string owned by the library.
        let text =
            if message.is_null() { "" } else { unsafe { CStr::from_ptr(message) }.to_str().unwrap_or("") };
        format!("{code}: {text}")
    })
}

#[test]
fn cpu_device_denoises_a_constant_image() {
    // SAFETY: plain calls on handles created here, checked for null and errors, released at the
    // end; the images are Vecs that outlive the filter's execution.
    unsafe {
        let device = oidnNewDevice(OIDN_DEVICE_TYPE_CPU);
        assert!(!device.is_null(), "oidnNewDevice: {:?}", error(ptr::null_mut()));
        oidnSetDeviceInt(device, c"numThreads".as_ptr(), 2);
        oidnCommitDevice(device);
        assert_eq!(error(device), None);
        assert_eq!(oidnGetDeviceInt(device, c"versionMajor".as_ptr()), 2);

        let (w, h) = (64usize, 32usize);
        let mut color = vec![0.5f32; w * h * 3];
        let mut output = vec![0.0f32; w * h * 3];
        let filter = oidnNewFilter(device, c"RT".as_ptr());
        assert!(!filter.is_null(), "oidnNewFilter: {:?}", error(device));
        let image = |name: &CStr, data: *mut f32| {
            oidnSetSharedFilterImage(
                filter,
                name.as_ptr(),
                data as *mut c_void,
                OIDN_FORMAT_FLOAT3,
                w,
                h,
                0,
                0,
                0,
            )
        };
        image(c"color", color.as_mut_ptr());
        image(c"output", output.as_mut_ptr());
        oidnSetFilterBool(filter, c"hdr".as_ptr(), true);
        oidnCommitFilter(filter);
        oidnExecuteFilter(filter);
        assert_eq!(error(device), None);
        oidnReleaseFilter(filter);
        oidnReleaseDevice(device);
        // The network is not exactly flat on a flat image (measured 0.477..0.518 at 64x64).
        let (lo, hi) = output.iter().fold((f32::MAX, f32::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let mean = output.iter().sum::<f32>() / output.len() as f32;
        assert!((mean - 0.5).abs() < 0.01, "denoised constant 0.5 has mean {mean}");
        assert!(lo > 0.45 && hi < 0.55, "denoised constant 0.5 became {lo}..{hi}");
    }
}
