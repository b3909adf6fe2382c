//! Raw Embree 4 bindings, generated at build time by bindgen from the headers of the Embree
//! that is linked (see `build.rs`). No safe API here: dormant's safe wrapper lives in
//! `dormant::accel::embree`.
//!
//! Enums are modules of constants (`RTCError::RTC_ERROR_NONE`), so values coming back from
//! the library that the headers do not name cannot be undefined behaviour.
#![allow(non_upper_case_globals, non_camel_case_types, non_snake_case, dead_code)]
#![allow(clippy::all)]

include!(concat!(env!("OUT_DIR"), "/bindings.rs"));

/// Size of `RTCRayHit` as the linked library's headers declare it. The safe wrapper checks
/// this against a hit written by the library (tests/embree_ffi.rs).
pub const RAY_HIT_SIZE: usize = core::mem::size_of::<RTCRayHit>();

/// Include directory whose headers these bindings were generated from.
pub const HEADER_INCLUDE_DIR: &str = env!("EMBREE4_SYS_INCLUDE_DIR");

/// How the build found Embree: `EMBREE_DIR`, the project-local prefix, pkg-config or the
/// system paths.
pub const HEADER_ORIGIN: &str = env!("EMBREE4_SYS_ORIGIN");

/// `RTC_INVALID_GEOMETRY_ID` is `((unsigned int)-1)` in rtcore_common.h; bindgen does not
/// evaluate the cast.
pub const RTC_INVALID_GEOMETRY_ID: u32 = u32::MAX;
