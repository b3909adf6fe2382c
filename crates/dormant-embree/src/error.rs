//! [`EmbreeError`]: what Embree or the wrapper's own checks report.

use embree4_sys as sys;

/// Errors reported by Embree or by the wrapper's own checks.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum EmbreeError {
    #[error("Embree device creation failed ({code}){message}")]
    DeviceCreation { code: &'static str, message: String },
    #[error(
        "Embree library {library} does not match the headers dormant was built with ({header}): \
         the major versions must be equal and the library at least as new. Rebuild against the \
         installed Embree (scripts/setup.sh, or set EMBREE_DIR)"
    )]
    VersionMismatch { library: String, header: String },
    #[error("Embree error {code}: {message}")]
    Api { code: &'static str, message: String },
    #[error("geometry id {0} is not attached to this scene")]
    NotAttached(u32),
    #[error("geometry {id} is not an instance")]
    NotAnInstance { id: u32 },
    #[error("transform is not finite")]
    NonFiniteTransform,
    /// An instance array's moving entries mix matrices and rigid poses.
    #[error("an instance array's poses must all be matrices or all be rigid")]
    MixedPoses,
    #[error("{what} has {count} elements, more than Embree's 32-bit indices allow")]
    TooLarge { what: &'static str, count: usize },
}

/// Embree's name for an error code.
pub(crate) fn code_name(code: sys::RTCError::Type) -> &'static str {
    use sys::RTCError::*;
    match code {
        RTC_ERROR_NONE => "RTC_ERROR_NONE",
        RTC_ERROR_UNKNOWN => "RTC_ERROR_UNKNOWN",
        RTC_ERROR_INVALID_ARGUMENT => "RTC_ERROR_INVALID_ARGUMENT",
        RTC_ERROR_INVALID_OPERATION => "RTC_ERROR_INVALID_OPERATION",
        RTC_ERROR_OUT_OF_MEMORY => "RTC_ERROR_OUT_OF_MEMORY",
        RTC_ERROR_UNSUPPORTED_CPU => "RTC_ERROR_UNSUPPORTED_CPU",
        RTC_ERROR_CANCELLED => "RTC_ERROR_CANCELLED",
        _ => "unrecognised Embree error code",
    }
}
